r"""Running TLC on a generated trace spec and reading how far it got.

A trace spec has the invariant ``TraceExplained == l <= Len(Log) \/ PrintT(MARKER)``:
TLC prints the marker exactly when some behaviour of the spec explains every line, so
*the marker is the verdict "accepted"* (the older ``TraceNotAccepted == l <= Len(Log)``,
violated there, is the same verdict, but TLC then prints the whole behaviour: on a long
trace that cost as much as checking it). When TLC finishes without the marker, no
behaviour gets past some line; the states TLC reached (``-dump``) say which line that
is: the largest ``l`` of any reachable state is the first line nothing explains.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from .. import resources
from ..specs.tlc import UNDECIDED, meaning

_VIOLATED = re.compile(r"^Error: Invariant (\w+) is violated")
_STATS = re.compile(r"^([\d,]+) states generated, ([\d,]+) distinct states found")
_SUCCESS = "Model checking completed. No error has been found."
MARKER = '"keel-trace: every line explained"'
_STATE_HEADER = re.compile(r"^State (\d+):")
_ASSIGNMENT = re.compile(r"^/\\ (\w+) = (.*)$")


@dataclass
class Run:
    """One TLC run on a trace spec."""

    outcome: str  # "accepted", "stuck", "undecided", "input-error"
    exit_code: int | None
    seconds: float
    distinct_states: int | None = None
    max_l: int | None = None  # the largest l reached (stuck runs)
    states_at_max: list[dict[str, str]] = field(default_factory=list)
    final_state: dict[str, str] = field(default_factory=dict)  # accepted runs: last state
    message: str = ""
    output: str = ""


def _read_states(text: str) -> list[dict[str, str]]:
    """States as TLC prints them (dump files and error traces): var -> value text."""
    states: list[dict[str, str]] = []
    current: dict[str, str] | None = None
    name: str | None = None
    for raw in text.splitlines():
        line = raw.rstrip()
        if _STATE_HEADER.match(line):
            current = {}
            states.append(current)
            name = None
            continue
        if current is None:
            continue
        if not line.strip():
            current, name = None, None
            continue
        if assignment := _ASSIGNMENT.match(line):
            name = assignment.group(1)
            current[name] = assignment.group(2)
        elif name is not None:
            current[name] += " " + line.strip()
    return states


def run(
    jar: Path,
    spec_dir: Path,
    module: str,
    module_text: str,
    cfg_text: str,
    timeout_s: float | None,
    dump: bool = True,
    extra_files: dict[str, str] | None = None,
) -> Run:
    """Model-check the trace spec ``module`` in a scratch directory under /tmp."""
    with tempfile.TemporaryDirectory(prefix="keel-trace-") as scratch_name:
        scratch = Path(scratch_name)
        for folder in (spec_dir, spec_dir / "trace"):
            for path in folder.glob("*.tla"):
                shutil.copyfile(path, scratch / path.name)
        for name, text in (extra_files or {}).items():
            (scratch / name).write_text(text)
        (scratch / f"{module}.tla").write_text(module_text)
        (scratch / f"{module}.cfg").write_text(cfg_text)
        # A trace spec has few states: one worker, a small heap and the quick JIT keep
        # the fixed cost (JVM start, parsing) low.
        # TLC unpacks its standard modules (TLC.tla, Sequences.tla) into java.io.tmpdir;
        # a private one keeps concurrent runs from reading each other's half-written files.
        java = os.environ.get("KEEL_JAVA", "java")
        command = [java, f"-Djava.io.tmpdir={scratch}",
                   "-XX:+UseSerialGC", "-Xmx1g", "-XX:TieredStopAtLevel=1",
                   *resources.class_archive_options(java, str(jar)),
                   "-cp", str(jar), "tlc2.TLC", "-workers", "1",
            "-config", f"{module}.cfg", "-metadir", str(scratch / "states"), "-cleanup",
            "-deadlock",
        ]
        if dump:
            command += ["-dump", str(scratch / "reached")]
        command.append(f"{module}.tla")
        started = time.monotonic()
        try:
            completed = subprocess.run(command, cwd=scratch, capture_output=True, text=True,
                                       timeout=timeout_s, check=False)
            output, exit_code = completed.stdout + completed.stderr, completed.returncode
        except subprocess.TimeoutExpired as expired:
            output = (expired.stdout or b"").decode(errors="replace") if isinstance(
                expired.stdout, bytes) else (expired.stdout or "")
            exit_code = None
        except FileNotFoundError as error:
            return Run("input-error", None, 0.0, message=f"cannot run java: {error}")
        seconds = time.monotonic() - started
        dumped = scratch / "reached.dump"
        dump_text = dumped.read_text() if dumped.is_file() else ""
    result = Run("undecided", exit_code, seconds, output=output)
    for line in output.splitlines():
        if stats := _STATS.match(line.strip()):
            result.distinct_states = int(stats.group(2).replace(",", ""))
    violated = next((m.group(1) for ln in output.splitlines()
                     if (m := _VIOLATED.match(ln.strip()))), None)
    if exit_code == 12 and violated in ("TraceNotAccepted", "NotPastRelax"):
        result.outcome = "accepted"
        if not dump:  # a diagnosis run: the state after the relaxed line is what counts
            trace = _read_states(output.split("constitutes a counter-example", 1)[-1])
            result.final_state = trace[-1] if trace else {}
        return result
    if exit_code == 0 and _SUCCESS in output and any(
            ln.strip() == MARKER for ln in output.splitlines()):
        result.outcome = "accepted"
        return result
    if exit_code == 0 and _SUCCESS in output and not dump:
        result.outcome = "stuck"  # the caller runs it again with -dump to find the line
        return result
    if exit_code == 0 and _SUCCESS in output:
        states = _read_states(dump_text)
        levels = [int(state["l"]) for state in states if state.get("l", "").isdigit()]
        if not levels:
            result.message = "TLC reached no state: the trace spec's initial state is empty"
            result.outcome = "stuck"
            result.max_l = 1
            return result
        result.outcome = "stuck"
        result.max_l = max(levels)
        result.states_at_max = [s for s in states if s.get("l") == str(result.max_l)]
        return result
    verdict, text = meaning(exit_code)
    if verdict == "input-error":
        result.outcome = "input-error"
    else:
        result.outcome = UNDECIDED
    errors = [ln.strip() for ln in output.splitlines() if ln.startswith("Error:")]
    result.message = errors[0] if errors else text
    if exit_code is None:
        result.message = f"TLC did not finish within {timeout_s:.0f} s"
    return result
