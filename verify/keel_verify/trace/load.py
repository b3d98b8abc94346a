"""Reading NDJSON traces: one JSON object per line, merged across files by ``t_ns``."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

FSMS = ("heartbeat", "election", "switch", "env", "health")
# Lines of these fsms annotate a trace (keel-node's task health events) but belong to no
# spec: they are read, checked for shape, and left out of every protocol's validation.
ANNOTATIONS = ("health",)
REQUIRED = ("t_ns", "node", "fsm", "action", "vars")
# Trace action names before one name per meaning (spec/NAMES.md, "Renamed actions"): a
# node's suspicion (election) and the Master's exclusion (switch) were both logged as
# DeclareFailed, as a monitor's declaration (heartbeat) still is. A line of an older trace
# is read under today's name, so traces recorded before the rename still validate.
LEGACY_ACTIONS = {("election", "DeclareFailed"): "Suspect", ("switch", "DeclareFailed"): "Exclude"}

# The parameter that names the node that acts, per action (spec/NAMES.md: `m` a monitor or
# the Master, `n` any node): a line is that node's, so the two must agree. A line whose
# args name another node as the one acting contradicts itself (a checker that read the
# node from one and the state from the other would validate a step nobody took).
ACTOR = {
    **{("heartbeat", a): "m" for a in ("Tick", "ReceiveHeartbeat", "DeclareFailed", "Readmit",
                                         "Rejoin", "Withdraw")},
    ("heartbeat", "SendHeartbeat"): "n",
    **{("election", a): "n" for a in ("Suspect", "BecomeMaster", "ReceiveCommand", "OpenEpoch",
                                        "WarmBoot")},
    **{("switch", a): "m" for a in ("BootSwitch", "Exclude", "RequestPhase", "GroundRecovery",
                                      "Readmit", "HandOver", "BroadcastCommand",
                                      "BroadcastActivate", "CompleteSwitch",
                                      "RefuseGroundCommand")},
    **{("switch", a): "n" for a in ("BecomeMaster", "ReceiveCommand", "Deactivate",
                                      "FlushCheckpoint", "Ack", "ReceiveActivate", "Activate",
                                      "AskHolders", "StateOutOfReach", "Hold", "Release",
                                      "LeaseLapsed", "Resign", "Resigned", "AskExclusion",
                                      "Backed", "Refused", "Recovered", "Restored", "HeardPrepared", "GroundPause",
                                      "GroundResume")},
}


class TraceInputError(Exception):
    """A trace that cannot be read (exit 2); the message starts with file:line."""


@dataclass
class Line:
    """One trace line and where it came from."""

    file: str
    number: int
    t_ns: int
    node: str | None
    fsm: str
    action: str
    args: dict[str, object] = field(default_factory=dict)
    vars: dict[str, object] = field(default_factory=dict)

    @property
    def where(self) -> str:
        return f"{self.file}:{self.number}"

    def as_json(self) -> dict[str, object]:
        return {"file": self.file, "line": self.number, "t_ns": self.t_ns, "node": self.node,
                "fsm": self.fsm, "action": self.action, "args": self.args, "vars": self.vars}


def _parse_line(path: str, number: int, text: str) -> Line:
    where = f"{path}:{number}"
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise TraceInputError(f"{where}: not JSON: {error.msg} (column {error.colno})") from None
    if not isinstance(data, dict):
        raise TraceInputError(f"{where}: a trace line is a JSON object")
    missing = [key for key in REQUIRED if key not in data]
    if missing:
        raise TraceInputError(f"{where}: missing field(s) {', '.join(missing)}")
    t_ns, node, fsm, action = data["t_ns"], data["node"], data["fsm"], data["action"]
    args = data.get("args", {})
    variables = data["vars"]
    if not isinstance(t_ns, int) or isinstance(t_ns, bool) or t_ns < 0:
        raise TraceInputError(f"{where}: t_ns must be a non-negative integer")
    if fsm not in FSMS:
        raise TraceInputError(f"{where}: unknown fsm {fsm!r} (one of {', '.join(FSMS)})")
    if node is not None and not isinstance(node, str):
        raise TraceInputError(f"{where}: node must be a string (or null for env lines)")
    if node is None and fsm != "env":
        raise TraceInputError(f"{where}: a {fsm} line needs a node")
    if not isinstance(action, str) or not action:
        raise TraceInputError(f"{where}: action must be a non-empty string")
    if not isinstance(args, dict):
        raise TraceInputError(f"{where}: args must be an object")
    if not isinstance(variables, dict):
        raise TraceInputError(f"{where}: vars must be an object")
    action = LEGACY_ACTIONS.get((fsm, action), action)
    actor = ACTOR.get((fsm, action))
    if actor is not None and actor in args and args[actor] != node:
        raise TraceInputError(f"{where}: a {fsm} {action} line of {node} whose args name "
                              f"{actor}={args[actor]!r} as the node that acts: a line "
                              "contradicts itself")
    return Line(path, number, t_ns, node, fsm, action, args, variables)


def trace_files(paths: list[str]) -> list[Path]:
    """The files to read: each argument, or every ``*.ndjson`` of a run directory."""
    files: list[Path] = []
    for argument in paths:
        path = Path(argument)
        if path.is_dir():
            found = sorted(path.glob("*.ndjson")) or sorted(path.glob("**/*.ndjson"))
            if not found:
                raise TraceInputError(f"{argument}: no *.ndjson trace in this directory")
            files.extend(found)
        elif path.is_file():
            files.append(path)
        else:
            raise TraceInputError(f"{argument}: no such file or directory")
    return files


def load(paths: list[str]) -> list[Line]:
    """Every line of every file, merged by t_ns (stable: file order, then line order)."""
    lines: list[Line] = []
    for index, path in enumerate(trace_files(paths)):
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as error:
            raise TraceInputError(f"{path}: cannot read: {error}") from None
        for number, raw in enumerate(text.splitlines(), start=1):
            if not raw.strip():
                continue
            line = _parse_line(str(path), number, raw)
            lines.append(line)
        del index
    lines.sort(key=lambda line: line.t_ns)  # sort is stable: ties keep file, line order
    return causal_order(lines)


# keel-node stamps a line when it writes it, after the step has sent its messages; on one
# machine a receiver can then log its receipt a few microseconds "before" the sender's
# line, and on a loaded machine (a sender's thread preempted between its send and its
# log line) several milliseconds: a Master's CompleteSwitch once came 5+ ms before a
# node's logged Ack. Within this window a receipt is moved after the line that caused it
# (the causes are specific: the same epoch, switch, task and version; see _causes and
# _caused_before).
SKEW_NS = 50_000_000


def _causes(effect: Line, cause: Line) -> bool:
    """Whether `cause` (another node's line) is the send that `effect` received."""
    a, c = effect.args, cause.args
    if effect.fsm == "switch" and cause.fsm == "switch":
        if effect.action in ("CompleteSwitch", "BroadcastActivate") and cause.action == "Ack":
            kind = "Activated" if effect.action == "CompleteSwitch" else "Prepared"
            return (c.get("kind") == kind and cause.vars.get("seq") == a.get("seq")
                    and cause.vars.get("epoch") == effect.vars.get("epoch"))
        if effect.action == "ReceiveCommand" and cause.action == "BroadcastCommand":
            return (c.get("epoch"), c.get("seq"), c.get("c")) == (
                a.get("epoch"), a.get("seq"), a.get("c"))
        if effect.action == "ReceiveActivate" and cause.action == "BroadcastActivate":
            return c.get("seq") == a.get("seq") and cause.vars.get("epoch") == a.get("epoch")
        if effect.action == "StoreCheckpoint" and cause.action == "FlushCheckpoint":
            return (cause.node, c.get("t"), c.get("version")) == (
                a.get("from"), a.get("t"), a.get("version"))
        if effect.action == "Activate" and cause.action == "StoreCheckpoint":
            return a.get("restored") is True and (c.get("t"), c.get("version")) == (
                a.get("t"), a.get("version"))
    if effect.fsm == "election" and cause.fsm == "election":
        return (effect.action == "ReceiveCommand" and cause.action == "BecomeMaster"
                and cause.node == a.get("from") and c.get("epoch") == a.get("epoch"))
    return False


def _caused_before(order: list[Line], i: int, skew_ns: int) -> bool:
    """Whether the one send that line `i` received is already before it: a later line that
    looks the same (a final flush of the version a periodic write stored a moment before)
    is then not its cause."""
    effect = order[i]
    if effect.action in ("CompleteSwitch", "BroadcastActivate"):
        return False  # these wait for an ack of every node: each may be a cause
    for k in range(i - 1, -1, -1):
        cause = order[k]
        if cause.t_ns < effect.t_ns - skew_ns:
            return False
        if cause.node not in (None, effect.node) and _causes(effect, cause):
            return True
    return False


def causal_order(lines: list[Line], skew_ns: int = SKEW_NS) -> list[Line]:
    """Lines in t_ns order, except that a line is moved (with the lines of its node that
    follow it in the window) after a send it received that carries a slightly later t_ns,
    unless a send it could have received is before it already."""
    order = list(lines)
    start = 0  # the lines before it need no move (a pass moves the first that does)
    for _ in range(len(order)):  # a limit: every pass moves at least one line forward
        moved = False
        for i in range(start, len(order)):
            effect = order[i]
            if effect.node is None:
                continue
            last = -1
            for j in range(i + 1, len(order)):
                cause = order[j]
                if cause.t_ns > effect.t_ns + skew_ns:
                    break
                if cause.node not in (None, effect.node) and _causes(effect, cause):
                    last = j
            if last < 0 or _caused_before(order, i, skew_ns):
                continue
            mine = [k for k in range(i, last + 1) if order[k].node == effect.node]
            block = [order[k] for k in mine]
            rest = [order[k] for k in range(i, last + 1) if order[k].node != effect.node]
            order[i:last + 1] = rest + block
            moved = True
            start = i
            break
        if not moved:
            break
    return order
