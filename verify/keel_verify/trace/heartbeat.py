"""Heartbeat: each node's lines against spec/Heartbeat.tla with that node as the monitor
(spec/trace/TraceHeartbeat.tla)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from . import explicit_heartbeat, tla, values
from .environment import Environment
from .engine import Job
from .load import Line
from .mission_facts import Facts

# A node's own resignation (a Master's Resign, a Worker's AskExclusion).
RESIGN = ("Resign", "AskExclusion")
ACTIONS = {"Tick", "SendHeartbeat", "ReceiveHeartbeat", "DeclareFailed", "Readmit", "Rejoin",
           "Withdraw"}


def _fields(line: Line, action: str, nodes: list[str],
            lossy: list[str] | None = None) -> dict[str, object]:
    """Log[i] as JSON values: turned into a TLA+ record for TLC (``_record``) and read as
    they are by the explicit-state port (explicit_heartbeat.py), so both check one Log."""
    args, state = line.args, line.vars
    missed = state.get("missed", {})
    if not isinstance(missed, dict):
        missed = {}
    return {
        "action": action,
        "n": args.get("n", args.get("m", line.node)),
        "reason": args.get("reason", "missed"),
        # A Tick whose monitor suspected itself (it heard no one, or ran late) counts no miss.
        # `late` of a Tick that counts: whether the node logged a cause to suspect itself
        # (its loop ran late, or it heard no other node at all): then it must not count.
        "suspect": args.get("suspect") is True,
        "late": args.get("late") is True if args.get("suspect") is True
        else args.get("late") is True or args.get("silent") is True,
        "heard": state.get("heard", []),
        "missed": {k: v for k, v in missed.items() if k in nodes},
        # A node the cluster excluded lists itself: that is no heartbeat declaration.
        "failed": [n for n in state.get("failed", []) or [] if n != line.node],
        # Start-up grace: the nodes heard since the node booted (absent in older traces).
        "hasHeardOnce": "heardOnce" in state,
        "heardOnce": [n for n in state.get("heardOnce", []) or [] if n in nodes],
        # A Tick's senders whose loss in the period may go beyond the loss bound: the
        # environment's faults on their link, or they sent nothing (environment.py).
        "lossy": lossy or [],
    }


def _record(fields: dict[str, object]) -> str:
    return tla.record({name: tla.literal(value) for name, value in fields.items()})


@dataclass
class ExplicitPort:
    """A job's check by the Python port of TraceHeartbeat (explicit_heartbeat.py): the
    same constants and Log as TLC's. The records are made again as the port reads them:
    kept for every line, they cost the garbage collector more than they save."""

    constants: explicit_heartbeat.Constants
    lines: list[Line]
    actions: list[str]  # the action each line is in Log (markers: ViewChange, Restart)
    nodes: list[str]
    lossy: list[list[str]]  # each line's `lossy`

    def records(self) -> Iterator[dict[str, object]]:
        for line, action, lossy in zip(self.lines, self.actions, self.lossy, strict=True):
            yield _fields(line, action, self.nodes, lossy)

    def __call__(self) -> explicit_heartbeat.ExplicitRun:
        return explicit_heartbeat.check(self.constants, self.records())


def cfg_constants(constants: explicit_heartbeat.Constants) -> list[str]:
    """The constants as TLC's cfg binds them (the sets are the definitions TNodes, ...)."""
    c = constants
    return ["Nodes <- TNodes", "Monitors <- TMonitors", "M <- TM", "Order <- TOrder",
            f"MissLimit = {c.miss_limit}", f"MaxLoss = {c.max_loss}",
            f"MaxCrashes = {c.max_crashes}", f"StartupGrace = {c.startup_grace}",
            f"MaxLateBoots = {c.max_late_boots}", f"MaxBootDelay = {c.max_boot_delay}",
            f"MaxHidden = {c.max_hidden}"]


def jobs(lines: list[Line], facts: Facts) -> list[Job]:
    nodes = facts.nodes
    environment = Environment(lines, nodes, facts.mission.heartbeat.period_ms * 1_000_000)
    by_node: dict[str, list[tuple[Line, str]]] = {}
    for line in lines:
        if line.fsm == "heartbeat" and line.node in nodes and line.action in ACTIONS:
            by_node.setdefault(line.node, []).append((line, line.action))
    result = []
    for node in sorted(by_node):
        selected: list[tuple[Line, str]] = []
        notes: list[str] = []
        for line in lines:
            if line.node == node and line.fsm == "heartbeat" and line.action in ACTIONS:
                selected.append((line, line.action))
            elif line.node == node and line.fsm == "election" and line.action == "ReceiveCommand":
                selected.append((line, "ViewChange"))
            elif line.node == node and line.fsm == "switch" and line.action in RESIGN:
                # A Master that steps down stops monitoring (it sends heartbeats, counts
                # nothing): a view change, after which its boundaries are not counted
                # until its next Tick (TraceHeartbeat's UncountedTick).
                selected.append((line, "ViewChange"))
            elif line.fsm == "env" and line.action == "Restart" and line.args.get("n") == node:
                selected.append((line, "Restart"))
        # Markers after the node's last heartbeat line explain nothing.
        while selected and selected[-1][1] not in ACTIONS:
            selected.pop()
        # Each Tick's `lossy`: the period it ends starts at the node's previous Tick (or
        # its restart).
        lossy: list[list[str]] = []
        previous: int | None = None
        for ln, action in selected:
            if action == "Tick":
                suspect = ln.args.get("suspect") is True or ln.args.get("late") is True
                lossy.append(environment.lossy(node, previous, ln.t_ns, suspect))
                previous = ln.t_ns
            else:
                lossy.append([])
                if action == "Restart":
                    previous = ln.t_ns
        skipped = sum(1 for ln in lines if ln.node == node and ln.fsm == "heartbeat"
                      and ln.action not in ACTIONS)
        # The model's constants, for TLC's cfg and for the port alike.
        constants = explicit_heartbeat.Constants(
            nodes=tuple(nodes), monitors=(node,), m=node,
            order=tuple(n for n in nodes if n != node), miss_limit=facts.miss_limit,
            max_loss=max(facts.miss_limit - 1, 0), max_crashes=0, startup_grace=facts.startup_grace,
            max_late_boots=0, max_boot_delay=0, max_hidden=2 * len(nodes) + 4)
        job_lines = [ln for ln, _ in selected]
        actions = [action for _, action in selected]
        job = Job(
            protocol="heartbeat",
            subject=node,
            template="TraceHeartbeat",
            lines=job_lines,
            records=[_record(_fields(ln, action, nodes, lost))
                     for (ln, action), lost in zip(selected, lossy, strict=True)],
            definitions={
                "TNodes": tla.literal(list(constants.nodes)),
                "TMonitors": tla.literal(list(constants.monitors)),
                "TM": tla.string(constants.m),
                "TOrder": "<<" + ", ".join(tla.string(n) for n in constants.order) + ">>",
            },
            constants=cfg_constants(constants),
            explicit=ExplicitPort(constants, job_lines, actions, nodes, lossy),
            spec_values=lambda line, state, node=node: _spec_values(node, state),
            compared=lambda line: _compared(line),
            compared_before=lambda line: _compared_before(line),
            skipped=skipped,
            notes=notes,
        )
        result.append(job)
    return result


def _period_end(line: Line) -> bool:
    """A Tick and its declarations log the `heard` of the period that ends."""
    return line.action == "Tick" or (line.action == "DeclareFailed"
                                     and line.args.get("reason", "missed") == "missed")


def _compared_before(line: Line) -> dict[str, object]:
    if line.fsm == "heartbeat" and line.action == "Tick" and "heard" in line.vars:
        return {"heard": line.vars["heard"]}
    return {}


def _compared(line: Line) -> dict[str, object]:
    if line.fsm != "heartbeat":
        return {}
    out = {k: line.vars[k] for k in ("heard", "missed", "failed", "heardOnce")
           if k in line.vars}
    if _period_end(line):
        out.pop("heard", None)
    if isinstance(out.get("failed"), list):
        out["failed"] = [n for n in out["failed"] if n != line.node]
    if isinstance(out.get("missed"), dict):
        out["missed"] = {k: v for k, v in out["missed"].items() if k != line.node}
    return out


def _spec_values(node: str, state: dict[str, str]) -> dict[str, object]:
    out: dict[str, object] = {}
    for var in ("heard", "missed", "failed"):
        if var in state:
            function = values.parse(state[var])
            if isinstance(function, dict) and node in function:
                value = function[node]
                if var == "missed" and isinstance(value, dict):
                    value = {k: v for k, v in value.items() if k != node}
                out[var] = value
    # The runtime's heardOnce is the spec's heardOnce \cup heard (see TraceHeartbeat.tla).
    if "heardOnce" in state:
        once = values.parse(state["heardOnce"])
        heard = values.parse(state["heard"]) if "heard" in state else {}
        if isinstance(once, dict) and node in once:
            now = heard.get(node, []) if isinstance(heard, dict) else []
            out["heardOnce"] = frozenset(once[node] or ()) | frozenset(now or ())
    return out
