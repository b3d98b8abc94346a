-------------------------------- MODULE Resign --------------------------------
(***************************************************************************)
(* A Master that resigns: what it does with its tasks and with what it has *)
(* not flushed, and that it runs nothing after (core/fsm/node_protocol.cpp  *)
(* NodeProtocol::resign and advance_resign; ConfigSwitch::resign and       *)
(* abandon_flushes).                                                       *)
(*                                                                         *)
(* Lease.tla and LeaseStepDown.tla say when a Master resigns (its lease    *)
(* lapsed, it is cut off or stalled; also a task that keeps failing on it, *)
(* the ground's exclude of it, a disk that failed) and that its word lets  *)
(* its successor take over without further evidence. They leave out its    *)
(* tasks. This spec adds them, on ConfigSwitch.tla, as the runtime does:   *)
(*  - Resign (the Master's `Resign` line). The acting Master, having       *)
(*    started its boot switch (a Master still waiting to boot one is no    *)
(*    acting Master: it asks to be excluded instead, AskExclusion.tla),    *)
(*    steps down at once: it drives no switch any more (its                *)
(*    ReconfigurationManager steps down: the driver's stage is Idle and no *)
(*    driver step is taken), its own switch position is Stable, and it     *)
(*    deactivates every task it runs; the final checkpoint of each is      *)
(*    pending (`unflushed`) and retransmitted every period                 *)
(*    (ConfigSwitch::tick) until the Storage node acknowledges it          *)
(*    (ConfigSwitch's FlushCheckpoint, which a resigned Master still       *)
(*    takes). It adopts no Command (a resigned Master adopts only one that *)
(*    excludes it, NodeProtocol::handle_command, after which it runs       *)
(*    nothing: see Resigned), acks nothing and activates nothing. Its      *)
(*    heartbeats still flow, so no Observer takes over yet.                *)
(*  - Resigned (its `Resigned` line, advance_resign). Once every final     *)
(*    checkpoint is acknowledged ("flushed"), or once its deadline of      *)
(*    miss_limit periods has passed ("abandoned": the acknowledgements may *)
(*    all be lost, so the deadline may come at any time here), it is done: *)
(*    what is still unflushed is dropped (abandon_flushes: lost, as in a   *)
(*    crash), and its heartbeats say `excluded`, on which every monitor    *)
(*    declares it at once and the first Observer takes over without        *)
(*    further evidence. From then on it takes no part until it restarts:   *)
(*    for ConfigSwitch it is a crashed node (the take-over and the         *)
(*    exclusion that follow are ConfigSwitch's BecomeMaster and Exclude),  *)
(*    as TraceConfigSwitch maps it (`ResignedLine`, then `Fence`).        *)
(* A resignation is a failure announced in advance: it takes one of the    *)
(* failures the decision graph tolerates (`crashes`, at the Resign step).  *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - ResignedRunsNothingInv: from its Resign on, a Master runs no task    *)
(*    and drives no switch.                                                *)
(*  - ResignedLeftCleanInv: a Master that says it left (done) claims       *)
(*    nothing unflushed any more: every final checkpoint was stored at the *)
(*    version it ran, or abandoned.                                        *)
(*  - ConfigSwitch's NoDoubleActivationInv and ResumeLatestCheckpointInv,  *)
(*    with resignations: the successor's switch never runs a task beside  *)
(*    the resigned Master, nor below what it flushed.                      *)
(* Mutants (mutants/ResignKeepsTasks.tla, ResignedKeepsUnflushed.tla,      *)
(* ResignStillDrives.tla) break them; witnesses (MCResign.tla) reach a     *)
(* resignation whose tasks were all flushed before the successor took      *)
(* over, and one that abandoned a version no one else holds.               *)
(*                                                                         *)
(* Abstraction: ConfigSwitch's flush is the write, the store and the       *)
(* acknowledgement in one step, so an abandoned write is never stored      *)
(* later here. In the runtime one still on its way may be; the Storage     *)
(* node refuses writes of a node its view excludes                         *)
(* (CheckpointStore::receive_write), and it adopts the successor's view,   *)
(* which excludes the resigned Master, before any member activates one of  *)
(* its tasks (the Storage node acks Prepared first).                       *)
(***************************************************************************)
EXTENDS ConfigSwitch

VARIABLES
    resign,  \* [Nodes -> {"none", "flushing", "done"}]: NodeProtocol::Resign (asked is
             \* a non-Master's, AskExclusion.tla)
    how,     \* history: [Nodes -> {"", "flushed", "abandoned"}], how each resignation ended
    gave,    \* history: [Nodes -> SUBSET Tasks], the tasks each Master stopped at its Resign
    lost     \* history: [Nodes -> BOOLEAN], an abandoned final checkpoint was of a
             \* version the Storage node did not hold

resignVars == <<resign, how, gave, lost>>
allVars == <<vars, resignVars>>

RTypeOK ==
    /\ TypeOK
    /\ resign \in [Nodes -> {"none", "flushing", "done"}]
    /\ how \in [Nodes -> {"", "flushed", "abandoned"}]
    /\ gave \in [Nodes -> SUBSET Tasks]
    /\ lost \in [Nodes -> BOOLEAN]

RInit ==
    /\ Init
    /\ resign = [n \in Nodes |-> "none"]
    /\ how = [n \in Nodes |-> ""]
    /\ gave = [n \in Nodes |-> {}]
    /\ lost = [n \in Nodes |-> FALSE]

Acting(n) == resign[n] = "none"

(***************************************************************************)
(* Resignation                                                             *)
(***************************************************************************)

\* Master m steps down (NodeProtocol::resign, the acting Master's branch). `stops`: it
\* deactivates its tasks (ConfigSwitch::resign; FALSE in the mutant that keeps them).
ResignBy(m, stops) ==
    /\ IsMaster(m)
    /\ Acting(m)
    /\ masterSeq[m] > 0
    /\ crashes < MaxCrashes
    /\ crashes' = crashes + 1
    /\ resign' = [resign EXCEPT ![m] = "flushing"]
    /\ gave' = [gave EXCEPT ![m] = active[m]]
    /\ stage' = [stage EXCEPT ![m] = "Stable"]
    /\ masterStage' = [masterStage EXCEPT ![m] = "Idle"]
    /\ IF stops
       THEN /\ active' = [active EXCEPT ![m] = {}]
            /\ unflushed' = [unflushed EXCEPT ![m] = @ \cup active[m]]
       ELSE UNCHANGED <<active, unflushed>>
    /\ UNCHANGED <<alive, role, epoch, seq, config, version, stored, masterConfig, masterSeq,
                   failed, msgs, acks, phaseChanges, unbooted, how, lost>>

\* Its resignation ends (advance_resign): every final checkpoint acknowledged, or its
\* deadline passed, the rest abandoned. `abandons`: what is unflushed is dropped (FALSE in
\* the mutant that says it left and keeps claiming it). It takes no part any more: a
\* crashed node for ConfigSwitch (see the header).
ResignedBy(m, abandons) ==
    /\ alive[m]
    /\ resign[m] = "flushing"
    /\ resign' = [resign EXCEPT ![m] = "done"]
    /\ how' = [how EXCEPT ![m] = IF unflushed[m] = {} THEN "flushed" ELSE "abandoned"]
    /\ lost' = [lost EXCEPT ![m] = \E t \in unflushed[m] : version[m][t] # stored[t]]
    /\ alive' = [alive EXCEPT ![m] = FALSE]
    /\ IF abandons THEN unflushed' = [unflushed EXCEPT ![m] = {}] ELSE UNCHANGED unflushed
    /\ UNCHANGED <<role, epoch, seq, config, stage, active, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes, phaseChanges,
                   unbooted, gave>>

(***************************************************************************)
(* ConfigSwitch's steps, with what a resigned Master no longer does        *)
(***************************************************************************)

\* `drives`: the guard of the driver's steps (the mutant lets a resigned Master drive).
RProtocolNextBy(Drives(_)) ==
    \/ \E m \in Nodes : BootSwitch(m) /\ Drives(m)
    \/ \E m, f \in Nodes : Exclude(m, f) /\ Drives(m)
    \/ \E m \in Nodes : BroadcastActivate(m) /\ Drives(m)
    \/ \E m \in Nodes : CompleteSwitch(m) /\ Drives(m)
    \/ \E n \in Nodes : BecomeMaster(n) /\ Acting(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg) /\ Acting(n)
    \/ \E n \in Nodes, t \in Tasks : Deactivate(n, t) /\ Acting(n)
    \* A resigned Master flushes its final checkpoints too.
    \/ \E n \in Nodes, t \in Tasks : FlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : Ack(n, k) /\ Acting(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveActivate(n, msg) /\ Acting(n)
    \/ \E n \in Nodes, t \in Tasks : Activate(n, t) /\ Acting(n)

RNextBy(stops, abandons, Drives(_)) ==
    \/ RProtocolNextBy(Drives) /\ UNCHANGED resignVars
    \/ \E m \in Nodes, c \in ConfigIds : RequestPhase(m, c) /\ Drives(m) /\ UNCHANGED resignVars
    \/ EnvironmentNext /\ UNCHANGED resignVars
    \/ \E m \in Nodes : ResignBy(m, stops)
    \/ \E m \in Nodes : ResignedBy(m, abandons)

RNext == RNextBy(TRUE, TRUE, Acting)

RSpec == RInit /\ [][RNext]_allVars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* From its Resign on, a Master runs no task and drives no switch.
ResignedRunsNothingInv ==
    \A m \in Nodes : resign[m] # "none" => active[m] = {} /\ masterStage[m] = "Idle"

\* A Master that says it left claims nothing unflushed: its successor takes over on that
\* word, and nothing of the resigned Master's is pending any more.
ResignedLeftCleanInv ==
    \A m \in Nodes : resign[m] = "done" => unflushed[m] = {} /\ active[m] = {}
=============================================================================
