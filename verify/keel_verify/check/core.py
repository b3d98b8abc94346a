"""``check_file``/``check_mission``: load, prove, and attach file positions."""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from pathlib import Path

import yaml

from keel_verify.check.components import check_components
from keel_verify.check.model import KINDS, DecisionGraph
from keel_verify.check.online import answered_by_placer
from keel_verify.check.prover import Prover, Undecided
from keel_verify.check.recovery import check_recovery
from keel_verify.check.result import PROVED, UNDECIDED, VIOLATED, Advisory, CheckResult, Violation
from keel_verify.mission import LoadError, Mission, MissionError, load_mission

# Loading is reported on files larger than this: the loader takes seconds per megabyte.
LARGE_FILE_BYTES = 256_000


class InputError(Exception):
    """The file cannot be checked at all (kind ``schema``: exit 2)."""

    def __init__(self, errors: list[LoadError]):
        self.errors = errors
        super().__init__("\n".join(str(e) for e in errors))


def _position(mission: Mission, v: Violation) -> tuple[int, str]:
    """The line a violation points at (the edge, the on_phase entry, the node or the
    configuration) and the key written there."""
    if v.kind == "safe-mode-unhostable" and v.node in mission.nodes:
        return mission.nodes[v.node].line, v.node
    if v.kind == "component-missing" and v.task in mission.tasks:
        task = mission.tasks[v.task]
        return task.line, task.component
    phase = mission.phases.get(v.phase)
    if phase is None:
        return 0, ""
    if v.kind in ("master-mismatch", "safe-mode-within-tolerance"):
        line = phase.on_failure_lines.get((v.config, v.node or ""))
        if line:
            return line, v.node or ""
    if v.kind == "missing-transition":
        # The edge is missing: point where it is to be written, the configuration's
        # on_failure block, else the phase's on_failure key.
        line = phase.on_failure_block_lines.get(v.config) or phase.on_failure_block_lines.get("")
        if line:
            return line, v.config if v.config in phase.on_failure_block_lines else "on_failure"
    if v.kind == "recovery-unproven":
        line = phase.on_recovery_lines.get((v.config, v.node or ""))
        if line:
            return line, v.node or ""
    if v.kind == "phase-transition-invalid":
        line = phase.on_phase_lines.get((v.target, v.config))
        if line:
            return line, v.config
    config = phase.configurations.get(v.config)
    return (config.line, config.name) if config else (phase.line, phase.name)


def _column(lines: list[str], line: int, key: str) -> int:
    """The 1-based column of ``key`` (as a whole name) on a 1-based line; 0 if not found."""
    if not key or not 1 <= line <= len(lines):
        return 0
    found = re.search(rf"(?<![\w-]){re.escape(key)}(?![\w-])", lines[line - 1])
    return found.start() + 1 if found else 0


def column_of(path: str, line: int, key: str) -> int:
    """The 1-based column of ``key`` on a line of the file at ``path``; 0 if not found."""
    return _column(_source_lines(path), line, key)


def _source_lines(path: str) -> list[str]:
    try:
        return Path(path).read_text(encoding="utf-8-sig", errors="replace").splitlines()
    except OSError:
        return []  # an in-memory mission: lines without columns


def check_mission(
    mission: Mission,
    max_failures: int | None = None,
    timeout_s: float | None = None,
    progress: Callable[[str], None] | None = None,
    prune: bool = True,
    components: frozenset[str] | None = None,
) -> CheckResult:
    """``components``: the components the node binary has (``check_components``); None:
    not checked."""
    start = time.perf_counter()
    graph = DecisionGraph(mission, max_failures)
    prover = Prover(graph, timeout_s=timeout_s, progress=progress, prune=prune)
    status = PROVED
    reason = ""
    stats: dict[str, object] = {}
    try:
        stats = prover.run()
    except Undecided as undecided:
        status = UNDECIDED
        reason = str(undecided) or "unknown"
    violations = (list(prover.found.values()) + check_recovery(graph, progress)
                  + check_components(mission, components))
    # In a phase placed online the placer answers where the graph stops (check/online.py);
    # keel-verify check proves its answers with keel-place --prove.
    violations = answered_by_placer(mission, violations)
    lines = _source_lines(mission.path) if violations else []
    for v in violations:
        v.file = mission.path
        v.line, key = _position(mission, v)
        v.col = _column(lines, v.line, key)
    violations.sort(key=lambda v: (v.sort_key()[0], KINDS.index(v.kind), v.sort_key()[1:]))
    group_consequences(violations)
    if violations:
        status = VIOLATED
    stats.update(
        {
            "configurations": len(graph.configs),
            "phases": len(mission.phases),
            "tolerance_nodes": len(graph.tolerance_nodes),
            "node_failures": graph.tolerated,
            "depth": graph.depth,
            "queries": prover.queries,
            "seconds": round(time.perf_counter() - start, 3),
        }
    )
    return CheckResult(mission.name, mission.path, status, violations, stats, reason,
                       advise(mission))


INVALID_BECAUSE = ", which is invalid: "


def group_consequences(violations: list[Violation]) -> None:
    """One cause, one count: an on_phase move into a configuration that breaks a rule
    under the failures of the path (`phase-transition-invalid ... which is invalid: WHY`)
    follows from that configuration's own violation (the same rule, the same failures),
    when that is reported too. Sets `cause` on the consequence."""
    for v in violations:
        if v.kind != "phase-transition-invalid" or INVALID_BECAUSE not in v.message or not v.steps:
            continue
        why = v.message.split(INVALID_BECAUSE, 1)[1]
        target = v.steps[-1].to
        for index, root in enumerate(violations):
            if (root is not v and root.cause is None and root.config == target
                    and root.message == why and sorted(root.failures) == sorted(v.failures)):
                v.cause = index
                break


def advise(mission: Mission) -> list[Advisory]:
    """Advisories: a checkpointed task without max_state_bytes (unbounded-state)."""
    out = []
    for task in mission.tasks.values():
        if task.checkpoint and task.max_state_bytes is None:
            out.append(Advisory(
                "unbounded-state", task.name,
                f"task {task.name} is checkpointed and states no max_state_bytes: its "
                "checkpoints may be as large as the capacity allows (16 MiB), so the protocol's "
                "DDS domain admits messages that large, and a node holding valid credentials can "
                "make the Storage node take and write as many as it sends; state the largest "
                "checkpoint state its component writes",
                mission.path, task.line))
    return out


def load_errors_as_violations(path: str, errors: list[LoadError]) -> CheckResult:
    """``unknown-reference`` and ``port-conflict`` are violations (exit 1), not input errors."""
    violations = [
        Violation(kind=e.kind, phase="", config="", task=None, node=None, message=e.message,
                  file=e.file or path, line=e.line, col=e.col)
        for e in errors
    ]
    return CheckResult(_declared_name(path), path, VIOLATED, violations, {"loaded": False})


def _declared_name(path: str) -> str:
    """The `mission:` a file that parses but does not load declares (its names or ports
    are wrong), else the file's stem."""
    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8-sig"))
    except (OSError, yaml.YAMLError):
        return Path(path).stem
    name = data.get("mission") if isinstance(data, dict) else None
    return name if isinstance(name, str) and name else Path(path).stem


def check_file(
    path: str,
    max_failures: int | None = None,
    timeout_s: float | None = None,
    progress: Callable[[str], None] | None = None,
    admit: Callable[[Mission], None] | None = None,
    components: frozenset[str] | None = None,
) -> tuple[CheckResult, Mission | None]:
    """Raises :class:`InputError` for schema errors; returns the result and the mission.

    ``admit``, when given, sees the loaded mission before it is proved and may refuse it
    by raising :class:`InputError` (``compile`` refuses what an image cannot hold)."""
    start = time.perf_counter()
    try:
        size = Path(path).stat().st_size
    except OSError:
        size = 0
    if progress is not None and size > LARGE_FILE_BYTES:
        progress(f"loading {path} ({size / 1e6:.1f} MB) ...")
    try:
        mission = load_mission(path)
    except MissionError as error:
        if error.is_input_error:
            raise InputError(error.errors) from None
        return load_errors_as_violations(path, error.errors), None
    if admit is not None:
        admit(mission)
    if progress is not None and size > LARGE_FILE_BYTES:
        progress(f"loaded in {time.perf_counter() - start:.1f} s; proving ...")
    return check_mission(mission, max_failures, timeout_s, progress,
                         components=components), mission


__all__ = ["InputError", "check_file", "check_mission", "UNDECIDED"]
