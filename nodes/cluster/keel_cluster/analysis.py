"""Reads a run directory's traces and the launcher's event log, and derives the timeline
and the metrics: per fault, detection / decision / switch / task-restore latencies, per
phase command the switch time, and the reliability counters (lost tasks, double
activations, split masters, lost checkpoints).

Trace lines follow spec/NAMES.md: `{"t_ns", "node", "fsm", "action", "args", "vars"}`,
with `t_ns` wall-clock nanoseconds, so lines from all nodes merge into one timeline.
"""

from __future__ import annotations

import json
import statistics
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


@dataclass
class TraceLine:
    t_ns: int
    node: str
    fsm: str
    action: str
    args: dict[str, Any]
    vars: dict[str, Any]


@dataclass
class Malformed:
    file: str
    line: int
    reason: str


# Trace action names before one name per meaning (spec/NAMES.md): the election's
# suspicion and the Master's exclusion were both logged as DeclareFailed. A copy of
# keel_verify.trace.load.LEGACY_ACTIONS (keel-cluster does not depend on keel-verify);
# tests/cluster/test_analysis.py holds the two equal.
LEGACY_ACTIONS = {("election", "DeclareFailed"): "Suspect", ("switch", "DeclareFailed"): "Exclude"}


def legacy_action(fsm: str, action: str) -> str:
    """The action a line of an older trace stands for under today's names."""
    return LEGACY_ACTIONS.get((fsm, action), action)


def read_traces(run_dir: Path) -> tuple[list[TraceLine], list[Malformed]]:
    lines: list[TraceLine] = []
    bad: list[Malformed] = []
    for path in sorted(run_dir.glob("*.trace.ndjson")):
        with open(path, encoding="utf-8", errors="replace") as handle:
            for number, text in enumerate(handle, 1):
                text = text.strip()
                if not text:
                    continue
                try:
                    raw = json.loads(text)
                    lines.append(
                        TraceLine(
                            int(raw["t_ns"]),
                            str(raw["node"]),
                            str(raw["fsm"]),
                            legacy_action(str(raw["fsm"]), str(raw["action"])),
                            dict(raw.get("args") or {}),
                            dict(raw.get("vars") or {}),
                        )
                    )
                except (ValueError, KeyError, TypeError) as error:
                    # A node killed mid-write leaves a truncated last line: report, go on.
                    bad.append(Malformed(str(path), number, str(error)))
    lines.sort(key=lambda x: x.t_ns)
    return lines, bad


def _arg(line: TraceLine, *names: str) -> str | None:
    for name in names:
        if name in line.args:
            return str(line.args[name])
    return None


@dataclass
class FaultMetrics:
    kind: str  # "kill" | "phase" | "partition"
    target: str
    t_ns: int
    detection_ms: float | None = None
    # The node that decided (the Master, or the Observer that took over) may have detected
    # later than the first monitor: its own DeclareFailed of the victim.
    decider_detection_ms: float | None = None
    decision_ms: float | None = None
    switch_ms: float | None = None
    restore_ms: float | None = None
    total_ms: float | None = None
    new_master: str | None = None
    config: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def _ms(later: int | None, earlier: int | None) -> float | None:
    if later is None or earlier is None:
        return None
    return (later - earlier) / 1e6


def fault_metrics(lines: list[TraceLine], events: list[dict[str, Any]]) -> list[FaultMetrics]:
    """One entry per kill, partition, phase and exclude command of the run."""
    out: list[FaultMetrics] = []
    timed = [e for e in events if e["action"] in ("kill", "partition", "phase", "exclude")]
    for index, event in enumerate(timed):
        t0 = int(event["t_ns"])
        horizon = int(timed[index + 1]["t_ns"]) if index + 1 < len(timed) else None
        window = [x for x in lines if x.t_ns >= t0 and (horizon is None or x.t_ns < horizon)]
        m = FaultMetrics(event["action"], event["argument"], t0)
        if event["action"] in ("kill", "partition", "exclude"):
            target = event["argument"]
            # The ground's exclude is detected when the Master takes it: its Exclude with
            # the ground's hold, or, for the Master itself, its resignation.
            detected = next(
                (x for x in window if (x.fsm == "heartbeat" and x.action == "DeclareFailed"
                                       and _arg(x, "n", "f") == target)
                 or (event["action"] == "exclude" and x.fsm == "switch"
                     and ((x.node == target and x.action in ("AskExclusion", "Resign"))
                          or (x.action == "Exclude" and _arg(x, "f", "n") == target
                              and x.args.get("ground") is True)))),
                None,
            )
            decided = next(
                (x for x in window if x.fsm == "switch" and x.action in ("Exclude", "BecomeMaster")
                 and (x.action == "BecomeMaster" or _arg(x, "f", "n") == target)),
                None,
            )
            start = decided
        else:
            detected = None
            start = decided = next(
                (x for x in window if x.fsm == "switch" and x.action == "RequestPhase"), None
            )
        completed = None
        if start is not None:
            completed = next(
                (x for x in window if x.fsm == "switch" and x.action == "CompleteSwitch"
                 and x.t_ns >= start.t_ns),
                None,
            )
        activations = [
            x for x in window
            if x.fsm == "switch" and x.action == "Activate" and start is not None
            and x.t_ns >= start.t_ns and (completed is None or x.t_ns <= completed.t_ns)
        ]
        m.detection_ms = _ms(detected.t_ns if detected else None, t0)
        if event["action"] in ("kill", "partition", "exclude") and decided is not None:
            own = next(
                (x for x in window if x.fsm == "heartbeat" and x.action == "DeclareFailed"
                 and x.node == decided.node and _arg(x, "n", "f") == event["argument"]
                 and x.t_ns <= decided.t_ns),
                None,
            )
            m.decider_detection_ms = _ms(own.t_ns if own else None, t0)
        m.decision_ms = _ms(
            decided.t_ns if decided else None, detected.t_ns if detected else (t0 if event["action"] == "phase" else None)
        )
        m.switch_ms = _ms(completed.t_ns if completed else None, start.t_ns if start else None)
        m.restore_ms = _ms(max((x.t_ns for x in activations), default=None), start.t_ns if start else None)
        m.total_ms = _ms(completed.t_ns if completed else None, t0)
        if completed is not None:
            m.new_master = completed.node
            m.config = _arg(completed, "c") or str(completed.vars.get("masterConfig", "")) or None
        out.append(m)
    return out


@dataclass
class Reliability:
    double_activations: list[str] = field(default_factory=list)
    split_masters: list[str] = field(default_factory=list)
    lost_checkpoints: list[str] = field(default_factory=list)
    lost_tasks: list[str] = field(default_factory=list)
    # Fault model 2, without the specs' exemptions: what an operator would call a failure.
    two_masters_ms: float = 0.0  # two nodes running as Master at once, across epochs
    double_run_ms: float = 0.0  # one task running on two live nodes at once, whatever their views
    activations_below_known: list[str] = field(default_factory=list)
    # A checkpointed task started without its newest state: the Storage node and its last
    # host were both out of reach (the node says so: StateOutOfReach). Unavoidable within
    # the protocol, reported apart from activations_below_known, which are avoidable.
    unrecoverable_starts: list[str] = field(default_factory=list)
    starting_afresh: set[tuple[str, str]] = field(default_factory=set)  # (node, task)
    false_exclusions: list[str] = field(default_factory=list)
    overlaps: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return {
            "double_activations": len(self.double_activations),
            "split_masters": len(self.split_masters),
            "lost_checkpoints": len(self.lost_checkpoints),
            "lost_tasks": len(self.lost_tasks),
            "two_masters_ms": round(self.two_masters_ms, 1),
            "double_run_ms": round(self.double_run_ms, 1),
            "activations_below_known": len(self.activations_below_known),
            "unrecoverable_starts": len(self.unrecoverable_starts),
            "false_exclusions": len(self.false_exclusions),
            "details": self.double_activations + self.split_masters + self.lost_checkpoints
            + self.lost_tasks + self.activations_below_known + self.unrecoverable_starts
            + self.false_exclusions + self.overlaps,
        }


# Scenario actions whose argument is the faulty node (a partition isolates its argument).
FAULT_ACTIONS = ("kill", "restart", "partition", "pause", "resume")


class _Overlaps:
    """Time during which two nodes run as Master, and a task runs on two live nodes."""

    def __init__(self, active: dict[str, set[str]], down: set[str]) -> None:
        self.active = active  # task -> nodes running it (shared with reliability())
        self.down = down  # killed nodes (shared)
        self.masters: set[str] = set()
        self.since: int | None = None
        self.two_masters_ns = 0
        self.double_since: int | None = None
        self.double_run_ns = 0
        self.notes: list[str] = []

    def update(self, t_ns: int) -> None:
        down = self.down
        many = len(self.masters - down) > 1
        if many and self.since is None:
            self.since = t_ns
            self.notes.append(f"t={t_ns}: {sorted(self.masters - down)} run as Master at once")
        elif not many and self.since is not None:
            self.two_masters_ns += t_ns - self.since
            self.since = None
        double = any(len(nodes - down) > 1 for nodes in self.active.values())
        if double and self.double_since is None:
            self.double_since = t_ns
        elif not double and self.double_since is not None:
            self.double_run_ns += t_ns - self.double_since
            self.double_since = None

    def close(self, t_ns: int) -> None:
        if self.since is not None:
            self.two_masters_ns += t_ns - self.since
        if self.double_since is not None:
            self.double_run_ns += t_ns - self.double_since


def reliability(
    lines: list[TraceLine],
    events: list[dict[str, Any]],
    final_status: dict[str, dict[str, Any]],
    storage_nodes: set[str] | None = None,
) -> Reliability:
    """Checks the run against the properties the specs prove, from the outside.

    As in spec/ConfigSwitch.tla (and keel-sim's checkers): a task may run on two nodes
    when one of them is excluded by the other's view — a partitioned node runs what it ran
    until it hears it was declared failed (NoDoubleActivationInv); and a checkpointed task
    must resume from the latest stored version only while the storage node is alive and
    not excluded by the activating node's view (ResumeLatestCheckpointInv). A node's view
    of the failed nodes is the `failed` variable of its latest trace line that has one.
    The latest stored version is what the storage node traced as stored (StoreCheckpoint):
    a flush sent into a partition never arrives. Only where the storage node traced
    nothing, the owners' FlushCheckpoint lines stand in for it.

    `storage_nodes`: the mission's storage nodes; by default the nodes whose final status
    says Storage, or that traced a StoreCheckpoint.
    """
    result = Reliability()
    store_lines = [x for x in lines if x.fsm == "switch" and x.action == "StoreCheckpoint"]
    storage = set(storage_nodes) if storage_nodes is not None else (
        {x.node for x in store_lines} | {n for n, s in final_status.items() if s.get("role") == "Storage"}
    )
    stored_action = "StoreCheckpoint" if store_lines else "FlushCheckpoint"
    process_events = sorted(
        (int(e["t_ns"]), e["action"], e["argument"]) for e in events
        if e["action"] in ("kill", "restart", "pause", "resume")
    )
    merged: list[tuple[int, str, Any]] = [(x.t_ns, "trace", x) for x in lines]
    merged += [(t, action, node) for t, action, node in process_events]
    merged.sort(key=lambda item: item[0])
    active: dict[str, set[str]] = {}  # task -> nodes running it
    # node -> tasks it holds for want of a lease (spec/Lease.tla): stopped, still placed
    # (its Hold line stops them; Activate lines meanwhile start nothing; Release restarts)
    held: dict[str, set[str]] = {}
    masters: dict[int, set[str]] = {}  # epoch -> nodes that became master in it
    stored: dict[str, Version] = {}  # task -> latest flushed checkpoint version
    failed_view: dict[str, set[str]] = {}  # node -> nodes its latest view holds failed
    down: set[str] = set()  # killed and not restarted, or stopped
    waking: set[str] = set()  # resumed, and nothing traced since
    known: dict[str, Version] = {}  # task -> highest version stored, flushed or activated
    # (node, task) -> version of a final flush its node has not yet seen acknowledged
    unacknowledged: dict[tuple[str, str], Version] = {}
    faulty = {str(e["argument"]) for e in events if e["action"] in FAULT_ACTIONS}
    ground_holds: dict[str, set[str]] = {}  # node -> the nodes it holds out (its Ground* lines)
    overlaps = _Overlaps(active, down)
    for t_ns, kind, item in merged:
        if kind == "kill":
            down.add(item)
            waking.discard(item)
            failed_view.pop(item, None)
            held.pop(item, None)
            overlaps.masters.discard(item)
            for nodes in active.values():
                nodes.discard(item)
            overlaps.update(t_ns)
            continue
        if kind == "restart":
            down.discard(item)
            continue
        if kind == "pause":
            down.add(item)  # a stopped process runs nothing
            overlaps.update(t_ns)
            continue
        if kind == "resume":
            # Still nothing until its loop has acted (its first trace line): its pool
            # starts no execution past the lease it held before the stop (Executor::
            # set_run_until), and anyone else could only have taken its tasks or its
            # mastership after that lease. A stop shorter than the lease loses nothing.
            waking.add(item)
            continue
        x: TraceLine = item
        if x.node in waking and _acts(x):
            waking.discard(x.node)
            down.discard(x.node)
            overlaps.update(t_ns)
        _follow_fault_model_2(x, t_ns, result, known, faulty, overlaps, stored_action,
                              unacknowledged, ground_holds)
        if isinstance(x.vars.get("failed"), list):
            failed_view[x.node] = {str(n) for n in x.vars["failed"]}
        task = _arg(x, "t")
        if x.fsm == "switch" and x.action == "Hold":
            mine = {t for t, nodes in active.items() if x.node in nodes}
            held[x.node] = held.get(x.node, set()) | mine
            for t in mine:
                active[t].discard(x.node)
            overlaps.update(t_ns)
            continue
        if x.fsm == "switch" and x.action == "Release":
            for t in held.pop(x.node, set()):
                active.setdefault(t, set()).add(x.node)
            overlaps.update(t_ns)
            continue
        if x.fsm == "switch" and x.action == "Activate" and task and x.node in held:
            held[x.node].add(task)  # placed here, started only on Release
            continue
        if x.fsm == "switch" and x.action == "Activate" and task:
            holders = active.setdefault(task, set())
            mine = failed_view.get(x.node, set())
            others = {o for o in holders - {x.node}
                      if o not in mine and x.node not in failed_view.get(o, set())}
            if others:
                result.double_activations.append(
                    f"t={t_ns}: {task} activated on {x.node} while active on {sorted(others)}"
                )
            holders.add(x.node)
            overlaps.update(t_ns)
            version = _version(x)
            # Without a storage node in the traces there is nothing to exempt.
            storage_usable = not (storage & down) and not (storage & mine)
            if storage_usable and version is not None and version < stored.get(task, ZERO):
                result.lost_checkpoints.append(
                    f"t={t_ns}: {task} resumed on {x.node} from version {_show(version)}, "
                    f"latest stored {_show(stored[task])}"
                )
        elif x.fsm == "switch" and x.action == "Deactivate" and task:
            active.setdefault(task, set()).discard(x.node)
            held.get(x.node, set()).discard(task)
            overlaps.update(t_ns)
        elif x.fsm == "switch" and x.action == stored_action and task:
            version = _version(x)
            if version is not None:
                stored[task] = max(stored.get(task, ZERO), version)
        elif x.fsm == "election" and x.action == "BecomeMaster":
            epoch = x.args.get("e", x.vars.get("epoch"))
            if isinstance(epoch, int):
                claimed = masters.setdefault(epoch, set())
                claimed.add(x.node)
                if len(claimed) > 1:
                    result.split_masters.append(f"epoch {epoch}: masters {sorted(claimed)}")
    overlaps.close(merged[-1][0] if merged else 0)
    result.two_masters_ms = overlaps.two_masters_ns / 1e6
    result.double_run_ms = overlaps.double_run_ns / 1e6
    result.overlaps = overlaps.notes
    alive = {n: s for n, s in final_status.items() if s}
    expected: set[str] = set()
    for status in alive.values():
        expected |= set(status.get("expected_tasks", []))
    running: dict[str, list[str]] = {}
    for node, status in alive.items():
        for task in status.get("tasks", []):
            running.setdefault(task, []).append(node)
    for task in sorted(expected):
        holders = running.get(task, [])
        if len(holders) != 1:
            result.lost_tasks.append(f"at the end, {task} runs on {holders or 'no node'}")
    return result


# A resumed node's lines that stop what it ran, or only watch: they do not show it running.
_STOPPING = ("Hold", "Deactivate", "Resign", "Resigned", "LeaseLapsed")


def _acts(x: TraceLine) -> bool:
    """Whether a line shows its node running (tasks or mastership) rather than stopping."""
    if x.fsm in ("heartbeat", "health"):
        return False
    if x.fsm == "switch" and x.action in _STOPPING:
        return False
    return not (x.fsm == "election" and x.action == "ReceiveCommand" and x.args.get("stepDown") is True)


# A task state's version: (epoch, seq) of the lineage, then the count (core/fsm/types.hpp,
# Version): compared as tuples, lineage first. A line without "lineage" is in the initial
# lineage.
Version = tuple[int, int, int]
ZERO: Version = (0, 0, 0)


@dataclass
class TaskMove:
    """A task that started on another node than the one that ran it before: where from,
    where to, and the state it started from."""

    t_ns: int
    task: str
    source: str
    target: str
    version: int
    lineage: tuple[int, int]
    restored: bool

    def as_dict(self) -> dict[str, Any]:
        return {"t_ns": self.t_ns, "task": self.task, "from": self.source, "to": self.target,
                "version": self.version, "lineage": list(self.lineage), "restored": self.restored}

    def describe(self) -> str:
        if not self.restored:
            state = "from its initial state (no checkpoint)"
        else:
            state = f"from checkpoint version {_show((*self.lineage, self.version))}"
        return f"{self.task} {self.source} -> {self.target} {state}"


def task_moves(lines: list[TraceLine]) -> list[TaskMove]:
    """Every task that a node activated after another node had run it (its switch
    Activate lines, in time order): the migrations a reconfiguration made."""
    host: dict[str, str] = {}
    moves = []
    # A node that holds its tasks (the lease's Hold) starts what it activates meanwhile only
    # at its Release; one excluded before then never does (as `reliability` counts them).
    holding: set[str] = set()
    held: dict[str, list[TraceLine]] = {}

    def start(x: TraceLine, t_ns: int) -> None:
        task, node = _arg(x, "t"), _arg(x, "n") or x.node
        if task is None:
            return
        before = host.get(task)
        host[task] = node
        if before is not None and before != node:
            count = x.args.get("version")
            moves.append(TaskMove(t_ns, task, before, node, count if isinstance(count, int) else 0,
                                  _lineage(x.args.get("lineage")), bool(x.args.get("restored"))))

    for x in sorted(lines, key=lambda x: x.t_ns):
        node = _arg(x, "n") or x.node
        if x.fsm == "env" and x.action in ("Crash", "Restart"):
            holding.discard(node)
            held.pop(node, None)  # a new process: what the old one held never ran
            continue
        if x.fsm != "switch":
            continue
        if x.action == "Hold":
            holding.add(node)
        elif x.action == "Release":
            holding.discard(node)
            for activated in held.pop(node, []):
                start(activated, x.t_ns)
        elif x.action == "ReceiveCommand" and node in _list(x.args.get("out")):
            holding.discard(node)
            held.pop(node, None)  # excluded or gone before its Release: it never ran them
        elif x.action == "Activate":
            if node in holding:
                held.setdefault(node, []).append(x)
            else:
                start(x, x.t_ns)
    return moves


def _list(value: object) -> list[str]:
    return [str(v) for v in value] if isinstance(value, list) else []


def _lineage(value: object) -> tuple[int, int]:
    if isinstance(value, list) and len(value) == 2 and all(isinstance(v, int) for v in value):
        return (value[0], value[1])
    return (0, 0)


def _version(x: TraceLine, lineage_key: str = "lineage") -> Version | None:
    """The version a line logs (its args' version and lineage), None without one."""
    count = x.args.get("version")
    if not isinstance(count, int):
        return None
    return (*_lineage(x.args.get(lineage_key)), count)


def _show(version: Version) -> str:
    epoch, seq, count = version
    return str(count) if (epoch, seq) == (0, 0) else f"{count} (lineage {epoch}.{seq})"


def _follow_fault_model_2(x: TraceLine, t_ns: int, result: Reliability,
                          known: dict[str, Version], faulty: set[str], overlaps: _Overlaps,
                          stored_action: str = "StoreCheckpoint",
                          unacknowledged: dict[tuple[str, str], Version] | None = None,
                          ground_holds: dict[str, set[str]] | None = None) -> None:
    """The counters the specs' exemptions do not excuse: who runs as Master (from its
    first command or take-over to its step-down, resignation or kill), activations below a
    version the cluster already had, and exclusions of nodes no fault touched."""
    task = _arg(x, "t")
    if x.fsm == "election" and x.action == "BecomeMaster" or (
            x.fsm == "switch" and x.action == "BroadcastCommand" and _arg(x, "m") == x.node):
        if x.node not in overlaps.masters:
            overlaps.masters.add(x.node)
            overlaps.update(t_ns)
    elif (x.fsm == "election" and x.action == "ReceiveCommand" and x.args.get("stepDown") is True) or (
            x.fsm == "switch" and x.action in ("Resign", "Resigned")):
        overlaps.masters.discard(x.node)
        overlaps.update(t_ns)
    elif x.fsm == "switch" and x.action == "StateOutOfReach" and task:
        result.starting_afresh.add((x.node, task))  # the Activate that follows starts afresh
    elif x.fsm == "switch" and x.action == "Activate" and task:
        # The state the task starts from (version, lineage), and the one it runs at: a
        # start without the Storage node opens a lineage ("opened"), same count.
        version = _version(x)
        if version is not None:
            running = (*_lineage(x.args["opened"]), version[2]) if "opened" in x.args \
                else version
            if (x.node, task) in result.starting_afresh:
                result.starting_afresh.discard((x.node, task))
                result.unrecoverable_starts.append(
                    f"t={t_ns}: {task} started on {x.node} at version {_show(version)} without "
                    f"its newest state (the Storage node and its last host out of reach; "
                    f"highest version traced {_show(known.get(task, ZERO))})")
                known[task] = running  # a new lineage
            elif version < known.get(task, ZERO):
                result.activations_below_known.append(
                    f"t={t_ns}: {task} activated on {x.node} at version {_show(version)}, "
                    f"below version {_show(known[task])} the cluster had")
            known[task] = max(known.get(task, ZERO), running)
    elif x.fsm == "switch" and x.action in ("StoreCheckpoint", "FlushCheckpoint") and task:
        # What the cluster had: what the Storage node stored, or a final flush once its
        # host acks Prepared (it waits for the flush's acknowledgement, or keeps the state
        # as a hand-off). A write sent into a partition never arrived: the steps it carried
        # were only its cut-off host's, as a final flush its host gave up on (it resigned
        # unflushed). Where the Storage node traced nothing, every flush stands in for it.
        version = _version(x)
        if version is None:
            return
        if x.action == "StoreCheckpoint" or stored_action == "FlushCheckpoint":
            known[task] = max(known.get(task, ZERO), version)
        elif x.args.get("final") is True:
            if unacknowledged is None:
                known[task] = max(known.get(task, ZERO), version)
            else:
                unacknowledged[(x.node, task)] = version
    elif x.fsm == "switch" and x.action == "Ack" and x.args.get("kind") == "Prepared":
        for (node, flushed), version in list((unacknowledged or {}).items()):
            if node == x.node:
                known[flushed] = max(known.get(flushed, ZERO), version)
                del unacknowledged[(node, flushed)]
    elif x.fsm == "switch" and x.action in ("AskExclusion", "Resign", "Resigned"):
        faulty.add(x.node)  # its own word: a task kept failing there, or it stepped down
        if x.action == "Resigned" and unacknowledged:
            for key in [k for k in unacknowledged if k[0] == x.node]:
                del unacknowledged[key]  # flushed: stored (traced); not: never arrived
    elif x.fsm == "switch" and x.action in ("GroundExclude", "GroundReadmit"):
        # The ground's hold, as the node took it: a Master's exclusion on it (its Exclude
        # says `ground`) is the ground's, not a false one (docs/operations.md, `exclude`).
        held = _arg(x, "f")
        if held:
            holds = ground_holds.setdefault(x.node, set()) if ground_holds is not None else set()
            (holds.add if x.action == "GroundExclude" else holds.discard)(held)
    elif x.fsm == "switch" and x.action == "Exclude":
        excluded = _arg(x, "f")
        on_ground = (x.args.get("ground") is True and ground_holds is not None
                     and excluded in ground_holds.get(x.node, set()))
        if excluded and excluded not in faulty and not on_ground:
            result.false_exclusions.append(
                f"t={t_ns}: {x.node} excluded {excluded}, which no fault touched")


# Fig. 9's milestones, in the order a switch passes them (switch_stages).
SWITCH_MILESTONES = (
    ("command", "the Master's BroadcastCommand line"),
    ("first_receive", "the first member's ReceiveCommand"),
    ("last_receive", "the last member's ReceiveCommand"),
    ("last_prepared", "the last member's Ack (Prepared)"),
    ("activate", "the Master's BroadcastActivate (every Prepared in)"),
    ("last_receive_activate", "the last member's ReceiveActivate"),
    ("last_task_started", "the last Activate of a task"),
    ("complete", "the Master's CompleteSwitch (every Activated in)"),
)


def switch_stages(lines: list[TraceLine]) -> dict[str, dict[str, float | int | None]]:
    """Where a planned switch's time goes (Fig. 9): for each of the Master's RequestPhase
    lines, the time from it to each milestone of SWITCH_MILESTONES (the first line after it,
    up to the Master's CompleteSwitch; a member is any node but the Master), then their
    distributions in ms. A trace line is written before the messages of its step leave
    (keel-node saves its durable state, then sends), so a hop's time includes the sender's
    save and the receiver's wake-up."""
    ordered = sorted(lines, key=lambda x: x.t_ns)
    samples: dict[str, list[float]] = {name: [] for name, _ in SWITCH_MILESTONES}
    for index, start in enumerate(ordered):
        if start.fsm != "switch" or start.action != "RequestPhase":
            continue
        master, t0 = start.node, start.t_ns
        found: dict[str, int] = {}
        for x in ordered[index + 1:]:
            if x.fsm != "switch":
                continue
            member = x.node != master
            if x.action == "RequestPhase" and not member:
                break
            if x.action == "BroadcastCommand" and not member:
                found.setdefault("command", x.t_ns)
            elif x.action == "ReceiveCommand" and member:
                found.setdefault("first_receive", x.t_ns)
                found["last_receive"] = x.t_ns
            elif x.action == "Ack" and member and x.args.get("kind", "Prepared") == "Prepared":
                found["last_prepared"] = x.t_ns
            elif x.action == "BroadcastActivate" and not member:
                found.setdefault("activate", x.t_ns)
            elif x.action == "ReceiveActivate" and member:
                found["last_receive_activate"] = x.t_ns
            elif x.action == "Activate":
                found["last_task_started"] = x.t_ns
            elif x.action == "CompleteSwitch" and not member:
                found["complete"] = x.t_ns
                break
        if "complete" not in found:
            continue
        for name, _ in SWITCH_MILESTONES:
            if name in found:
                samples[name].append((found[name] - t0) / 1e6)
    return {name: distribution(values) for name, values in samples.items()}


def switch_hops(lines: list[TraceLine]) -> dict[str, dict[str, float | int | None]]:
    """Fig. 9's hops, each a distribution in ms over the messages of the planned switches
    (a Master's RequestPhase to its CompleteSwitch), from the trace lines of the nodes at
    each end (one clock on loopback):
    - command: the Master's BroadcastCommand line to a member's ReceiveCommand line: the
      Master's durable save of its new view, then the message (and the receiver's wake-up);
    - activate: the Master's BroadcastActivate line to a member's ReceiveActivate line: a
      message and a wake-up with no save before it, the hop's floor in the same run;
    - flush: a member's first final FlushCheckpoint line of the switch to its Ack Prepared
      line: the final checkpoint to the Storage node and its acknowledgement back (a member
      acks Prepared only once the Storage node acknowledged its final checkpoint, which it
      does once the checkpoint is on its disk, or at once for a version it holds already)."""
    ordered = sorted(lines, key=lambda x: x.t_ns)
    samples: dict[str, list[float]] = {"command": [], "activate": [], "flush": []}
    commanded: dict[tuple[Any, Any], int] = {}  # (epoch, seq) -> the Master's BroadcastCommand
    activated: dict[str, int] = {}  # master -> its last BroadcastActivate
    flushed: dict[str, int] = {}  # member -> its first final FlushCheckpoint of the switch
    seen_command: set[tuple[str, Any, Any]] = set()
    planned: set[str] = set()  # Masters between a RequestPhase line and its CompleteSwitch
    for x in ordered:
        if x.fsm != "switch":
            continue
        if x.action == "RequestPhase":
            planned.add(x.node)
        elif x.action == "CompleteSwitch":
            planned.discard(x.node)
        elif x.action == "BroadcastCommand" and x.node in planned:
            commanded.setdefault((x.args.get("epoch"), x.args.get("seq")), x.t_ns)
        elif x.action == "ReceiveCommand" and x.args.get("from") not in (None, x.node):
            key = (x.args.get("epoch"), x.args.get("seq"))
            if key in commanded and (x.node, *key) not in seen_command:
                seen_command.add((x.node, *key))
                samples["command"].append((x.t_ns - commanded[key]) / 1e6)
        elif x.action == "BroadcastActivate" and x.node in planned:
            activated[x.node] = x.t_ns
        elif x.action == "ReceiveActivate":
            sent = [t for master, t in activated.items() if master != x.node]
            if sent:
                samples["activate"].append((x.t_ns - max(sent)) / 1e6)
        if x.action == "CompleteSwitch":
            activated.pop(x.node, None)
        elif x.action == "FlushCheckpoint" and x.args.get("final") and planned:
            flushed.setdefault(x.node, x.t_ns)
        elif x.action == "Ack" and x.args.get("kind") == "Prepared" and x.node in flushed:
            samples["flush"].append((x.t_ns - flushed.pop(x.node)) / 1e6)
    return {name: distribution(values) for name, values in samples.items()}


def distribution(values: list[float]) -> dict[str, float | int | None]:
    values = sorted(v for v in values if v is not None)
    if not values:
        return {"n": 0, "mean": None, "p50": None, "p99": None, "min": None, "max": None}

    def pct(p: float) -> float:
        k = min(len(values) - 1, max(0, round(p / 100.0 * (len(values) - 1))))
        return values[k]

    return {
        "n": len(values),
        "mean": statistics.fmean(values),
        "p50": pct(50),
        "p99": pct(99),
        "min": values[0],
        "max": values[-1],
    }
