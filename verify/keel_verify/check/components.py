"""``component-missing``: a task names a component the node binary it will run on lacks.

A node refuses at boot a mission with a task whose component its binary does not have
(``unknown component``), so a mission proved against one binary may still not fly on
another. Given the components a node binary has (``keel-node --list-components``, or the
binary itself), ``check`` and ``compile`` make that refusal a violation first: proved
means it runs."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from keel_verify.check.result import Violation
from keel_verify.mission import Mission

KIND = "component-missing"


class ComponentsError(Exception):
    """The component list cannot be read (an input error: exit 2)."""


def read_components(spec: str) -> frozenset[str]:
    """The component names of ``spec``: a node binary (an executable file, asked with
    ``--list-components``), ``@FILE`` (names separated by white space, as the binary
    prints them), or names separated by commas."""
    if spec.startswith("@"):
        try:
            names = Path(spec[1:]).read_text(encoding="utf-8").split()
        except (OSError, UnicodeDecodeError) as error:
            raise ComponentsError(f"cannot read the component list {spec[1:]}: {error}") \
                from None
    elif os.path.isfile(spec) and os.access(spec, os.X_OK):
        try:
            done = subprocess.run([spec, "--list-components"], capture_output=True,
                                  text=True, timeout=30, check=False)
        except (OSError, subprocess.TimeoutExpired) as error:
            raise ComponentsError(f"cannot run {spec} --list-components: {error}") from None
        if done.returncode != 0:
            raise ComponentsError(f"{spec} --list-components exited {done.returncode}: "
                                  f"{(done.stderr or done.stdout).strip()[:200]}")
        names = done.stdout.split()
    else:
        names = [name.strip() for name in spec.split(",")]
    names = [name for name in names if name]
    if not names:
        raise ComponentsError(f"no component names in {spec!r}")
    return frozenset(names)


def check_components(mission: Mission, components: frozenset[str] | None,
                     source: str = "the node binary") -> list[Violation]:
    """One violation per task whose component is not among ``components``."""
    if components is None:
        return []
    known = ", ".join(sorted(components))
    return [
        Violation(kind=KIND, phase="", config="", task=name, node=None,
                  message=f"task {name} needs component {task.component!r}, which "
                          f"{source} does not have (it has: {known})")
        for name, task in mission.tasks.items() if task.component not in components
    ]
