"""ConfigSwitch: the switch lines of every node but the Storage node, merged, against
spec/ConfigSwitch.tla with the mission's configurations (spec/trace/TraceConfigSwitch.tla).
"""

from __future__ import annotations

from . import tla, values
from .engine import Job
from .load import Line
from .mission_facts import Facts

SAFE = "SAFE"
UNPLACED = "unplaced"  # ConfigSwitch's Unplaced: a task of another phase
VARS = ("epoch", "seq", "config", "stage", "active", "unflushed", "version", "masterStage",
        "masterConfig", "masterSeq", "failed")
# A node's own switch (as opposed to the one it drives as Master).
PARTICIPANT = {"epoch", "seq", "config", "stage", "active", "unflushed", "version"}
# Environment lines the spec has no counterpart for: validation stops before them.
UNMODELLED_ENV = {"Partition": "partitions", "Block": "partitions",
                  "Resign": "resignations (a node asking to be excluded)"}
# Switch lines the spec has no counterpart for: validation stops before them.
UNMODELLED_SWITCH = {"Resign": "resignations (a node asking to be excluded)",
                     "AskHolders": "Storage failures (a task's state taken from its old host)",
                     "StateOutOfReach": "Storage failures (a task's state out of reach)"}
# The lease's lines (spec/Lease.tla): they change no ConfigSwitch variable (a held task
# stays active in the switch; it only stops running): steps that change nothing.
LEASE = ("Hold", "Release", "LeaseLapsed")


def _record(line: Line, action: str, node: str, dropped: set[str]) -> str:
    args, state = line.args, line.vars
    has = [k for k in VARS if k in state and k not in dropped]
    fields = {
        "action": tla.string(action),
        "n": tla.string(node),
        # The readmitted node of a Readmit line; the failed node of a DeclareFailed.
        "f": tla.literal(args.get("r", "none") if action in ("Readmit", "HandOver")
                         else args.get("f", "none")),
        "c": tla.literal(args.get("c", "none")),
        "t": tla.literal(args.get("t", "none")),
        "kind": tla.literal(args.get("kind", "none")),
        "epoch": tla.literal(args.get("epoch", 0)),
        "seq": tla.literal(args.get("seq", 0)),
        "version": tla.literal(args.get("version", 0)),
        "has": tla.literal(has),
    }
    defaults: dict[str, object] = {"epoch": 0, "seq": 0, "config": "none", "stage": "none",
                                   "active": [], "unflushed": [], "version": {},
                                   "masterStage": "none", "masterConfig": "none",
                                   "masterSeq": 0, "failed": []}
    for key in VARS:
        fields["v" + key] = tla.literal(state.get(key, defaults[key]))
    return tla.record(fields)


def jobs(lines: list[Line], facts: Facts) -> list[Job]:
    mission = facts.mission
    storage = facts.storage
    # The Storage node takes part in switches like any node (it acks, and may run tasks);
    # its StoreCheckpoint lines are the spec's `stored`.
    nodes = list(facts.nodes)
    tasks = list(mission.tasks)
    configs = {name: cfg for phase in mission.phases.values()
               for name, cfg in phase.configurations.items()}
    notes: list[str] = []
    if storage is None:
        notes.append("the mission has no storage node")
        return [_empty(notes)]
    selected: list[tuple[Line, str, str, set[str]]] = []
    skipped = 0
    lease = 0
    stopped = ""
    for line in lines:
        if line.fsm == "env":
            if line.action in UNMODELLED_ENV:
                stopped = (f"validated up to {line.where} ({line.action}): ConfigSwitch has "
                           f"no {UNMODELLED_ENV[line.action]}")
                break
            if line.action in ("Crash", "Restart") and line.args.get("n") in nodes:
                selected.append((line, line.action, str(line.args["n"]), set()))
            continue
        if line.fsm != "switch":
            continue
        args, action = line.args, line.action
        if action in UNMODELLED_SWITCH:
            stopped = (f"validated up to {line.where} ({action}): ConfigSwitch has no "
                       f"{UNMODELLED_SWITCH[action]}")
            break
        if args.get("c") == SAFE:
            stopped = f"validated up to {line.where}: safe mode is not part of ConfigSwitch"
            break
        if line.node == storage and action == "StoreCheckpoint":
            selected.append((line, "Store", str(args.get("from")), set()))
            continue
        node = str(line.node)
        if action in LEASE:
            lease += 1
            selected.append((line, "Lease", node, set()))
            continue
        if action == "BecomeMaster":
            selected.append((line, "TakeOver", node, set()))
        elif action == "FlushCheckpoint":
            if args.get("final"):
                selected.append((line, "FlushFinal", node, {"unflushed"}))
            else:
                selected.append((line, "Steps", node, set()))
        elif action == "Deactivate":
            selected.append((line, "Deactivate", node, {"unflushed"}))
        elif action == "BroadcastCommand":
            # Logged before the Master delivers the command to itself (the spec's
            # StartSwitch has already applied it): only the driver's variables compare.
            selected.append((line, action, node, PARTICIPANT))
        elif action in ("BootSwitch", "DeclareFailed", "RequestPhase", "ReceiveCommand", "Readmit",
                        "HandOver",
                        "Ack", "BroadcastActivate", "ReceiveActivate", "Activate",
                        "CompleteSwitch"):
            selected.append((line, action, node, set()))
        else:
            skipped += 1
    if stopped:
        notes.append(stopped)
    if skipped:
        notes.append(f"{skipped} line(s) of actions ConfigSwitch has no counterpart for")
    if lease:
        notes.append(f"{lease} lease line(s) (Hold, Release, LeaseLapsed) validated as steps "
                     "that change no ConfigSwitch variable (spec/Lease.tla states the lease)")
    while selected and selected[-1][1] in ("Crash", "Restart"):
        selected.pop()
    count = max(len(selected), 1)
    checkpointed = [t for t, task in mission.tasks.items() if task.checkpoint]
    place = "[c \\in TConfigIds |-> " + "CASE " + "\n    [] ".join(
        f"c = {tla.string(name)} -> "
        f"{tla.literal({t: cfg.placement.get(t, UNPLACED) for t in tasks})}"
        for name, cfg in configs.items()) + "]"
    on_failure = []
    on_phase: dict[str, set[str]] = {name: set() for name in configs}
    for phase in mission.phases.values():
        for config, edges in phase.on_failure.items():
            for failed, target in edges.items():
                on_failure.append(f"<<{tla.string(config)}, {tla.string(failed)}>> :> "
                                  f"{tla.string(target)}")
        for _target_phase, mapping in phase.on_phase.items():
            for source, target in mapping.items():
                on_phase.setdefault(source, set()).add(target)
    failure_map = "(" + " @@ ".join(on_failure) + ")" if on_failure else "<<>>"
    priority = "<<" + ", ".join(tla.string(n) for n in facts.priority) + ">>"
    first_phase = next(iter(mission.phases.values()))
    late = [x for x in _late_nodes(selected, nodes) if x != facts.priority[0]]
    job = Job(
        protocol="switch",
        subject="cluster",
        template="TraceConfigSwitch",
        lines=[ln for ln, *_ in selected],
        records=[_record(ln, action, node, dropped) for ln, action, node, dropped in selected],
        definitions={
            "TNodes": tla.literal(nodes),
            "TPriority": priority,
            "TTasks": tla.literal(tasks),
            "TCheckpointed": tla.literal(checkpointed),
            "TConfigIds": tla.literal(list(configs)),
            "TPlace": place,
            "TPlacement(c, t)": "TPlace[c][t]",
            "TFailureMap": failure_map,
            "TOnFailure(c, f)": "IF <<c, f>> \\in DOMAIN TFailureMap THEN TFailureMap[<<c, f>>] "
                                "ELSE c",
            "TOnPhaseMap": tla.literal({k: sorted(v) for k, v in on_phase.items()}),
            "TOnPhase(c)": "TOnPhaseMap[c]",
            "TLate": tla.literal(late),
            "TMasterMap": tla.literal({name: cfg.master for name, cfg in configs.items()}),
            "TMasterOf(c)": "TMasterMap[c]",
        },
        constants=[
            "Nodes <- TNodes", "Priority <- TPriority", f"Storage = {tla.string(storage)}",
            "Tasks <- TTasks", "Checkpointed <- TCheckpointed", "ConfigIds <- TConfigIds",
            "MasterOf <- TMasterOf",
            f"InitialConfig = {tla.string(first_phase.initial)}", "Placement <- TPlacement",
            "OnFailure <- TOnFailure", "OnPhase <- TOnPhase",
            f"MaxCrashes = {len(facts.priority) - 1}", f"MaxPhaseChanges = {count}",
            f"MaxVersion = {10 ** 9}", f"MaxLateBoots = {len(nodes) - 1}",
            f"MaxHidden = {len(nodes) * len(tasks) + len(nodes) + 2}",
        ],
        spec_values=lambda line, state: _spec_values(line, state, storage, checkpointed),
        compared=lambda line: _compared(line, checkpointed),
        skipped=skipped,
        notes=notes,
    )
    return [job] if selected else []


def _late_nodes(selected: list[tuple[Line, str, str, set[str]]],
                nodes: list[str]) -> list[str]:
    """The nodes a Master declared failed (or a take-over found failed) before their first
    line: their processes started after that, so the spec's Init leaves them unbooted."""
    seen: set[str] = set()
    late: list[str] = []
    for line, action, node, _dropped in selected:
        declared: list[str] = []
        if action == "DeclareFailed":
            declared = [str(line.args.get("f"))]
        elif action == "TakeOver":
            declared = [str(n) for n in line.vars.get("failed", []) or []]
        for x in declared:
            if x in nodes and x not in seen and x not in late:
                late.append(x)
        if action not in ("Crash", "Restart", "Store"):
            seen.add(node)
    return late


def _compared(line: Line, checkpointed: list[str]) -> dict[str, object]:
    out = {k: v for k, v in line.vars.items() if k in VARS}
    if line.action == "BroadcastCommand":
        out = {k: v for k, v in out.items() if k not in PARTICIPANT}
    if isinstance(out.get("version"), dict):
        out["version"] = {t: v for t, v in out["version"].items() if t in checkpointed}
    return out


def _empty(notes: list[str]) -> Job:
    return Job("switch", "cluster", "TraceConfigSwitch", [], [], {}, [],
               lambda line, state: {}, lambda line: {}, notes=notes)


def _spec_values(line: Line, state: dict[str, str], storage: str,
                 checkpointed: list[str]) -> dict[str, object]:
    node = line.args.get("from") if line.node == storage and line.action == "StoreCheckpoint" \
        else line.node
    out: dict[str, object] = {}
    for var in VARS:
        if var in state:
            function = values.parse(state[var])
            if isinstance(function, dict) and node in function:
                value = function[node]
                out[var] = value
    if "version" in out and isinstance(out["version"], dict):
        logged = line.vars.get("version", {}) or {}
        out["version"] = {k: v for k, v in out["version"].items()
                          if k in logged and k in checkpointed}
    if line.action == "BroadcastCommand":
        out = {k: v for k, v in out.items() if k not in PARTICIPANT}
    return out
