"""ConfigSwitch: the switch lines of every node, merged (the Storage node's StoreCheckpoint
lines are the spec's `stored`), against spec/ConfigSwitch.tla with the mission's
configurations, safe mode as a pseudo-configuration per phase and Master
(spec/trace/TraceConfigSwitch.tla).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from . import tla, values
from .engine import Job
from .load import Line
from .mission_facts import Facts
from ..check.model import DecisionGraph
from ..mission import Configuration

SAFE = "SAFE"
# Safe mode as pseudo-configurations (spec/README.md, "Trace validation"): the runtime's
# SAFE view places its phase's essential tasks on its Master and nothing else, so "SAFE"
# in a line is the configuration SAFE_ID.format(phase, master): the phase of the
# configuration safe mode was entered from, the Master that drives it.
SAFE_ID = "SAFE/{}/{}"
UNPLACED = "unplaced"  # ConfigSwitch's Unplaced: a task of another phase
# Online configurations (core/fsm/online.hpp): a line names one "online" and carries it
# whole (`online`: its phase, master, observers and hosts). Each switch <<epoch, seq>> that
# goes to one is the pseudo-configuration ONLINE_ID.format(epoch, seq), with that placement,
# registered only where the checker (the verifier's "valid under F", non-essential tasks
# may be shed) accepts it under the failed set of the switch: the spec's switch target is
# any configuration the checker accepts (spec/Online.tla). A phase's `placement` says where
# the decision graph gives way to them (_online_targets).
ONLINE = "online"
ONLINE_ID = "ONLINE/{}.{}"
VARS = ("epoch", "seq", "config", "stage", "active", "unflushed", "version", "masterStage",
        "masterConfig", "masterSeq", "failed")
# A node's own switch (as opposed to the one it drives as Master).
PARTICIPANT = {"epoch", "seq", "config", "stage", "active", "unflushed", "version"}
# Environment lines the spec has no counterpart for: validation stops before them.
UNMODELLED_ENV: dict[str, str] = {}
# Environment lines that only change which messages are delivered, or when (Partition,
# Block, Heal, Deaf, DeafTo, Pause): ConfigSwitch's network may lose, duplicate, delay
# and reorder any message (msgs and acks only grow; no step must receive), so a cut
# link is a run in which those messages are not received: no spec step, no line. A node
# the cluster excludes for it, alive, is fenced at that exclusion (TraceConfigSwitch's
# Fence: Lease.tla makes it stop first).
# Switch lines the spec has no counterpart for: validation stops before them.
UNMODELLED_SWITCH: dict[str, str] = {}
# The lease's lines (spec/Lease.tla): they change no ConfigSwitch variable (a held task
# stays active in the switch; it only stops running): steps that change nothing.
LEASE = ("Hold", "Release", "LeaseLapsed")
# The ground's vote (spec/Designate.tla): a designation a node took (GroundDesignate), and a
# node's lease lapsed in a tie (StandDown) or resumed (StandUp). Steps that change no
# ConfigSwitch variable; a decision the vote completed is held to the designation by
# _vote_held.
GROUND_VOTE = ("GroundDesignate", "StandDown", "StandUp")


# A report counts at the decider for the period it arrives in and the next
# (NodeProtocol's reports_now_ and reports_before_, swapped at each of its period
# boundaries, before it considers exclusions); a monitor sends one every period while it
# holds its declaration (NodeProtocol::tick). Its last report, sent before it stopped
# holding it, arrives within the decider's period of that instant or the next (a message's
# delay below a period), and counts until the boundary after the next: at most two of the
# decider's Tick lines come after the declaration ended, its deciding step's own included.
# From EXPIRED_PERIODS on, the report is no evidence any more.
EXPIRED_PERIODS = 3


def _vote_held(lines: list[Line], facts: Facts) -> dict[tuple[str, int], bool]:
    """Per Exclude and take-over (BecomeMaster) line that says the ground's vote completed
    its evidence (`vote`), keyed by (file, line number): whether the decider held the vote
    then and each node the vote completed was one it could not hear (TraceConfigSwitch's
    `voteOk`). The vote is its own (its last GroundDesignate line names it), its wait is
    over (the line at least `wait` periods after it took the designation) and its span is
    not (less than `span` periods after: the span counts from an earlier heartbeat, so the
    runtime's end comes first); and the decider's own declaration of each such node, still
    held, came at least tie_grace periods before (spec/Designate.tla, rule 4)."""
    period = facts.period_ns
    slack = period // 10  # the clocks' drift over a span, and a line's own time
    designation: dict[str, tuple[str, int, int, int]] = {}  # node -> (designee, at, wait, span)
    declared: dict[tuple[str, str], int] = {}  # (monitor, node) -> time of its declaration
    out: dict[tuple[str, int], bool] = {}
    for line in lines:
        node, args = str(line.node), line.args
        if line.fsm == "heartbeat":
            if line.action == "DeclareFailed":
                declared.setdefault((node, str(args.get("n"))), line.t_ns)
            elif line.action in ("Withdraw", "Readmit"):
                declared.pop((node, str(args.get("n"))), None)
            elif line.action == "Rejoin":
                kept = {str(x) for x in line.vars.get("failed", []) or []}
                for key in [k for k in declared if k[0] == node and k[1] not in kept]:
                    declared.pop(key)
            continue
        if line.fsm == "env" and line.action == "Restart":
            restarted = str(args.get("n"))
            designation.pop(restarted, None)
            for key in [k for k in declared if k[0] == restarted]:
                declared.pop(key)
            continue
        if line.fsm != "switch":
            continue
        if line.action == "GroundDesignate":
            designation[node] = (str(args.get("d")), line.t_ns, int(args.get("wait", 0)),
                                 int(args.get("span", 0)))
            continue
        if line.action == "Exclude" and args.get("vote") is True:
            voted, decider = [str(args.get("f"))], str(args.get("m", node))
        elif line.action == "BecomeMaster" and isinstance(args.get("vote"), list) and args["vote"]:
            voted, decider = [str(x) for x in args["vote"]], str(args.get("n", node))
        else:
            continue
        held = False
        if decider in designation and facts.tie_grace > 0:
            designee, at, wait, span = designation[decider]
            held = (designee == decider and line.t_ns + slack >= at + wait * period
                    and line.t_ns < at + span * period + slack)
        stood = all((decider, x) in declared
                    and declared[(decider, x)] <= line.t_ns - facts.tie_grace * period + slack
                    for x in voted)
        out[(line.file, line.number)] = held and stood
    return out


def _expired_reports(lines: list[Line]) -> dict[tuple[str, int], dict[str, list[str]]]:
    """Per Exclude and take-over (BecomeMaster) line, keyed by (file, line number): for
    each node it excludes on declarations, the reporters it counted whose declaration had
    ended (withdrawn, readmitted, forgotten at the reporter's own readmission or restart)
    EXPIRED_PERIODS or more of the decider's periods before (TraceConfigSwitch's
    `expired`). The decider's own declaration is held to `declaring` instead."""
    held: set[tuple[str, str]] = set()  # (reporter, node) declared and not ended
    ended: dict[tuple[str, str], int] = {}  # (reporter, node) -> index of the line that ended it
    ticks: dict[str, list[int]] = {}  # node -> indices of its heartbeat Tick lines
    out: dict[tuple[str, int], dict[str, list[str]]] = {}

    def end(reporter: str, node: str, at: int) -> None:
        if (reporter, node) in held:
            held.discard((reporter, node))
            ended[(reporter, node)] = at

    def stale(decider: str, reporter: str, node: str, at: int) -> bool:
        if reporter == decider or (reporter, node) in held or (reporter, node) not in ended:
            return False
        since = ended[(reporter, node)]
        return sum(1 for t in ticks.get(decider, []) if t > since) >= EXPIRED_PERIODS

    for at, line in enumerate(lines):
        node, args = str(line.node), line.args
        if line.fsm == "heartbeat":
            if line.action == "Tick":
                ticks.setdefault(node, []).append(at)
            elif line.action == "DeclareFailed":
                held.add((node, str(args.get("n"))))
                ended.pop((node, str(args.get("n"))), None)
            elif line.action in ("Withdraw", "Readmit"):
                end(node, str(args.get("n")), at)
            elif line.action == "Rejoin":
                kept = {str(x) for x in line.vars.get("failed", []) or []}
                for reporter, declared in list(held):
                    if reporter == node and declared not in kept:
                        end(reporter, declared, at)
        elif line.fsm == "env" and line.action == "Restart":
            for reporter, declared in list(held):
                if reporter == str(args.get("n")):
                    end(reporter, declared, at)
        elif line.fsm == "switch" and line.action == "Exclude" and isinstance(args.get("ev"), list):
            failed = str(args.get("f"))
            gone = [str(r) for r in args["ev"] if stale(node, str(r), failed, at)]
            if gone:
                out[(line.file, line.number)] = {failed: gone}
        elif line.fsm == "switch" and line.action == "BecomeMaster" and isinstance(args.get("ev"), dict):
            gone_of = {str(x): [str(r) for r in by if stale(node, str(r), str(x), at)]
                       for x, by in args["ev"].items() if isinstance(by, list)}
            gone_of = {x: rs for x, rs in gone_of.items() if rs}
            if gone_of:
                out[(line.file, line.number)] = gone_of
    return out


def _record(line: Line, action: str, node: str, dropped: set[str],
            expired: dict[str, list[str]] | None = None, rolled_back: bool = False,
            vote_ok: bool = False, placer_places: bool = False) -> str:
    args, state = line.args, line.vars
    has = [k for k in VARS if k in state and k not in dropped]
    fields = {
        "action": tla.string(action),
        "n": tla.string(node),
        # The readmitted node of a Readmit line; the failed node of an Exclude.
        "f": tla.literal(args.get("r", "none") if action in ("Readmit", "HandOver")
                         else args.get("n", "none") if action in ("Resign", "AskExclusion",
                                                                   "Report", "Withdraw")
                         else args.get("f", "none")),
        "c": tla.literal(args.get("c", "none")),
        "t": tla.literal(args.get("t", "none")),
        # Resigned: how it ended; Report: why the monitor declared; Lease: the lease's line
        # (Hold, Release, LeaseLapsed).
        "kind": tla.literal(("flushed" if args.get("flushed") else "abandoned")
                            if action == "Resigned" else args.get("reason", "missed")
                            if action == "Report" else line.action
                            if action == "Lease" else args.get("kind", "none")),
        "epoch": tla.literal(args.get("epoch", 0)),
        "seq": tla.literal(args.get("seq", 0)),
        "version": tla.literal(args.get("version", 0)),
        # Whether an Activate line opens a lineage, and the state it then runs at (mapped
        # like versions).
        "opens": tla.literal("opened" in args),
        "opened": tla.literal(args.get("opened", 0)),
        "has": tla.literal(has),
        # Why a Master's Exclude excludes the node (TraceConfigSwitch's
        # EvidenceSuffices): its own word, the ground's hold (`ground`, false on a line of
        # a build before the Master's ground exclusion), or the members and the
        # declarations that counted.
        "own": tla.literal(bool(args.get("own"))) if action == "Exclude" else "FALSE",
        "ground": tla.literal(bool(args.get("ground"))) if action == "Exclude" else "FALSE",
        "mem": tla.literal(args.get("mem", []) if action in ("Exclude", "TakeOver")
                           else []),
        "ev": tla.literal(args.get("ev", []) if action == "Exclude" else []),
        # A take-over's: the failed nodes of the view it took over, and per node it
        # excludes the declarations that counted (TraceConfigSwitch's TakeOverEvidence).
        "was": tla.literal(args.get("was", []) if action == "TakeOver" else []),
        "evOf": tla.literal(args.get("ev", {}) if action == "TakeOver" else {}),
        # Of the reporters an Exclude or a take-over counted, per node, those whose
        # declaration had ended too long before to be counted (_expired_reports).
        "expired": tla.literal(expired or {}),
        # and the members it passed over for going by an older epoch (`passed`).
        "passed": tla.literal(list(args.get("passed") or []) if action == "TakeOver" else []),
        # Of them, those passed over for a newer switch of the taker's view's epoch (`newer`).
        "newer": tla.literal(list(args.get("newer") or []) if action == "TakeOver" else []),
        # and those passed over for never preparing the taker's view (`unprepared`).
        "unprepared": tla.literal(list(args.get("unprepared") or []) if action == "TakeOver" else []),
        # A take-over that is a warm boot (every node idle after a whole-cluster power
        # cycle, the election job's WarmBoot): a fenced node may make it.
        "warm": tla.literal(action == "TakeOver" and args.get("warm") is True),
        # A ReceiveActivate's (rule 4, TraceConfigSwitch's PeersPreparedLine): the members
        # whose Prepared of the view the node holds, and the nodes the view excludes.
        # A trace of a build before rule 4 logs neither: its lines are not held to it.
        "peers": tla.literal(args.get("peers", []) if action == "ReceiveActivate" else []),
        "out": tla.literal(args.get("out", []) if action in ("ReceiveActivate", "ReceiveCommand")
                           else []),
        "logsPeers": tla.literal("peers" in args and "out" in args),
        # A Restored line's saved epoch (the view's is `epoch`).
        "saved": tla.literal(args.get("saved", 0) if action == "Restored" else 0),
        # and whether that restart read back a state that went back on purpose (keel-sim's
        # rolled-back restart, its env line's `rolled_back`: a lost write, a restored
        # file): the environment's doing, not held to what the node said before.
        "rolledBack": tla.literal(action == "Restored" and rolled_back),
        # A Backed line's (rule 5, TraceConfigSwitch's BackedLine): the Command's sender,
        # and per exclusion the node checked, the kind of backing and the node it came by.
        # A ReceiveCommand's (rule 5, TraceConfigSwitch's BackedComplete): the sender and
        # the view's excluded nodes (`out`); a trace of a build before logs neither.
        "from": tla.literal(args.get("from", "none") if action in ("Backed", "ReceiveCommand",
                                                                   "HeardPrepared")
                            else "none"),
        "logsFrom": tla.literal(action == "ReceiveCommand" and "from" in args),
        "bkKind": tla.literal({x: b[0] for x, b in args.get("by", {}).items()}
                              if action == "Backed" else {}),
        "bkBy": tla.literal({x: b[1] for x, b in args.get("by", {}).items()}
                            if action == "Backed" else {}),
        # spec/Designate.tla, at an Exclude or take-over: the ground a member of the view
        # decided in (`gm`), and what its vote completed (`vote`: the Exclude's node, or
        # the take-over's list), held to a designation the decider took (`voteOk`).
        "gm": tla.literal(args.get("gm") is True if action in ("Exclude", "TakeOver") else False),
        "vote": tla.literal(args.get("vote") is True if action == "Exclude" else False),
        "voted": tla.literal([str(x) for x in args.get("vote") or []]
                             if action == "TakeOver" and isinstance(args.get("vote"), list) else []),
        "voteOk": tla.literal(vote_ok),
        # A take-over into safe mode from an online configuration where the nodes' placer
        # places the essential tasks with this node Master (_safe_where_the_placer_places).
        "placerPlaces": tla.literal(placer_places),
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
    # Masters whose own latest command (epoch, seq) is not delivered to them yet.
    commanding: dict[str, tuple[object, object]] = {}
    for line in lines:
        if line.fsm == "env":
            if line.action in UNMODELLED_ENV:
                stopped = (f"validated up to {line.where} ({line.action}): ConfigSwitch has "
                           f"no {UNMODELLED_ENV[line.action]}")
                break
            if line.action in ("Crash", "Restart") and line.args.get("n") in nodes:
                selected.append((line, line.action, str(line.args["n"]), set()))
            continue
        if line.fsm == "heartbeat" and line.action == "DeclareFailed":
            # A monitor's declaration: what a Master's exclusion may count (Report, which
            # changes no ConfigSwitch variable; its heartbeat variables are not compared).
            selected.append((line, "Report", str(line.node), set(VARS)))
            continue
        if line.fsm == "heartbeat" and line.action in ("Withdraw", "Readmit", "Rejoin"):
            # What the monitor no longer holds declared (TraceConfigSwitch's `declaring`):
            # a declaration withdrawn, forgotten at a readmission, or all but the view's
            # exclusions at its own (Rejoin; `failed` read, not compared).
            selected.append((line, "Rejoin" if line.action == "Rejoin" else "Withdraw",
                             str(line.node), set(VARS)))
            continue
        if line.fsm != "switch":
            continue
        args, action = line.args, line.action
        if action in UNMODELLED_SWITCH:
            stopped = (f"validated up to {line.where} ({action}): ConfigSwitch has no "
                       f"{UNMODELLED_SWITCH[action]}")
            break
        if line.node == storage and action == "StoreCheckpoint":
            selected.append((line, "Store", str(args.get("from")), set()))
            continue
        if line.node == storage and action == "Recovered":
            # What a restarted Storage node read back from its disk: never below a
            # StoreCheckpoint line it logged (TraceConfigSwitch's `written`).
            selected.append((line, "Recovered", str(line.node), set()))
            continue
        node = str(line.node)
        if action == "HeardPrepared":
            # A member's Prepared received (its first receipt): the member said that view;
            # it must have acked it (TraceConfigSwitch's HeardPrepared), and a restart of
            # it is held to it (`received`).
            selected.append((line, "HeardPrepared", node, set(VARS)))
            continue
        if action == "Restored":
            # A restarted node's view as read back from its disk: not older than a switch
            # of its that another node received (TraceConfigSwitch's `received`). Its
            # variables are the restored ones, not the spec's (a view the node logged but
            # had not saved when it went down is lost under a correct driver too).
            selected.append((line, "Restored", node, set(VARS)))
            continue
        # Between a Master's BroadcastCommand line and the delivery of that command to
        # itself (its own ReceiveCommand line; the spec's StartSwitch applied it at the
        # Exclude, RequestPhase or take-over line) the Master may log lines of the
        # switch it leaves: a final checkpoint resent in the same step (keel-sim
        # --disk-faults storage-power-loss, seed 2: the Storage node lost power before
        # acknowledging it). Their switch position is not compared.
        # So may a Master that supersedes its own command before it delivers it (keel-sim
        # earth_observation_all_online.yaml --max-failures 3, seed 69: PN3 takes over into
        # SAFE at seq 1, excludes IF1 at seq 2, then delivers seq 1 to itself and
        # deactivates under it while the spec holds seq 2): until its latest own command
        # is delivered, its Deactivate lines' position is not compared either. (Its
        # ReceiveCommand and Ack of the superseded switch are the spec's: Superseded.)
        if action == "ReceiveCommand" and str(args.get("from")) == node:
            if commanding.get(node) == (args.get("epoch"), args.get("seq")):
                del commanding[node]
        elif node in commanding and action in ("FlushCheckpoint", "Deactivate"):
            position = {"epoch", "seq", "config", "stage"}
            if action == "Deactivate":
                selected.append((line, "Deactivate", node, {"unflushed"} | position))
            elif args.get("final"):
                selected.append((line, "FlushFinal", node, {"unflushed"} | position))
            else:
                selected.append((line, "Steps", node, position))
            continue
        if action == "BroadcastCommand":
            commanding[node] = (args.get("epoch"), args.get("seq"))
        if action in LEASE or action in GROUND_VOTE:
            lease += 1
            # A lease line may come between a take-over and the new Master's delivery of
            # its own command (the spec applies it at once): its switch position is not
            # compared, only what it holds (active, unflushed, versions).
            selected.append((line, "Lease", node, {"epoch", "seq", "config", "stage"}))
            continue
        if action == "BecomeMaster":
            selected.append((line, "TakeOver", node, set()))
        elif action == "RefuseGroundCommand":
            selected.append((line, "RefuseGround", node, set()))
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
        elif action in ("BootSwitch", "Exclude", "RequestPhase", "ReceiveCommand", "Readmit",
                        "HandOver", "GroundRecovery", "AskHolders", "StateOutOfReach", "Resign",
                        "Resigned", "AskExclusion", "GroundExclude", "GroundReadmit", "GroundPause",
                        "GroundResume", "Backed",
                        "Refused",
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
        notes.append(f"{lease} lease line(s) (Hold, Release, LeaseLapsed; the ground's "
                     "GroundDesignate, StandDown, StandUp) validated as steps "
                     "that change no ConfigSwitch variable, a node that holds taking no step "
                     "until its Release (spec/Lease.tla states the lease)")
    while selected and selected[-1][1] in ("Crash", "Restart"):
        selected.pop()
    selected, online = _map_online(selected, mission)
    if online.refused:
        notes.append("online configurations not admitted (the checker refuses them, or their "
                      "phase places none: no configuration the spec knows, so the lines naming "
                      "them are no behaviour): " +
                      "; ".join(f"{k} ({why})" for k, why in online.refused.items()))
    phase_names = {name: cfg.phase for name, cfg in configs.items()}
    phase_names.update({name: cfg.phase for name, cfg in online.configs.items()})
    selected = _map_safe(selected, phase_names)
    selected, top, base, lineages = _map_lineages(selected)
    if top > TLC_INT_MAX:
        notes.append(f"versions of {top} after ordering lineages: beyond TLC's integers")
        return [_empty(notes)]
    if lineages > 1:
        notes.append(f"{lineages} lineages of task states: a version below reads "
                     f"lineage rank * {base} + count")
    count = max(len(selected), 1)
    checkpointed = [t for t, task in mission.tasks.items() if task.checkpoint]
    every = dict(configs)
    every.update(online.configs)
    placements = {name: {t: cfg.placement.get(t, UNPLACED) for t in tasks}
                  for name, cfg in every.items()}
    masters = {name: cfg.master for name, cfg in every.items()}
    observers = {name: list(cfg.observers) for name, cfg in every.items()}
    monitors = {name: sorted({cfg.master, *cfg.observers}) for name, cfg in every.items()}
    phase_of = {name: cfg.phase for name, cfg in every.items()}
    for phase_name, phase in mission.phases.items():
        essential = [t for t in phase.tasks if mission.tasks[t].essential]
        for master in facts.priority:
            safe = SAFE_ID.format(phase_name, master)
            placements[safe] = {t: master if t in essential else UNPLACED for t in tasks}
            masters[safe] = master
            observers[safe] = []
            # The runtime's SAFE view counts the monitors of the configuration it was
            # entered from (Topology::monitors): one of this phase's.
            monitors[safe] = sorted({master}.union(*(
                monitors[name] for name in [*phase.configurations,
                                            *(k for k, c in online.configs.items() if c.phase == phase_name)])))
            phase_of[safe] = phase_name
    place = "[c \\in TConfigIds |-> " + "CASE " + "\n    [] ".join(
        f"c = {tla.string(name)} -> {tla.literal(placement)}"
        for name, placement in placements.items()) + "]"
    on_failure = []
    on_phase: dict[str, set[str]] = {name: set() for name in placements}
    for phase_name, phase in mission.phases.items():
        for config, cfg in phase.configurations.items():
            for failed in nodes:
                target = _on_failure(config, failed, phase, mission, storage)
                if target == SAFE:
                    target = SAFE_ID.format(phase_name, cfg.master)
                elif target != config and masters[target] != cfg.master:
                    # The runtime follows no edge to a configuration another node is the
                    # master of: it goes to safe mode (ReconfigurationManager::exclude).
                    target = SAFE_ID.format(phase_name, cfg.master)
                if target != config:
                    on_failure.append(f"<<{tla.string(config)}, {tla.string(failed)}>> :> "
                                      f"{tla.string(target)}")
        for _target_phase, mapping in phase.on_phase.items():
            for source, target in mapping.items():
                on_phase.setdefault(source, set()).add(target)
    # The switches to online configurations (and to safe mode from one) the lines make,
    # where the phase's placement lets the placer answer.
    graph_failure = {}
    for entry in on_failure:
        key, _, target = entry.partition(" :> ")
        graph_failure[key] = target
    excluded = _online_targets(selected, mission, online, "Exclude")
    # Safe mode from an online configuration, where the placer places: an Exclude's
    # (source, failed node) keeps the graph's target in the failure map, a take-over line
    # is marked (`placerPlaces`, which TraceConfigSwitch's take-over refuses).
    unplaced = _safe_where_the_placer_places(
        [((source, failed), source, str(line.args.get("m", line.node)), line)
         for source, failed, target, line in excluded
         if source in online.configs and target.startswith("SAFE/")]
        + [((line.file, line.number), source, master, line)
           for source, master, line in _take_overs_into_safe(selected, online)], mission, online)
    if unplaced:
        notes.append("safe mode entered from an online configuration where the placer places "
                     "the essential tasks, with the line's Master (core/fsm/online.hpp, "
                     "failure_target; no switch the spec knows, so the lines are no behaviour): " +
                     "; ".join(f"line {n}: {why}" for n, why in unplaced.values()))
    for (source, failed, target, _line) in excluded:
        if (source, failed) in unplaced:
            continue
        key = f"<<{tla.string(source)}, {tla.string(failed)}>>"
        safe_there = graph_failure.get(key, tla.string(source)).startswith('"SAFE/')
        if _gives_way(mission, phase_of.get(source), source in online.configs, safe_there):
            graph_failure[key] = tla.string(target)
    on_failure = [f"{k} :> {v}" for k, v in graph_failure.items()]
    for (source, _phase, target, _line) in _online_targets(selected, mission, online, "RequestPhase"):
        if target in online.configs or source in online.configs:
            on_phase.setdefault(source, set()).add(target)
    failure_map = "(" + " @@ ".join(on_failure) + ")" if on_failure else "<<>>"
    recovery_map = _recovery_map(selected, mission, storage, phase_of, placements, online, masters)
    priority = "<<" + ", ".join(tla.string(n) for n in facts.priority) + ">>"
    first_phase = next(iter(mission.phases.values()))
    late = [x for x in _late_nodes(selected, nodes) if x != facts.priority[0]]
    expired = _expired_reports(lines)
    vote_held = _vote_held(lines, facts)
    # Each node's restarts, and whether each read back a state that went back on purpose.
    restarts: dict[str, list[tuple[int, bool]]] = {}
    for ln in lines:
        if ln.fsm == "env" and ln.action == "Restart" and isinstance(ln.args.get("n"), str):
            restarts.setdefault(ln.args["n"], []).append(
                (ln.t_ns, ln.args.get("rolled_back") is True))

    def rolled_back(ln: Line) -> bool:
        before = [back for t, back in restarts.get(str(ln.node), []) if t <= ln.t_ns]
        return bool(before) and before[-1]

    job = Job(
        protocol="switch",
        subject="cluster",
        template="TraceConfigSwitch",
        lines=[ln for ln, *_ in selected],
        records=[_record(ln, action, node, dropped, expired.get((ln.file, ln.number)),
                         action == "Restored" and rolled_back(ln),
                         vote_held.get((ln.file, ln.number), False),
                         (ln.file, ln.number) in unplaced)
                 for ln, action, node, dropped in selected],
        definitions={
            "TNodes": tla.literal(nodes),
            "TPriority": priority,
            "TTasks": tla.literal(tasks),
            "TCheckpointed": tla.literal(checkpointed),
            "TConfigIds": tla.literal(list(placements)),
            "TSafeIds": tla.literal([c for c in placements if c not in configs]),
            "TPhaseMap": tla.literal(phase_of),
            "TPhaseOf(c)": "TPhaseMap[c]",
            "TObserversMap": tla.literal(observers),
            "TObservers(c)": "TObserversMap[c]",
            "TTieGrace": str(facts.tie_grace),
            "TMonitorsMap": tla.literal(monitors),
            "TMonitors(c)": "TMonitorsMap[c]",
            "TPlace": place,
            "TPlacement(c, t)": "TPlace[c][t]",
            "TFailureMap": failure_map,
            "TOnFailure(c, f)": "IF <<c, f>> \\in DOMAIN TFailureMap THEN TFailureMap[<<c, f>>] "
                                "ELSE c",
            "TOnPhaseMap": tla.literal({k: sorted(v) for k, v in on_phase.items()}),
            "TOnPhase(c)": "TOnPhaseMap[c]",
            "TLate": tla.literal(late),
            "TRecoveryMap": recovery_map,
            "TRecovery(c, r, F)": "IF <<c, r, F>> \\in DOMAIN TRecoveryMap "
                                  "THEN TRecoveryMap[<<c, r, F>>] ELSE \"none\"",
            "TMasterMap": tla.literal(masters),
            "TMasterOf(c)": "TMasterMap[c]",
        },
        constants=[
            "Nodes <- TNodes", "Priority <- TPriority", f"Storage = {tla.string(storage)}",
            "Tasks <- TTasks", "Checkpointed <- TCheckpointed", "ConfigIds <- TConfigIds",
            "MasterOf <- TMasterOf", "SafeIds <- TSafeIds", "PhaseOf <- TPhaseOf",
            "ObserversOf <- TObservers", "MonitorsOf <- TMonitors",
            "RecoveryOf <- TRecovery",
            f"InitialConfig = {tla.string(first_phase.initial)}", "Placement <- TPlacement",
            "OnFailure <- TOnFailure", "OnPhase <- TOnPhase",
            f"MaxCrashes = {len(facts.priority) - 1}", f"MaxPhaseChanges = {count}",
            f"MaxVersion = {max(10 ** 9, top)}", f"MaxLateBoots = {len(nodes) - 1}",
            f"MaxHidden = {len(nodes) * len(tasks) + len(nodes) + 2}",
            f"LineageBase = {base}",
        ],
        spec_values=lambda line, state: _spec_values(line, state, storage, checkpointed),
        compared=lambda line: _compared(line, checkpointed),
        skipped=skipped,
        notes=notes,
        explain=lambda line: _explain(line, selected) + _explain_expired(line, expired),
    )
    return [job] if selected else []


def _matters(config: str, node: str, mission: object, storage: str | None) -> bool:
    """The runtime's `matters`: the configuration's master, observers and task hosts, and
    the Storage node when it places a checkpointed task (keel-verify check's rule)."""
    cfg = next(p.configurations[config] for p in mission.phases.values()
               if config in p.configurations)
    if node == cfg.master or node in cfg.observers or node in cfg.placement.values():
        return True
    return node == storage and any(mission.tasks[t].checkpoint for t in cfg.placement)


def _on_failure(config: str, failed: str, phase: object, mission: object,
                storage: str | None) -> str:
    """The runtime's walk for one failure (Topology::walk): the edge, SAFE when the node
    matters and there is none, else the same configuration."""
    edge = phase.on_failure.get(config, {}).get(failed)
    if edge is not None:
        return edge
    return SAFE if _matters(config, failed, mission, storage) else config


def _recovery(source: str, node: str, rest: set[str], mission: Any, storage: str | None,
              phase_of: dict[str, str]) -> str:
    """Where readmitting ``node`` in ``source`` with ``rest`` still failed leads
    (Topology::recovery_target): the mission's on_recovery edge from a real configuration,
    else the walk of ``rest`` (in node order, each pass the first with an edge or that
    matters) from the phase's initial configuration; SAFE when the walk ends there or in a
    configuration that uses a failed node."""
    phase = mission.phases[phase_of[source]]
    edge = phase.on_recovery.get(source, {}).get(node)
    if edge is not None:
        return str(edge)
    config = phase.initial
    pending = [n for n in mission.nodes if n in rest]
    for _ in range(len(pending) + 1):
        hit = next((n for n in pending if _matters(config, n, mission, storage)
                    or n in phase.on_failure.get(config, {})), None)
        if hit is None:
            break
        pending.remove(hit)
        nxt = phase.on_failure.get(config, {}).get(hit)
        if nxt is None or nxt == SAFE:
            return SAFE
        config = nxt
    cfg = phase.configurations[config]
    if cfg.master in rest or any(h in rest for h in cfg.placement.values()):
        return SAFE
    return config


def _recovery_map(selected: list[tuple[Line, str, str, set[str]]], mission: Any,
                  storage: str | None, phase_of: dict[str, str],
                  placements: dict[str, object], online: Online | None = None,
                  masters: dict[str, str] | None = None) -> str:
    """TRecoveryMap: for each readmission the trace logs (its node and the failed set it
    leaves, from its Readmit or HandOver line's `failed`), where readmitting it leads from every
    configuration (safe ids too) of its phase: the spec checks the Master's own."""
    entries: dict[tuple[str, str, tuple[str, ...]], str] = {}
    for line, action, _node, _dropped in selected:
        if action not in ("Readmit", "HandOver"):
            continue
        node = str(line.args.get("r"))
        target = str(line.args.get("c"))
        # A Readmit line logs the view after it, a HandOver line the one before.
        rest = tuple(sorted(str(n) for n in line.vars.get("failed", []) if str(n) != node))
        if target not in phase_of:
            continue
        for source in placements:
            if phase_of[source] == phase_of[target]:
                graph = _recovery(source, node, set(rest), mission, storage, phase_of)
                # graph+online: the graph's configuration where it is not SAFE and its
                # master is the source's or the readmitted node's (online.hpp).
                kept = graph != SAFE and masters is not None and masters.get(graph) in (
                    masters.get(source), node)
                if online is not None and target in online.configs and _gives_way(
                        mission, phase_of[source], source in online.configs, not kept):
                    graph = target
                entries[(source, node, rest)] = graph
    if not entries:
        return "<<>>"
    return "(" + " @@ ".join(
        f"<<{tla.string(s)}, {tla.string(n)}, {tla.literal(list(r))}>> :> {tla.string(t)}"
        for (s, n, r), t in entries.items()) + ")"


@dataclass
class Online:
    """The online configurations a trace names: per pseudo-configuration its
    Configuration; and those the checker refused, with why."""
    configs: dict[str, Configuration] = field(default_factory=dict)
    refused: dict[str, str] = field(default_factory=dict)


def _placement_mode(mission: Any, phase: str | None) -> str:
    """A phase's `placement` (docs/missions.md, "Placement modes"): graph, online or
    graph+online."""
    if phase is None or phase not in mission.phases:
        return "graph"
    return str(getattr(mission.phases[phase], "placement", "graph") or "graph")


def _gives_way(mission: Any, phase: str | None, from_online: bool, graph_safe: bool) -> bool:
    """Whether the Master's answer in `phase` is the placer's rather than the graph's
    (core/fsm/online.hpp): always in an online phase; in a graph+online one from an online
    configuration, or where the graph's answer is safe mode."""
    mode = _placement_mode(mission, phase)
    if mode == "online":
        return True
    return mode == "graph+online" and (from_online or graph_safe)


def _accepts(mission: Any, name: str, config: Configuration, failed: set[str]) -> str | None:
    """Why the checker refuses `config` under `failed` (shedding allowed), or None."""
    graph = DecisionGraph(mission)
    graph.configs[name] = config
    graph.phase_of[name] = config.phase
    essential = {t for t, task in mission.tasks.items() if task.essential}
    of_phase = set(mission.phases[config.phase].tasks)
    findings = [f for f in graph.invalid_under(name, frozenset(failed))
                if not (f.kind == "task-missing" and f.task in of_phase - essential
                        and f.task not in config.placement)]
    if not findings:
        return None
    return f"{findings[0].kind}: {findings[0].message}"


def _online_config(name: str, value: object, mission: Any) -> Configuration | str:
    """The Configuration a line's `online` object describes, or why it describes none."""
    if not isinstance(value, dict):
        return "no online object"
    phase, master = value.get("phase"), value.get("m")
    observers, host = value.get("obs", []), value.get("host", {})
    if phase not in mission.phases or not isinstance(master, str):
        return f"phase {phase!r} or master {master!r} is not the mission's"
    if not isinstance(observers, list) or not isinstance(host, dict):
        return "malformed observers or hosts"
    if any(n not in mission.nodes for n in [master, *observers, *host.values()]) or any(
            t not in mission.tasks for t in host):
        return "a node or task the mission does not have"
    return Configuration(name=name, phase=str(phase), master=master,
                         observers=tuple(str(o) for o in observers),
                         placement={str(t): str(n) for t, n in host.items()})


def _map_online(selected: list[tuple[Line, str, str, set[str]]], mission: Any
                ) -> tuple[list[tuple[Line, str, str, set[str]]], Online]:
    """Replaces "online" in the lines (args c; vars config, masterConfig) by the
    pseudo-configuration of its switch, ONLINE_ID.format(epoch, seq): the Master's lines
    name the switch they start (their vars' <<epoch, masterSeq>>; a HandOver line its
    <<epoch, 0>>), a BroadcastCommand or ReceiveCommand line its <<epoch, seq>>, every
    node's line in it its vars' <<epoch, seq>>; a Master's masterConfig is the last one it
    started. Each is registered with the configuration its first line carries, if the
    checker accepts it under that switch's failed set."""
    found = Online()
    by_switch: dict[tuple[object, object], str] = {}
    driving: dict[str, str] = {}

    def register(key: tuple[object, object], value: object, failed: set[str]) -> str:
        name = by_switch.get(key)
        if name is not None:
            return name
        name = by_switch[key] = ONLINE_ID.format(*key)
        config = _online_config(name, value, mission)
        if isinstance(config, str):
            found.refused[name] = config
            return name
        why = _accepts(mission, name, config, failed)
        if _placement_mode(mission, config.phase) == "graph":
            why = f"phase {config.phase} is placed by its graph alone"
        if why is None:
            found.configs[name] = config
        else:
            found.refused[name] = why
        return name

    out = []
    for line, action, node, dropped in selected:
        args, state = dict(line.args), dict(line.vars)
        actor = str(line.node) if line.node is not None else node
        if args.get("c") == ONLINE:
            failed = {str(x) for x in (args.get("out") if action == "ReceiveCommand"
                                       else state.get("failed", [])) or []}
            if action == "HandOver":
                key = (args.get("epoch"), 0)
                failed.discard(str(args.get("r")))
            elif action in MANAGER or action == "TakeOver":
                key = (state.get("epoch"), state.get("masterSeq"))
            elif "epoch" in args:
                key = (args.get("epoch"), args.get("seq"))
            else:
                key = (None, None)  # a line of the switch the Master drives (CompleteSwitch)
            if key == (None, None):
                args["c"] = driving.get(actor, ONLINE)
            else:
                args["c"] = register(key, args.get("online"), failed)
            if action in MANAGER or action == "TakeOver":
                driving[actor] = args["c"]
        if state.get("masterConfig") == ONLINE:
            state["masterConfig"] = driving.get(actor) or by_switch.get(
                (state.get("epoch"), state.get("masterSeq")), ONLINE)
        if state.get("config") == ONLINE:
            state["config"] = by_switch.get((state.get("epoch"), state.get("seq")), ONLINE)
        out.append((Line(line.file, line.number, line.t_ns, line.node, line.fsm, line.action,
                         args, state), action, node, dropped))
    return out, found


def _online_targets(selected: list[tuple[Line, str, str, set[str]]], mission: Any,
                    online: Online, action: str) -> list[tuple[str, str, str, Line]]:
    """(source, failed node or phase, target, the line) of each `action` line (Exclude or
    RequestPhase) whose target is an online configuration the checker accepted, or safe
    mode from one: the Master's masterConfig before the line is the source."""
    before: dict[str, str] = {}
    found = []
    for line, act, node, _dropped in selected:
        actor = str(line.node) if line.node is not None else node
        target = str(line.args.get("c"))
        if act == action and actor in before:
            source = before[actor]
            if target in online.configs or (source in online.configs and target.startswith("SAFE/")):
                what = str(line.args.get("f")) if action == "Exclude" else str(line.args.get("phase"))
                found.append((source, what, target, line))
        master_config = line.vars.get("masterConfig")
        if isinstance(master_config, str) and master_config != "none":
            before[actor] = master_config
    return found


def _take_overs_into_safe(selected: list[tuple[Line, str, str, set[str]]],
                          online: Online) -> list[tuple[str, str, Line]]:
    """(source, the new Master, the line) of each take-over (BecomeMaster) line into safe
    mode whose node ran an online configuration the checker accepted: its `config` before
    the line is the source (ReconfigurationManager::take_over answers from the node's own
    view)."""
    config: dict[str, str] = {}
    found = []
    for line, act, node, _dropped in selected:
        actor = str(line.node) if line.node is not None else node
        if (act == "TakeOver" and str(line.args.get("c")).startswith("SAFE/")
                and config.get(actor) in online.configs and line.args.get("warm") is not True):
            found.append((config[actor], actor, line))
        if isinstance(line.vars.get("config"), str):
            config[actor] = line.vars["config"]
    return found


def _safe_where_the_placer_places(entered: list[tuple[object, str, str, Line]], mission: Any,
                                  online: Online) -> dict[object, tuple[int, str]]:
    """Of the lines `entered`, each (key, source, Master, line) that takes safe mode from
    the online configuration `source` the checker accepted (an Exclude, or a take-over by
    the Master named), those where the runtime's placer (keel-place --batch, the nodes'
    own) places the essential tasks under the line's failed set, that node Master: key ->
    (the line's number, why). Such a failure is answered with the placer's configuration
    (core/fsm/online.hpp, failure_target), and receivers refuse a Master's safe mode there.
    A line that cannot be asked about is not admitted either."""
    from keel_verify.check.online import ProverFailed, ProverUnavailable, placer_answers

    asked: list[tuple[object, int, dict[str, Any], str]] = []
    for key, source, master, line in entered:
        cfg = online.configs[source]
        failed = sorted({str(x) for x in line.vars.get("failed", []) or []})
        query = {"op": "place", "phase": cfg.phase, "failed": failed,
                 "from": {"master": cfg.master, "observers": list(cfg.observers),
                          "tasks": [[t, n] for t, n in cfg.placement.items()]}}
        asked.append((key, line.number, query, master))
    if not asked:
        return {}
    found = {}
    try:
        answers = placer_answers(mission, [q for _, _, q, _ in asked])
    except (ProverUnavailable, ProverFailed) as error:  # unchecked is not admitted
        return {key: (number, f"not checked: {error}") for key, number, _, _ in asked}
    for (key, number, query, master), answer in zip(asked, answers):
        placed = answer.get("config") or {}
        if not answer.get("safe") and placed.get("master") == master:
            found[key] = (number, f"failed {', '.join(query['failed'])} in {query['phase']}: "
                                  f"the placer places every essential task with {master} Master")
    return found


# The lines of the Master's decisions (ReconfigurationManager): their vars are the view it
# drives (masterConfig, masterSeq, epoch, failed).
MANAGER = ("Exclude", "TakeOver", "BootSwitch", "Readmit", "HandOver", "GroundRecovery",
           "RequestPhase")


def _map_safe(selected: list[tuple[Line, str, str, set[str]]],
              configs: dict[str, str]) -> list[tuple[Line, str, str, set[str]]]:
    """Replaces "SAFE" in the lines (args c; vars config, masterConfig) by its
    pseudo-configuration: the Master that drives it, the phase it was entered from. A
    switch is known by <<epoch, seq>>: the Master's lines name it (its Exclude /
    BecomeMaster lines log the driven view, its BroadcastCommand the command), every
    node's line that is in it maps through it."""
    last_real: dict[str, str] = {}  # node -> the last real configuration it was in or drove
    driving: dict[str, str] = {}  # Master -> the safe id it drives
    by_switch: dict[tuple[object, object], str] = {}
    out = []
    for line, action, node, dropped in selected:
        args, state = dict(line.args), dict(line.vars)
        actor = str(line.node) if line.node is not None else node

        def safe_for(master: str) -> str:
            real = last_real.get(master) or next(iter(configs))
            return SAFE_ID.format(configs[real], master)

        if state.get("masterConfig") == SAFE:
            if action == "TakeOver" or actor not in driving:
                driving[actor] = safe_for(actor)  # entering SAFE, or taking it over
            if action in MANAGER and "epoch" in state and "masterSeq" in state:
                # The Master's own lines log the view it drives: <<epoch, masterSeq>>.
                by_switch[(state["epoch"], state["masterSeq"])] = driving[actor]
            state["masterConfig"] = driving[actor]
        if action == "BroadcastCommand" and args.get("c") == SAFE:
            by_switch.setdefault((args.get("epoch"), args.get("seq")),
                                 driving.get(actor) or safe_for(actor))
        if args.get("c") == SAFE:
            key = (args.get("epoch"), args.get("seq"))
            if action in ("Exclude", "TakeOver"):
                args["c"] = driving.get(actor) or safe_for(actor)
            else:
                args["c"] = by_switch.get(key) or driving.get(actor) or safe_for(actor)
        if state.get("config") == SAFE:
            state["config"] = by_switch.get((state.get("epoch"), state.get("seq"))) \
                or safe_for(actor)
        for value in (state.get("config"), state.get("masterConfig")):
            if isinstance(value, str) and value in configs:
                last_real[actor] = value
        if isinstance(state.get("masterConfig"), str) and state["masterConfig"] in configs:
            driving.pop(actor, None)
        mapped = Line(line.file, line.number, line.t_ns, line.node, line.fsm, line.action,
                      args, state)
        out.append((mapped, action, node, dropped))
    return out


TLC_INT_MAX = 2**31 - 1


def _lineage(value: object) -> tuple[int, int]:
    if isinstance(value, list) and len(value) == 2 and all(isinstance(x, int) for x in value):
        return (value[0], value[1])
    return (0, 0)


def _map_lineages(selected: list[tuple[Line, str, str, set[str]]]
                  ) -> tuple[list[tuple[Line, str, str, set[str]]], int, int, int]:
    """A task state's version is its lineage (<<epoch, seq>> of the view that opened it;
    [0, 0] when the line logs none) then its count (core/fsm/types.hpp, Version;
    spec/Handoff.tla, "Lineages"). ConfigSwitch's versions are numbers: each logged version
    becomes rank(lineage) * base + count, the lineages ranked in their order over the
    whole trace and base above every count, which orders the numbers exactly as the
    versions. Mapped: args version (with args lineage), args opened (a lineage an
    Activate line opens, with the line's count), vars version (with vars lineage). Returns
    the lines, the largest number, the base and the number of lineages."""
    lineages: set[tuple[int, int]] = {(0, 0)}
    counts = [0]
    for line, *_ in selected:
        args, state = line.args, line.vars
        lineages.add(_lineage(args.get("lineage")))
        if "opened" in args:
            lineages.add(_lineage(args.get("opened")))
        if isinstance(args.get("version"), int):
            counts.append(args["version"])
        for value in (state.get("lineage") or {}).values():
            lineages.add(_lineage(value))
        for value in (state.get("version") or {}).values():
            if isinstance(value, int):
                counts.append(value)
    base = max(counts) + 1
    rank = {lin: i for i, lin in enumerate(sorted(lineages))}
    top = (len(rank) - 1) * base + base - 1
    if len(rank) == 1:
        return selected, top, base, 1
    out = []
    for line, action, node, dropped in selected:
        args, state = dict(line.args), dict(line.vars)
        if isinstance(args.get("version"), int):
            count = args["version"]
            args["version"] = rank[_lineage(args.pop("lineage", None))] * base + count
            if "opened" in args:
                args["opened"] = rank[_lineage(args["opened"])] * base + count
        if isinstance(state.get("version"), dict):
            lineage_of = state.pop("lineage", None) or {}
            state["version"] = {
                t: rank[_lineage(lineage_of.get(t))] * base + v if isinstance(v, int) else v
                for t, v in state["version"].items()}
        out.append((Line(line.file, line.number, line.t_ns, line.node, line.fsm, line.action,
                         args, state), action, node, dropped))
    return out, top, base, len(rank)


def _late_nodes(selected: list[tuple[Line, str, str, set[str]]],
                nodes: list[str]) -> list[str]:
    """The nodes a Master declared failed (or a take-over found failed) before their first
    line: their processes started after that, so the spec's Init leaves them unbooted."""
    seen: set[str] = set()
    late: list[str] = []
    for line, action, node, _dropped in selected:
        declared: list[str] = []
        if action == "Exclude":
            declared = [str(line.args.get("f"))]
        elif action == "TakeOver":
            declared = [str(n) for n in line.vars.get("failed", []) or []]
        for x in declared:
            if x in nodes and x not in seen and x not in late:
                late.append(x)
        if action not in ("Crash", "Restart", "Store", "Recovered", "Report"):
            seen.add(node)
    return late


def needed(members: int, voters: int) -> int:
    """spec/QuorumRule.tla's Needed: a majority of the members, at most the voters, at
    least one."""
    return max(1, min(members // 2 + 1, voters))


def _explain(line: Line, selected: list[tuple[Line, str, str, set[str]]]) -> list[str]:
    """The exclusion-evidence rule a Master's Exclude line breaks, if its logged
    evidence shows it (TraceConfigSwitch's EvidenceSuffices)."""
    if line.fsm == "switch" and line.action == "BecomeMaster":
        return _explain_take_over(line)
    if (line.fsm != "switch" or line.action != "Exclude" or line.args.get("own")
            or line.args.get("ground")):
        return []
    if "mem" not in line.args or "ev" not in line.args:
        return ["the line logs no evidence (own, mem, ev): a runtime older than this "
                "validator"]
    failed = str(line.args.get("f"))
    members = {str(x) for x in line.args.get("mem") or []}
    declared = {str(x) for x in line.args.get("ev") or []}
    out = []
    count = needed(len(members), len(members - {failed}))
    if len(declared) < count:
        out.append(f"evidence: {len(declared)} declaration(s) ({', '.join(sorted(declared))}) "
                   f"of {len(members)} member(s); excluding {failed} needs {count} "
                   "(spec/Quorum.tla, rule 1)")
    if declared - (members - {failed}):
        out.append(f"evidence: {', '.join(sorted(declared - (members - {failed})))} "
                   f"counted but no member other than {failed}")
    reported = {str(before.node) for before, action, *_ in selected
                if action == "Report" and before.args.get("n") == failed
                and before.t_ns <= line.t_ns}
    if declared - reported:
        out.append(f"evidence: {', '.join(sorted(declared - reported))} counted but never "
                   f"declared {failed} (no heartbeat DeclareFailed line before)")
    master = str(line.node)
    if master in declared:
        # The Master's own declaration counts only while its monitor holds it.
        last = None
        for before, action, node, _dropped in selected:
            if before is line:
                break
            if node == master and action in ("Report", "Withdraw") and before.args.get("n") == failed:
                last = action
        if last == "Withdraw":
            out.append(f"evidence: {master} counted its own declaration of {failed}, which it had "
                       "withdrawn (its heartbeat Withdraw line)")
    return out


def _explain_expired(line: Line, expired: dict[tuple[str, int], dict[str, list[str]]]) -> list[str]:
    """The reporters an Exclude or a take-over counted whose declaration had ended too long
    before to count (_expired_reports)."""
    return [f"evidence: {', '.join(reporters)} counted as declaring {node}, whose declaration "
            f"had ended {EXPIRED_PERIODS} or more of {line.node}'s periods before (a report "
            "counts for two periods)"
            for node, reporters in sorted(expired.get((line.file, line.number), {}).items())]


def _explain_take_over(line: Line) -> list[str]:
    """The nodes a BecomeMaster line excludes on too few declarations (TakeOverEvidence;
    a node without an entry may have given its own word, which the line does not show)."""
    members = {str(x) for x in line.args.get("mem") or []}
    declared = line.args.get("ev") or {}
    was = {str(x) for x in line.args.get("was") or []}
    out = []
    for node in sorted({str(x) for x in line.vars.get("failed") or []} - was):
        by = {str(x) for x in declared.get(node, [])} if isinstance(declared, dict) else set()
        count = needed(len(members), len(members - {node}))
        if len(by) < count:
            out.append(f"evidence: {len(by)} declaration(s) of {node} among {len(members)} "
                       f"member(s); a take-over that excludes it needs {count} unless {node} "
                       "gave its own word (spec/Quorum.tla, rule 1)")
    return out


def _compared(line: Line, checkpointed: list[str]) -> dict[str, object]:
    if line.fsm != "switch":
        return {}  # a Report line: its variables are the heartbeat monitor's
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
    if line.fsm != "switch":
        return {}  # a Report line: its variables are the heartbeat monitor's
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
