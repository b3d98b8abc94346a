"""MasterElection: the processing nodes' election lines, merged, against
spec/MasterElection.tla (spec/trace/TraceElection.tla)."""

from __future__ import annotations

from . import tla, values
from .engine import Job
from .load import Line
from .mission_facts import Facts

ACTIONS = {"Suspect", "BecomeMaster", "ReceiveCommand", "OpenEpoch", "WarmBoot"}
# Reintegration's switch lines (spec/Rejoin.tla): a view that readmits a node (its
# election side is the Master's OpenEpoch line), or one handed over to another Master
# (TraceElection's HandOver).
READMISSION = ("Readmit", "HandOver")
NO_NODE = "none"


def _record(line: Line, action: str, processing: list[str], fenced: str = "?") -> str:
    args, state = line.args, line.vars
    if action == "HandOver":  # the switch's line: the Master hands its view to `to`
        args = {"n": line.node, "m": args.get("to", NO_NODE), "epoch": args.get("epoch", 0)}
        state = {}
    suspects = [s for s in state.get("suspects", []) or [] if s in processing]
    passed_arg = args.get("passed") if action == "BecomeMaster" else None
    heard = passed_arg if isinstance(passed_arg, dict) else {}
    passed = list(passed_arg or [])
    leader = state.get("leader")
    return tla.record({
        "action": tla.string(action),
        "n": tla.literal(args.get("n", line.node)),
        "m": tla.literal(args.get("m", NO_NODE)),
        "from": tla.literal(args.get("from", NO_NODE)),
        "epoch": tla.literal(args.get("epoch", 0)),
        "above": tla.literal(args.get("above", 0)),
        "vrole": tla.literal(state.get("role", "")),
        "vepoch": tla.literal(state.get("epoch", 0)),
        "vleader": tla.literal(leader if leader is not None else NO_NODE),
        "vsuspects": tla.literal(suspects),
        # A take-over's members passed over for going by an older epoch, with the epoch
        # each last said (TraceElection's PassOver; a list, of a build before: no epochs).
        "passed": tla.literal([p for p in passed if p in processing]),
        "heard": tla.literal({p: e for p, e in heard.items() if p in processing}),
        # Of them, those passed over for a newer switch of the taker's view's epoch.
        "newer": tla.literal([p for p in (args.get("newer") or []) if p in processing]
                             if action == "BecomeMaster" else []),
        # and those passed over for never preparing the taker's view.
        "unprepared": tla.literal([p for p in (args.get("unprepared") or []) if p in processing]
                                  if action == "BecomeMaster" else []),
        "vlast": tla.literal(state.get("lastCommand", 0)),
        # A ReceiveCommand line says whether the node stepped down (was Master, is not).
        "stepDown": tla.string({True: "yes", False: "no"}.get(args.get("stepDown"), "?")),
        # A ReceiveCommand line: whether the Command's view excludes its receiver ("yes",
        # "no"; "?" without the node's switch line of the same Command): it runs fenced.
        "fenced": tla.string(fenced),
    })


def _fenced(lines: list[Line]) -> dict[tuple[str, int], str]:
    """Each switch ReceiveCommand line's receiver and time: "yes" when the view it adopted
    excludes it (its `out`), else "no". The election line of the same Command has the same
    node and time."""
    out: dict[tuple[str, int], str] = {}
    for line in lines:
        if line.fsm == "switch" and line.action == "ReceiveCommand" and line.node is not None:
            excluded = line.args.get("out")
            if isinstance(excluded, list):
                out[(line.node, line.t_ns)] = "yes" if line.node in excluded else "no"
    return out


def jobs(lines: list[Line], facts: Facts) -> list[Job]:
    processing = facts.priority
    followers = [n for n in facts.nodes if n not in processing]
    fenced = _fenced(lines)
    # A node that boots late (keel-sim's Boot line) is, to the spec, a node whose lines
    # start late: alive from the start and silent. A crash before that boot cancels it (the
    # process never ran; its Boot line is then its first boot): no crash of the spec.
    boots = {}
    for line in lines:
        if line.fsm == "env" and line.action == "Boot":
            boots.setdefault(line.args.get("n"), line.t_ns)
    selected: list[tuple[Line, str]] = []
    skipped = 0
    skipped_env = 0
    notes = []
    for line in lines:
        if line.fsm == "switch" and line.action == "HandOver":
            selected.append((line, "HandOver"))
            continue
        if line.fsm == "election":
            if line.node in followers and line.action == "ReceiveCommand":
                # A node outside the succession obeys the Master (TraceElection's
                # FollowerCommand).
                selected.append((line, "FollowerCommand"))
                continue
            if line.node not in processing or line.action not in ACTIONS:
                skipped += 1
                continue
            action = line.action
            if action == "Suspect" and line.args.get("m") not in processing:
                action = "SuspectOther"
            if action == "BecomeMaster" and "above" in line.args:
                action = "Reclaim"
            selected.append((line, action))
        elif line.fsm == "env" and line.action in ("Crash", "Restart") \
                and line.args.get("n") in processing:
            if line.t_ns < boots.get(line.args.get("n"), -1):
                skipped_env += 1
                continue
            selected.append((line, line.action))
    while selected and selected[-1][0].fsm == "env":
        selected.pop()
    count = max(len(selected), 1)
    if skipped_env:
        notes.append(f"{skipped_env} crash or restart line(s) of nodes before their late boot "
                     "(the process had not run yet) are no step of MasterElection")
    if skipped:
        notes.append(f"{skipped} election line(s) of nodes outside the succession "
                     "(storage, interface) other than ReceiveCommand are not part of "
                     "MasterElection")
    job = Job(
        protocol="election",
        subject="cluster",
        template="TraceElection",
        lines=[ln for ln, _ in selected],
        records=[_record(ln, action, processing,
                         fenced.get((ln.node or "", ln.t_ns), "?")
                         if action == "ReceiveCommand" else "?")
                 for ln, action in selected],
        definitions={"TPriority": "<<" + ", ".join(tla.string(n) for n in processing) + ">>",
                     "TFollowers": tla.literal(followers)},
        constants=[
            "Priority <- TPriority", "Followers <- TFollowers",
            f"NumObservers = {len(facts.monitors) - 1}",
            f"MaxCrashes = {count}", f"MaxRestarts = {count}",
            f"MaxFalseSuspicions = {count}", f'NoNode = "{NO_NODE}"',
            f"MaxHidden = {2 * len(processing) + 2}",
        ],
        spec_values=lambda line, state: _spec_values(line, state),
        compared=lambda line: _compared(line, processing),
        skipped=skipped,
        notes=notes,
    )
    return [job] if selected else []


def _compared(line: Line, processing: list[str]) -> dict[str, object]:
    if line.fsm != "election":
        return {}
    out = {k: line.vars[k] for k in ("role", "epoch", "leader", "lastCommand") if k in line.vars}
    if "suspects" in line.vars:
        out["suspects"] = [s for s in line.vars["suspects"] or [] if s in processing]
    if out.get("leader") is None and "leader" in out:
        out["leader"] = NO_NODE
    return out


def _spec_values(line: Line, state: dict[str, str]) -> dict[str, object]:
    node = line.args.get("n", line.node)
    out: dict[str, object] = {}
    for var in ("role", "epoch", "leader", "suspects", "lastCommand"):
        if var in state:
            function = values.parse(state[var])
            if isinstance(function, dict) and node in function:
                out[var] = function[node]
    return out
