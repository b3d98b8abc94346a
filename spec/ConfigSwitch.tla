---------------------------- MODULE ConfigSwitch ----------------------------
(***************************************************************************)
(* Configuration switching of the OBC-NG middleware.                       *)
(*                                                                         *)
(* A configuration places every task on a node. The Master switches the    *)
(* cluster to a new configuration when a node fails (the decision graph,   *)
(* OnFailure) and for planned mission-phase changes (OnPhase). A switch is *)
(* identified by <<epoch, seq>>: the Master's epoch and its switch         *)
(* counter; a node follows only the newest switch it has seen.            *)
(*                                                                         *)
(* A switch has two phases, so that a task is never active on two nodes:   *)
(*  1. The Master broadcasts the reconfiguration command (epoch, seq,      *)
(*     configuration id). Each node deactivates the tasks that leave it,   *)
(*     flushes their final checkpoints to the Storage node, and acks       *)
(*     "Prepared".                                                         *)
(*  2. When every running node has acked "Prepared", the Master broadcasts *)
(*     "Activate". Each node activates the tasks the configuration places  *)
(*     on it, each from the latest checkpoint on the Storage node, and     *)
(*     acks "Activated". When every running node has, the switch is        *)
(*     complete.                                                           *)
(* The cluster starts with a switch too (the boot switch): every node     *)
(* boots in the initial view (epoch 1, seq 0, Stable, configuration        *)
(* InitialConfig) with no task active, and the initial Master starts an    *)
(* ordinary switch to InitialConfig at seq 1 (BootSwitch), whose Activate  *)
(* starts every task, from the Storage node's checkpoint. No node starts   *)
(* a task on its own: a node may boot late (at most MaxLateBoots of them,  *)
(* never the initial Master), and until it boots it is down like a crashed *)
(* node, so the Master may declare it failed and move its tasks elsewhere  *)
(* before it boots; a task it started at boot would then run twice, from  *)
(* a stale state (mutants/SwitchActivateAtBoot.tla). A late node boots in  *)
(* the initial view and follows the newest command like any other node.   *)
(* A newer command may arrive in the middle of a switch (a further failure *)
(* or a new Master): the node drops the old switch and starts the new one. *)
(* A running task executes steps (Execute), which advance its state       *)
(* version. The checkpoints a component writes after each step (as in the  *)
(* paper) are left out: they only make the stored state newer between     *)
(* switches; the write that races with a migration is the final one,       *)
(* FlushCheckpoint, after deactivation.                                    *)
(*                                                                         *)
(* Failures are crashes: a crashed node runs nothing. Failure detection is *)
(* the Heartbeat spec's: complete, and accurate within the loss bound, so  *)
(* here the Master may declare a node exactly when it is down (alive[]),   *)
(* and waits for every node it has not declared. Master failover is       *)
(* the MasterElection spec's, taken as one atomic step (BecomeMaster): the *)
(* first running node in Priority becomes Master in a higher epoch and     *)
(* restarts the switch from its own configuration. The Storage node is     *)
(* reliable, runs no task and holds `stored`; Nodes are the nodes that    *)
(* run tasks and switch. Messages may be lost, duplicated and             *)
(* reordered (msgs and acks only grow); crashed nodes are not restarted  *)
(* here (a late boot is a first start, not a restart).                    *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - NoDoubleActivationInv: no task is ever active on two nodes.          *)
(*  - ResumeLatestCheckpointInv: a running task's state is never older     *)
(*    than the Storage node's checkpoint: a migrated task resumed from the *)
(*    last checkpoint its previous owner wrote, and nothing older.         *)
(*  - SwitchConverges: under fairness, eventually a running Master has     *)
(*    completed its switch and every running node is Stable in the         *)
(*    Master's configuration: all live nodes agree on the configuration   *)
(*    id, also when a switch is interrupted by a further failure or a      *)
(*    Master failover.                                                     *)
(***************************************************************************)
EXTENDS Naturals, Sequences, FiniteSets

CONSTANTS
    Nodes,            \* the nodes that run tasks and take part in switches
    Priority,         \* the processing nodes in succession order; Priority[1] is Master
    Storage,          \* the Storage node: holds `stored`, which never fails; as a node
                      \* (it takes part in switches, and may run tasks) it may be one of
                      \* Nodes (the trace mapping lists it there), or not (the models)
    Tasks,            \* the application tasks (all checkpointed)
    ConfigIds,        \* configuration ids
    InitialConfig,    \* the configuration the cluster starts in
    Placement(_, _),  \* Placement(c, t): the node configuration c places task t on
    OnFailure(_, _),  \* OnFailure(c, f): the configuration after c when f fails
    OnPhase(_),       \* OnPhase(c): configurations a planned phase change leads to
    MaxCrashes,       \* environment: at most this many crashes
    MaxPhaseChanges,  \* at most this many planned switches
    MaxVersion,       \* environment: a task executes at most this many steps
    MaxLateBoots      \* environment: at most this many nodes boot after the others

ProcessingNodes == {Priority[i] : i \in 1..Len(Priority)}

\* Where a configuration places a task of another phase: on no node (a mission's phases
\* may run different tasks; the models place every task in every configuration).
Unplaced == "unplaced"

ASSUME NodesAssumption ==
    /\ ProcessingNodes \subseteq Nodes
    /\ Storage \notin ProcessingNodes
ASSUME ConfigAssumption ==
    /\ InitialConfig \in ConfigIds
    /\ \A c \in ConfigIds, t \in Tasks : Placement(c, t) \in Nodes \cup {Unplaced}
ASSUME BudgetAssumption ==
    {MaxCrashes, MaxPhaseChanges, MaxVersion, MaxLateBoots} \subseteq Nat
    /\ MaxCrashes < Len(Priority)
    /\ MaxLateBoots < Cardinality(Nodes)

VARIABLES
    alive,         \* env: [Nodes -> BOOLEAN]
    role,          \* [Nodes -> {"Master", "Observer", "Worker"}]
    epoch,         \* [Nodes -> Nat], epoch of the latest command accepted
    seq,           \* [Nodes -> Nat], switch number of the latest command accepted
    config,        \* [Nodes -> ConfigIds], configuration the node is in or moving to
    stage,         \* [Nodes -> Stages], the node's progress in the switch
    active,        \* [Nodes -> SUBSET Tasks], tasks running on the node
    unflushed,     \* [Nodes -> SUBSET Tasks], deactivated, final checkpoint not written
    version,       \* [Nodes -> [Tasks -> 0..MaxVersion]], task state held by the node
    stored,        \* [Tasks -> 0..MaxVersion], latest checkpoint on the Storage node
    masterStage,   \* [Nodes -> MasterStages], the switch as the Master drives it
    masterConfig,  \* [Nodes -> ConfigIds], configuration the Master is driving
    masterSeq,     \* [Nodes -> Nat], the Master's switch counter
    failed,        \* [Nodes -> SUBSET Nodes], nodes the Master has declared failed
    msgs,          \* env: Master broadcasts (commands and activates)
    acks,          \* env: node acks
    crashes,       \* env: number of crashes so far
    phaseChanges,  \* number of planned switches so far
    unbooted       \* env: SUBSET Nodes, the nodes that have not booted yet

vars == <<alive, role, epoch, seq, config, stage, active, unflushed, version, stored,
          masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes, phaseChanges,
          unbooted>>

Stages == {"Stable", "Deactivating", "Prepared", "Activating"}
MasterStages == {"Idle", "Preparing", "Activating"}

\* The tasks configuration c places on node n.
TasksOn(c, n) == {t \in Tasks : Placement(c, t) = n}

\* <<e1, s1>> is newer than <<e2, s2>>.
Newer(e1, s1, e2, s2) == e1 > e2 \/ (e1 = e2 /\ s1 > s2)

Command(e, s, c) == [kind |-> "Command", epoch |-> e, seq |-> s, config |-> c]
ActivateMsg(e, s, c) == [kind |-> "Activate", epoch |-> e, seq |-> s, config |-> c]
AckMsg(k, e, s, n) == [kind |-> k, epoch |-> e, seq |-> s, from |-> n]

Running == {n \in Nodes : alive[n]}
IsMaster(m) == alive[m] /\ role[m] = "Master"

TypeOK ==
    /\ alive \in [Nodes -> BOOLEAN]
    /\ role \in [Nodes -> {"Master", "Observer", "Worker"}]
    /\ epoch \in [Nodes -> Nat]
    /\ seq \in [Nodes -> Nat]
    /\ config \in [Nodes -> ConfigIds]
    /\ stage \in [Nodes -> Stages]
    /\ active \in [Nodes -> SUBSET Tasks]
    /\ unflushed \in [Nodes -> SUBSET Tasks]
    /\ version \in [Nodes -> [Tasks -> 0..MaxVersion]]
    /\ stored \in [Tasks -> 0..MaxVersion]
    /\ masterStage \in [Nodes -> MasterStages]
    /\ masterConfig \in [Nodes -> ConfigIds]
    /\ masterSeq \in [Nodes -> Nat]
    /\ failed \in [Nodes -> SUBSET Nodes]
    /\ crashes \in 0..MaxCrashes
    /\ phaseChanges \in 0..MaxPhaseChanges
    /\ unbooted \subseteq Nodes \ {Priority[1]}

\* Every node boots in the initial view with no task active; up to MaxLateBoots of them
\* (not the initial Master) have not booted yet: they are down until Boot.
Init ==
    /\ unbooted \in {B \in SUBSET (Nodes \ {Priority[1]}) :
                        Cardinality(B) <= MaxLateBoots}
    /\ alive = [n \in Nodes |-> n \notin unbooted]
    /\ role = [n \in Nodes |-> IF n = Priority[1] THEN "Master"
                               ELSE IF n \in ProcessingNodes THEN "Observer"
                               ELSE "Worker"]
    /\ epoch = [n \in Nodes |-> 1]
    /\ seq = [n \in Nodes |-> 0]
    /\ config = [n \in Nodes |-> InitialConfig]
    /\ stage = [n \in Nodes |-> "Stable"]
    /\ active = [n \in Nodes |-> {}]
    /\ unflushed = [n \in Nodes |-> {}]
    /\ version = [n \in Nodes |-> [t \in Tasks |-> 0]]
    /\ stored = [t \in Tasks |-> 0]
    /\ masterStage = [n \in Nodes |-> "Idle"]
    /\ masterConfig = [n \in Nodes |-> InitialConfig]
    /\ masterSeq = [n \in Nodes |-> 0]
    /\ failed = [n \in Nodes |-> {}]
    /\ msgs = {}
    /\ acks = {}
    /\ crashes = 0
    /\ phaseChanges = 0

(***************************************************************************)
(* Master                                                                  *)
(***************************************************************************)

\* Master m starts switch number masterSeq[m] + 1 to configuration c: it broadcasts the
\* command and applies it to itself at once.
StartSwitch(m, c) ==
    LET s == masterSeq[m] + 1 IN
    /\ masterSeq' = [masterSeq EXCEPT ![m] = s]
    /\ masterConfig' = [masterConfig EXCEPT ![m] = c]
    /\ masterStage' = [masterStage EXCEPT ![m] = "Preparing"]
    /\ msgs' = msgs \cup {Command(epoch[m], s, c)}
    /\ seq' = [seq EXCEPT ![m] = s]
    /\ config' = [config EXCEPT ![m] = c]
    /\ stage' = [stage EXCEPT ![m] = "Deactivating"]

\* Master m learns that f failed and switches along the decision graph. A failure that
\* leaves the configuration as it is starts no switch.
Exclude(m, f) ==
    /\ IsMaster(m)
    /\ masterSeq[m] > 0
    /\ ~alive[f]
    /\ f \notin failed[m]
    /\ failed' = [failed EXCEPT ![m] = @ \cup {f}]
    /\ LET c == OnFailure(masterConfig[m], f) IN
        IF c # masterConfig[m]
        THEN StartSwitch(m, c)
        ELSE UNCHANGED <<masterSeq, masterConfig, masterStage, msgs, seq, config, stage>>
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, acks,
                   crashes, phaseChanges, unbooted>>

\* Master m starts a planned switch to c (a mission-phase change), between switches.
RequestPhase(m, c) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Idle"
    /\ masterSeq[m] > 0
    /\ phaseChanges < MaxPhaseChanges
    /\ c \in OnPhase(masterConfig[m])
    /\ phaseChanges' = phaseChanges + 1
    /\ StartSwitch(m, c)
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, unbooted>>

\* The boot switch: the initial Master, having started no switch yet, switches the
\* cluster to InitialConfig (switch 1 of epoch 1). A Master that took over before it
\* did restarts the switch from its configuration, InitialConfig, instead.
BootSwitch(m) ==
    /\ IsMaster(m)
    /\ masterSeq[m] = 0
    /\ StartSwitch(m, InitialConfig)
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted>>

\* Every node Master m has not declared failed acked kind for its current switch. (Not
\* "every running node": a node that has not booted yet is down but not declared, and
\* a switch that went on without it would leave it a superseded switch to take up when
\* it boots, placing tasks on it that a later switch moved elsewhere.)
AllAcked(m, kind) ==
    \A n \in Nodes \ failed[m] : AckMsg(kind, epoch[m], masterSeq[m], n) \in acks

\* Phase 2: every running node has deactivated and flushed; tell them to activate.
BroadcastActivate(m) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Preparing"
    /\ AllAcked(m, "Prepared")
    /\ masterStage' = [masterStage EXCEPT ![m] = "Activating"]
    /\ msgs' = msgs \cup {ActivateMsg(epoch[m], masterSeq[m], masterConfig[m])}
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, version,
                   stored, masterConfig, masterSeq, failed, acks, crashes,
                   phaseChanges, unbooted>>

\* Every running node runs the new configuration: the switch is complete.
CompleteSwitch(m) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Activating"
    /\ AllAcked(m, "Activated")
    /\ masterStage' = [masterStage EXCEPT ![m] = "Idle"]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, version,
                   stored, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* The Master crashed; n, the first running node in Priority, takes over in an epoch
\* above every epoch seen (MasterElection, as one step) and restarts the switch from
\* the configuration it knows.
BecomeMaster(n) ==
    /\ \A x \in Nodes : role[x] = "Master" => ~alive[x]
    /\ alive[n]
    /\ n \in ProcessingNodes
    /\ \E i \in 1..Len(Priority) :
        /\ Priority[i] = n
        /\ \A j \in 1..(i - 1) : ~alive[Priority[j]]
    /\ LET e == 1 + CHOOSE x \in {epoch[y] : y \in Nodes} : \A y \in Nodes : epoch[y] <= x
       IN /\ role' = [x \in Nodes |-> IF x = n THEN "Master"
                                      ELSE IF role[x] = "Master" THEN "Worker"
                                      ELSE role[x]]
          /\ epoch' = [epoch EXCEPT ![n] = e]
          /\ masterSeq' = [masterSeq EXCEPT ![n] = 1]
          /\ masterConfig' = [masterConfig EXCEPT ![n] = config[n]]
          /\ masterStage' = [masterStage EXCEPT ![n] = "Preparing"]
          /\ failed' = [failed EXCEPT ![n] = {}]
          /\ msgs' = msgs \cup {Command(e, 1, config[n])}
          /\ seq' = [seq EXCEPT ![n] = 1]
          /\ stage' = [stage EXCEPT ![n] = "Deactivating"]
    /\ UNCHANGED <<alive, config, active, unflushed, version, stored, acks, crashes,
                   phaseChanges, unbooted>>

(***************************************************************************)
(* Nodes                                                                   *)
(***************************************************************************)

\* Node n accepts a newer command: it drops whatever switch it was in.
ReceiveCommand(n, msg) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.kind = "Command"
    /\ Newer(msg.epoch, msg.seq, epoch[n], seq[n])
    /\ epoch' = [epoch EXCEPT ![n] = msg.epoch]
    /\ seq' = [seq EXCEPT ![n] = msg.seq]
    /\ config' = [config EXCEPT ![n] = msg.config]
    /\ stage' = [stage EXCEPT ![n] = "Deactivating"]
    /\ UNCHANGED <<alive, role, active, unflushed, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* Node n stops task t, which its target configuration places elsewhere.
Deactivate(n, t) ==
    /\ alive[n]
    /\ stage[n] = "Deactivating"
    /\ t \in active[n]
    /\ Placement(config[n], t) # n
    /\ active' = [active EXCEPT ![n] = @ \ {t}]
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \cup {t}]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* Node n writes the final checkpoint of task t, which it deactivated, to the Storage
\* node.
FlushCheckpoint(n, t) ==
    /\ alive[n]
    /\ t \in unflushed[n]
    /\ stored' = [stored EXCEPT ![t] = version[n][t]]
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \ {t}]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, version, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* Every task leaving n is stopped and flushed (phase 1 done), or every task placed on n
\* runs (phase 2 done): n acks.
ReadyToAck(n, kind) ==
    IF kind = "Prepared"
    THEN /\ stage[n] = "Deactivating"
         /\ \A t \in active[n] : Placement(config[n], t) = n
         /\ unflushed[n] = {}
    ELSE /\ stage[n] = "Activating"
         /\ TasksOn(config[n], n) \subseteq active[n]

Ack(n, kind) ==
    /\ alive[n]
    /\ ReadyToAck(n, kind)
    /\ stage' = [stage EXCEPT ![n] = IF kind = "Prepared" THEN "Prepared" ELSE "Stable"]
    /\ acks' = acks \cup {AckMsg(kind, epoch[n], seq[n], n)}
    /\ UNCHANGED <<alive, role, epoch, seq, config, active, unflushed, version, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, crashes,
                   phaseChanges, unbooted>>

\* Node n receives the Activate of the switch it is in.
ReceiveActivate(n, msg) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.kind = "Activate"
    /\ stage[n] = "Prepared"
    /\ msg.epoch = epoch[n] /\ msg.seq = seq[n]
    /\ stage' = [stage EXCEPT ![n] = "Activating"]
    /\ UNCHANGED <<alive, role, epoch, seq, config, active, unflushed, version, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* Node n starts task t from the latest checkpoint on the Storage node.
Activate(n, t) ==
    /\ alive[n]
    /\ stage[n] = "Activating"
    /\ Placement(config[n], t) = n
    /\ t \notin active[n]
    /\ active' = [active EXCEPT ![n] = @ \cup {t}]
    /\ version' = [version EXCEPT ![n][t] = stored[t]]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, unflushed, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* Task t runs one step on n.
Execute(n, t) ==
    /\ alive[n]
    /\ t \in active[n]
    /\ version[n][t] < MaxVersion
    /\ version' = [version EXCEPT ![n][t] = @ + 1]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* Node n crashes; what it ran and had not flushed is lost.
Crash(n) ==
    /\ alive[n]
    /\ crashes < MaxCrashes
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ active' = [active EXCEPT ![n] = {}]
    /\ unflushed' = [unflushed EXCEPT ![n] = {}]
    /\ crashes' = crashes + 1
    /\ UNCHANGED <<role, epoch, seq, config, stage, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, phaseChanges, unbooted>>

\* Node n boots late: it runs from now on, in the initial view it was given at Init (no
\* step changes an unbooted node's variables), with nothing active.
Boot(n) ==
    /\ n \in unbooted
    /\ unbooted' = unbooted \ {n}
    /\ alive' = [alive EXCEPT ![n] = TRUE]
    /\ UNCHANGED <<role, epoch, seq, config, stage, active, unflushed, version, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges>>

ProtocolNext ==
    \/ \E m \in Nodes : BootSwitch(m)
    \/ \E m, f \in Nodes : Exclude(m, f)
    \/ \E m \in Nodes : BroadcastActivate(m)
    \/ \E m \in Nodes : CompleteSwitch(m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Deactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : FlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : Ack(n, k)
    \/ \E n \in Nodes, msg \in msgs : ReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Activate(n, t)

\* Planned phase changes are the operators' choice, not an obligation of the protocol.
PlannedNext == \E m \in Nodes, c \in ConfigIds : RequestPhase(m, c)

EnvironmentNext ==
    \/ \E n \in Nodes, t \in Tasks : Execute(n, t)
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : Boot(n)

Next == ProtocolNext \/ PlannedNext \/ EnvironmentNext

\* Every protocol step is finite in number (switches, versions and crashes are
\* bounded), so weak fairness of the protocol as a whole makes every behaviour end in a
\* state where no protocol step is enabled; SwitchConverges says what holds there. A
\* late node does boot (a node that never starts is a crash, which MaxCrashes bounds).
Fairness == WF_vars(ProtocolNext) /\ \A n \in Nodes : WF_vars(Boot(n))

Spec == Init /\ [][Next]_vars
FairSpec == Spec /\ Fairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

NoDoubleActivationInv ==
    \A t \in Tasks, n, m \in Nodes :
        (t \in active[n] /\ t \in active[m]) => n = m

ResumeLatestCheckpointInv ==
    \A n \in Nodes, t \in Tasks :
        (alive[n] /\ t \in active[n]) => version[n][t] >= stored[t]

Converged ==
    \E m \in Nodes :
        /\ IsMaster(m)
        /\ masterStage[m] = "Idle"
        /\ \A n \in Running : config[n] = masterConfig[m] /\ stage[n] = "Stable"
        /\ \A t \in Tasks : Placement(masterConfig[m], t) # Unplaced =>
                                t \in active[Placement(masterConfig[m], t)]

SwitchConverges == <>[]Converged

=============================================================================
