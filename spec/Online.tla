------------------------------- MODULE Online -------------------------------
(***************************************************************************)
(* Online configurations, beyond the decision graph (issue "Beyond the     *)
(* graph", item 5; docs/missions.md, "Placement modes"; core/placement).   *)
(*                                                                         *)
(* In a phase whose `placement` is online (or graph+online, past the       *)
(* graph's end) the Master does not walk a graph proven before launch: its *)
(* placer computes a configuration for the current failed set F (a master, *)
(* observers, and each task's host or none) and its Command carries that   *)
(* configuration whole. Every receiver runs the checker on it before it    *)
(* acts (Accepts(c, F), "valid under F"):                                  *)
(*  - every essential task is placed; a non-essential one may be shed      *)
(*    (left unplaced, Shed);                                               *)
(*  - every placed task is on a node not in F that is capable of it        *)
(*    (Capable), and no node's summed load is beyond its capacity;         *)
(*  - the master is a processing node not in F; the observers are          *)
(*    processing nodes not in F other than the master, and there is one at *)
(*    least while two processing nodes are alive;                          *)
(*  - a checkpointed task is placed only while a Storage node is alive.    *)
(* A configuration the checker refuses is evidence against the Master: the *)
(* receiver declares it failed, for good, and does not switch. SAFE, which *)
(* runs no task here, is taken only where no configuration at all passes   *)
(* the checker under F (NoPlacement(F)): the placer must not give up where *)
(* a placement exists.                                                     *)
(*                                                                         *)
(* The spec says nothing about how the placer chooses: a correct Master    *)
(* switches to ANY configuration the checker accepts with itself as its    *)
(* master (a nondeterministic choice), so every property below holds for   *)
(* whatever a correct placer picks. A lying Master (Liar, a processing     *)
(* node, or NoLiar for a correct cluster) sends any configuration: another *)
(* master, a failed or incapable host, an overloaded node, a missing       *)
(* essential task, a failed or missing observer, a checkpointed task with  *)
(* no Storage node, SAFE where a placement exists; any failed set; under   *)
(* its own identity (the transport authenticates senders).                 *)
(*                                                                         *)
(* The switch is ConfigSwitch's, in two phases, with ValueFault's receiver *)
(* rules, kept to what an online target needs:                             *)
(*  - Authority (MayCommand): a Command's view is followed only from its   *)
(*    master, the owner of its epoch (Owner(e), the succession Priority    *)
(*    round the epochs as in MasterElection), and only when it is newer    *)
(*    than the receiver's own (an epoch above, or the same epoch and a     *)
(*    higher switch number): receivers only move forward.                  *)
(*  - The checker (Checked: Accepts, or NoPlacement for SAFE, and the      *)
(*    configuration's master the view's). A view that fails is refused and *)
(*    its sender declared failed (`declared`), for good.                   *)
(*  - Backed exclusions (Backed): every node the view's failed set names   *)
(*    crashed (the crash detection of Heartbeat.tla, taken as perfect      *)
(*    here) or was declared failed by a correct node other than the        *)
(*    sender. A view not backed is not followed, and is no evidence.       *)
(*    Without it a lying Master would exclude a running correct node and   *)
(*    place its tasks elsewhere, each view passing the checker.            *)
(*  - Peers' Prepared (PeersPrepared): a node adopting a view stops the    *)
(*    tasks it places elsewhere and acks "Prepared" with the whole view;   *)
(*    it starts the tasks placed on it only once every other processing    *)
(*    node the view does not exclude acked "Prepared" of exactly that      *)
(*    view (the liar's ack taken as sent). A correct Master sends its      *)
(*    Activate once every such node acked, and the liar sends one at any   *)
(*    time, so the Activate itself is left out: a node activates when rule *)
(*    4 lets it.                                                           *)
(* A correct Master switches when it learns of a failure (Exclude: a crash *)
(* or a Command it refused), to any configuration the checker accepts      *)
(* under its view's failed set and that node, or SAFE where there is none; *)
(* from SAFE it stays in SAFE (no configuration passes under a larger F    *)
(* either). A correct node takes over (BecomeMaster) once the master of    *)
(* its view and every owner of the epochs before its next one crashed or   *)
(* were declared by it, in its next owned epoch, with a configuration it   *)
(* computes the same way under every failure it knows of.                  *)
(*                                                                         *)
(* Properties, about the correct processing nodes (Followers):             *)
(*  - OneMasterPerEpochInv: the correct nodes that follow views of one     *)
(*    epoch agree on its master.                                           *)
(*  - NoDoubleActivationInv: no task runs on two correct nodes at once (a  *)
(*    crashed node runs nothing).                                          *)
(*  - ValidConfigInv: every view a correct node switched to passes the     *)
(*    checker under the failed set it was switched to (its own: the one    *)
(*    the Master computed it for), that failed set names only crashed      *)
(*    nodes and the liar, and the node runs only tasks the view places on  *)
(*    it.                                                                  *)
(*  - NoHonestRefusalInv: no correct node refuses a correct Master's       *)
(*    Command, so none declares a correct node failed: the checker costs a *)
(*    correct cluster nothing, whatever its placer picks.                  *)
(*                                                                         *)
(* What TLC shows (MCOnline.tla has the models; one worker): every         *)
(* property holds with online targets in a correct cluster with two        *)
(* crashes (MCOnlineHonest, 288 states, 1 s; MCOnlineFour, four processing *)
(* nodes and three tasks, 27,499 states, 22 s), against a lying first      *)
(* Master with one crash (MCOnline, 3,777 states, 4 s; MCOnlineSkip, its   *)
(* switch numbers up to 2, 28,259 states, 45 s) and against a lying        *)
(* Observer that owns the next epoch (MCOnlineObserver, 4,150 states, 6    *)
(* s). Each rule binds: without the checker at the receivers (mutant       *)
(* OnlineNoReceiverCheck) a correct node follows the liar's SAFE where a   *)
(* placement exists (ValidConfigInv); a receiver that forbids shedding     *)
(* (OnlineNoShedding, the graph's check) refuses a correct Master's online *)
(* target (NoHonestRefusalInv); without peers' Prepared                    *)
(* (OnlineNoPeerPrepared) the liar's swap of the two tasks starts one      *)
(* twice (NoDoubleActivationInv); without the owner check                  *)
(* (OnlineNoOwnership) a correct node follows the liar's view of an epoch  *)
(* another node took over (OneMasterPerEpochInv); without backed           *)
(* exclusions (OnlineUnbackedExclusion) a correct node follows a view that *)
(* excludes a running correct node (ValidConfigInv; NoDoubleActivationInv  *)
(* too, by hand). Witnesses (manifest.json) show the premises reached: a   *)
(* task moved by an online target and started, a target that sheds, SAFE,  *)
(* a refusal, a lie followed, a take-over, the liar excluded.              *)
(*                                                                         *)
(* Not covered (stated, not hidden):                                       *)
(*  - The runtime's further rules. The nodes run online switches           *)
(*    (core/fsm/online.hpp, NodeProtocol through admission.hpp's           *)
(*    view_problem and edge_problem): besides the checker, their           *)
(*    online_edge_problem binds a switch to the phase it is in, the        *)
(*    graph+online mode to the graph where the graph answers, a            *)
(*    readmission to a new epoch, and SAFE to where their placer           *)
(*    (failure_target, a bounded search) finds no placement. The spec has  *)
(*    online phases only and takes SAFE only where no configuration passes *)
(*    at all (NoPlacement): a runtime Master whose placer gives up where   *)
(*    an exact packing fits (core/placement/README.md) sends SAFE that its *)
(*    receivers, running the same placer, accept, and that this spec's     *)
(*    receivers would refuse.                                              *)
(*  - Checkpoints, lineages, versions and the Storage node's part in a     *)
(*    switch (ValueFault, Handoff): the Storage node here is only alive or *)
(*    not, for the checker's storage rule. Phase changes, readmissions,    *)
(*    hand-overs and the observers' order (the election's succession is    *)
(*    Priority, not the configuration's observers).                        *)
(*  - Failure detection is perfect and immediate (a crashed node is known  *)
(*    to every correct node), and the liar never crashes nor is paused:    *)
(*    combined faults are ValueFault's "Not covered" too.                  *)
(*  - Liveness: a crashed node the view does not exclude holds a switch    *)
(*    until the Master excludes it; no liveness is checked. The checker    *)
(*    runs under the view's failed set, the one its Master computed it     *)
(*    for, not under what the receiver knows: a view from before a crash   *)
(*    may place a task on the crashed node (for a correct Master a race,   *)
(*    which its next switch ends). A lying Master may leave it so, and     *)
(*    nothing here is evidence against it, so the task stays unplaced      *)
(*    (WitnessOnlineStaleHostInv: reached in MCOnline), as a lying Master  *)
(*    may leave any crash unanswered (ValueFault's "Liveness"): no safety  *)
(*    property breaks.                                                     *)
(*  - The placer itself. Its answers are checked by core/placement's tests *)
(*    against the verifier's checker; here it may answer anything the      *)
(*    checker accepts. SAFE here runs no task (the runtime's safe mode     *)
(*    runs the essential ones on its master, with its own checks).         *)
(***************************************************************************)
EXTENDS Naturals, FiniteSets, Sequences, TLC

CONSTANTS
    Nodes,          \* every node: the processing nodes and the Storage nodes
    Priority,       \* the processing nodes in succession order; Priority[1] is the first
                    \*   Master, and Owner(e) the one node that may be Master in epoch e
    StorageNodes,   \* the Storage nodes: keep the checkpoints, own no epoch, host no task
    Tasks,          \* the application tasks
    Essential,      \* the tasks an online configuration may not shed
    Checkpointed,   \* the tasks that need an alive Storage node to run
    Capable,        \* [Tasks -> SUBSET Nodes]: the nodes capable of each task
    Capacity,       \* [Nodes -> Nat]: each node's capacity
    Load,           \* [Tasks -> Nat]: each task's load
    InitialConfig,  \* the configuration the cluster starts in (valid with no failure)
    MaxCrashes,     \* at most this many nodes crash (the liar never does)
    MaxEpoch,       \* the wire's epoch width: the largest epoch a Command may carry
    MaxSeq,         \* the liar's switch numbers are at most this (a bound on the model)
    Liar,           \* the lying processing node, or NoLiar: a correct cluster
    NoLiar,         \* no node (a model value)
    Shed,           \* where a configuration places a task it sheds (a model value)
    Safe            \* SAFE, a view's configuration when no placement exists (a model value)

ProcessingNodes == {Priority[i] : i \in 1..Len(Priority)}
N == Len(Priority)

\* Every configuration the wire can carry: a master, observers, each task's host or Shed.
Configurations ==
    [master : Nodes, observers : SUBSET Nodes, host : [Tasks -> Nodes \cup {Shed}]]

ASSUME NodesAssumption ==
    /\ Cardinality(ProcessingNodes) = N /\ N >= 1
    /\ ProcessingNodes \subseteq Nodes
    /\ StorageNodes \subseteq Nodes \ ProcessingNodes
    /\ Liar \in ProcessingNodes \cup {NoLiar}
    /\ NoLiar \notin Nodes /\ Shed \notin Nodes
ASSUME TaskAssumption ==
    /\ Essential \subseteq Tasks /\ Checkpointed \subseteq Tasks
    /\ Capable \in [Tasks -> SUBSET ProcessingNodes]
    /\ Capacity \in [Nodes -> Nat] /\ Load \in [Tasks -> Nat]
    /\ InitialConfig \in Configurations
ASSUME BudgetAssumption ==
    /\ {MaxCrashes, MaxEpoch, MaxSeq} \subseteq Nat
    /\ MaxEpoch >= 1

(***************************************************************************)
(* The checker: "valid under the set F of failed nodes" (check.hpp), one   *)
(* operator per rule, online (non-essential tasks may be shed).            *)
(***************************************************************************)
RECURSIVE SumLoad(_)
SumLoad(S) == IF S = {} THEN 0
              ELSE LET t == CHOOSE x \in S : TRUE IN Load[t] + SumLoad(S \ {t})

Placed(c) == {t \in Tasks : c.host[t] # Shed}
LoadOn(c, n) == SumLoad({t \in Tasks : c.host[t] = n})
AliveProcessing(F) == ProcessingNodes \ F

\* task-missing: every essential task is placed (a non-essential one may be shed).
EssentialPlaced(c) == Essential \subseteq Placed(c)
\* task-on-failed-node and capability: every placed task is on a capable node not in F.
HostsOk(c, F) == \A t \in Placed(c) : c.host[t] \in Capable[t] \ F
\* capacity: no node's summed load is beyond its capacity.
CapacityOk(c) == \A n \in Nodes : LoadOn(c, n) <= Capacity[n]
\* master-invalid: the master is a processing node not in F.
MasterOk(c, F) == c.master \in AliveProcessing(F)
\* observer-invalid: processing nodes not in F other than the master; one at least while
\* two processing nodes are alive.
ObserversOk(c, F) ==
    /\ c.observers \subseteq AliveProcessing(F) \ {c.master}
    /\ Cardinality(AliveProcessing(F)) >= 2 => c.observers # {}
\* storage-unavailable: a checkpointed task is placed only while a Storage node is alive.
StorageOk(c, F) == Checkpointed \cap Placed(c) # {} => StorageNodes \ F # {}

\* The checker's rules, by name, and how many configuration c breaks under F.
Rules == {"task-missing", "host", "capacity", "master", "observer", "storage"}
Holds(r, c, F) ==
    CASE r = "task-missing" -> EssentialPlaced(c)
      [] r = "host" -> HostsOk(c, F)
      [] r = "capacity" -> CapacityOk(c)
      [] r = "master" -> MasterOk(c, F)
      [] r = "observer" -> ObserversOk(c, F)
      [] r = "storage" -> StorageOk(c, F)
Broken(c, F) == {r \in Rules : ~Holds(r, c, F)}

\* The checker (placement::check with Shedding::allowed): c is valid under F.
Accepts(c, F) ==
    /\ EssentialPlaced(c) /\ HostsOk(c, F) /\ CapacityOk(c)
    /\ MasterOk(c, F) /\ ObserversOk(c, F) /\ StorageOk(c, F)

\* The configurations a correct placer may answer (processing masters and observers, tasks
\* on processing nodes), and those of them the checker accepts under each failed set.
PlacerConfigs ==
    [master : ProcessingNodes, observers : SUBSET ProcessingNodes,
     host : [Tasks -> ProcessingNodes \cup {Shed}]]
AcceptedOf == TLCEval([F \in SUBSET Nodes |-> {c \in PlacerConfigs : Accepts(c, F)}])
\* No configuration at all passes the checker under F: only then is SAFE taken. (Enough to
\* look at the placer's: a configuration the checker accepts has a processing master, its
\* observers and hosts are processing nodes.)
NoPlacement(F) == AcceptedOf[F] = {}

(***************************************************************************)
(* Views and epochs                                                        *)
(***************************************************************************)

\* A view, as a Command carries it: its id <<epoch, seq>>, its master (the sender's
\* identity), the failed set it was computed for, and its configuration (or Safe).
Views == [epoch : Nat, seq : Nat, master : Nodes, failed : SUBSET Nodes,
          config : Configurations \cup {Safe}]

Owner(e) == Priority[((e - 1) % N) + 1]
Newer(v, w) == v.epoch > w.epoch \/ (v.epoch = w.epoch /\ v.seq > w.seq)

\* The tasks view v places on node n (SAFE runs none here).
TasksOn(v, n) == IF v.config = Safe THEN {} ELSE {t \in Tasks : v.config.host[t] = n}

\* The checker as a receiver applies it to a view: an online configuration whose master
\* is the view's and that the checker accepts under the view's failed set; or SAFE, with a
\* master not in that set, only where no configuration passes under it.
Checked(v) ==
    IF v.config = Safe
    THEN v.master \in AliveProcessing(v.failed) /\ NoPlacement(v.failed)
    ELSE v.config.master = v.master /\ Accepts(v.config, v.failed)

\* What a correct Master switches to under failed set F: any configuration the checker
\* accepts with m its master (the placer's answer, whatever it is), or SAFE where none.
Targets(m, F) ==
    IF NoPlacement(F) THEN {Safe} ELSE {c \in AcceptedOf[F] : c.master = m}

(***************************************************************************)
(* What the liar may send: on the wire from the start.                     *)
(***************************************************************************)

\* The configurations and failed sets in the liar's views. Every configuration and failed
\* set by default; a model may replace either with a set that keeps each way to break the
\* checker (MCOnline.tla).
LiarConfigs == Configurations
LiarFailedSets == SUBSET Nodes
\* Its views: its own identity as master, any epoch the wire carries, any switch number up
\* to MaxSeq, with at most one defect: an epoch it does not own, or one rule of the checker
\* broken (a master that is not the view's counting as the master rule), or SAFE where a
\* placement exists. A view with two defects is refused or dropped as either alone is, so
\* this leaves out no state of the spec; a mutant, which removes one rule, sees the views
\* that rule alone stopped.
LiarViews ==
    [epoch : 1..MaxEpoch, seq : 1..MaxSeq, master : {Liar}, failed : LiarFailedSets,
     config : LiarConfigs \cup {Safe}]
Defects(v) ==
    (IF Owner(v.epoch) = Liar THEN 0 ELSE 1)
        + (IF v.config = Safe THEN (IF Checked(v) THEN 0 ELSE 1)
           ELSE Cardinality(Broken(v.config, v.failed) \ {"master"})
                    + (IF v.config.master = v.master /\ MasterOk(v.config, v.failed)
                       THEN 0 ELSE 1))
LiarCommands ==
    IF Liar = NoLiar THEN {} ELSE TLCEval({v \in LiarViews : Defects(v) <= 1})
\* The same, by switch id (a receiver looks only at ids newer than its own).
LiarIds == TLCEval({<<v.epoch, v.seq>> : v \in LiarCommands})
LiarCommandsById ==
    TLCEval([id \in LiarIds |-> TLCEval({v \in LiarCommands : <<v.epoch, v.seq>> = id})])

(***************************************************************************)
(* State                                                                   *)
(***************************************************************************)

\* The correct processing nodes: they follow views, run tasks, and may become Master.
Followers == ProcessingNodes \ {Liar}

VARIABLES
    view,      \* [Followers -> Views]: the view the node follows (the newest it adopted)
    stage,     \* [Followers -> {"Prepared", "Stable"}]: in that view's switch, waiting for
               \*   its peers' "Prepared" (its tasks placed elsewhere stopped), or done
    active,    \* [Followers -> SUBSET Tasks]: the tasks running on the node
    declared,  \* [Followers -> SUBSET Nodes]: the nodes it declared failed on evidence (a
               \*   Command it refused), for good; every correct node sees them
    failed,    \* env: the nodes that crashed (for good)
    msgs,      \* env: the correct Masters' Commands, each [from, view]
    acks       \* env: the correct nodes' "Prepared" acks, each [from, view], to every node

vars == <<view, stage, active, declared, failed, msgs, acks>>

InitialView == [epoch |-> 1, seq |-> 0, master |-> Priority[1], failed |-> {},
                config |-> InitialConfig]
ASSUME InitialAssumption ==
    InitialConfig.master = Priority[1] /\ Accepts(InitialConfig, {})

IsMaster(n) == view[n].master = n
Alive(n) == n \notin failed

TypeOK ==
    /\ view \in [Followers -> Views]
    /\ stage \in [Followers -> {"Prepared", "Stable"}]
    /\ active \in [Followers -> SUBSET Tasks]
    /\ declared \in [Followers -> SUBSET Nodes]
    /\ failed \subseteq Nodes \ {Liar}
    /\ Cardinality(failed) <= MaxCrashes
    /\ msgs \subseteq [from : Followers, view : Views]
    /\ acks \subseteq [from : Followers, view : Views]

\* The cluster runs the initial configuration, every task on its host there.
Init ==
    /\ view = [n \in Followers |-> InitialView]
    /\ stage = [n \in Followers |-> "Stable"]
    /\ active = [n \in Followers |-> TasksOn(InitialView, n)]
    /\ declared = [n \in Followers |-> {}]
    /\ failed = {}
    /\ msgs = {}
    /\ acks = {}

(***************************************************************************)
(* The receiver rules, one operator each, so that a mutant removes one     *)
(* (NextBy takes them as parameters).                                      *)
(***************************************************************************)

\* Authority: a Command's view comes from its master, the owner of its epoch.
MayCommand(s, v) == s = v.master /\ Owner(v.epoch) = s

\* Backed exclusions: every node v excludes crashed (every correct node detects a crash)
\* or was declared failed, on evidence, by a correct node other than the sender s.
Declarers(f) == {p \in Followers : f \in declared[p]}
Backed(s, v) == \A f \in v.failed : f \in failed \/ Declarers(f) \ {s} # {}

\* Peers' Prepared: node n starts its view's tasks only once every other processing node
\* its view does not exclude acked "Prepared" of exactly that view (the liar's ack of any
\* view is taken as sent).
PeersPrepared(n) ==
    \A p \in Followers \ (view[n].failed \cup {n}) : [from |-> p, view |-> view[n]] \in acks

(***************************************************************************)
(* Steps                                                                   *)
(***************************************************************************)

\* Node n adopts view v: it stops the tasks v places elsewhere and acks "Prepared".
Adopt(n, v) ==
    /\ view' = [view EXCEPT ![n] = v]
    /\ stage' = [stage EXCEPT ![n] = "Prepared"]
    /\ active' = [active EXCEPT ![n] = @ \cap TasksOn(v, n)]
    /\ acks' = acks \cup {[from |-> n, view |-> v]}

\* Node n receives a Command from s whose view v is newer than its own and sent with
\* authority. If v passes the checker, n adopts it once its exclusions are backed (a view
\* not backed is not followed, and is no evidence: its backing may come later, and the
\* Master retransmits); if not, n refuses it and declares s failed, for good, and does
\* not switch.
ReceiveCommand(MayCommandOp(_, _), CheckedOp(_), BackedOp(_, _), n, s, v) ==
    /\ Alive(n)
    /\ Newer(v, view[n])
    /\ MayCommandOp(s, v)
    /\ IF CheckedOp(v)
       THEN /\ BackedOp(s, v)
            /\ Adopt(n, v)
            /\ UNCHANGED declared
       ELSE /\ s \notin declared[n]
            /\ declared' = [declared EXCEPT ![n] = @ \cup {s}]
            /\ UNCHANGED <<view, stage, active, acks>>
    /\ UNCHANGED <<failed, msgs>>

\* Node n takes the Activate of its view's switch once its peers prepared that view, and
\* starts the tasks the view places on it.
Activate(PeersPreparedOp(_), n) ==
    /\ Alive(n)
    /\ stage[n] = "Prepared"
    /\ PeersPreparedOp(n)
    /\ stage' = [stage EXCEPT ![n] = "Stable"]
    /\ active' = [active EXCEPT ![n] = TasksOn(view[n], n)]
    /\ UNCHANGED <<view, declared, failed, msgs, acks>>

\* Master m switches to view v (its own Command): it adopts v and sends it to every node.
Switch(m, v) ==
    /\ Adopt(m, v)
    /\ msgs' = msgs \cup {[from |-> m, view |-> v]}
    /\ UNCHANGED <<declared, failed>>

\* A correct Master m excludes f, which crashed or which it declared failed: it switches
\* to any configuration the checker accepts under its view's failed set and f, with m its
\* master (the placer's answer, whatever it is), or to SAFE where none exists. From SAFE
\* it stays in SAFE.
Exclude(m, f) ==
    /\ Alive(m) /\ IsMaster(m)
    /\ view[m].config # Safe
    /\ f \in (failed \cup declared[m]) \ view[m].failed
    /\ LET F == view[m].failed \cup {f}
       IN  \E c \in Targets(m, F) :
              Switch(m, [epoch |-> view[m].epoch, seq |-> view[m].seq + 1, master |-> m,
                         failed |-> F, config |-> c])

\* The first epoch after node n's own view that n owns.
NextEpoch(n) == CHOOSE e \in (view[n].epoch + 1)..(view[n].epoch + N) : Owner(e) = n

\* Node n takes over once the master of its view and every owner of the epochs before its
\* next one crashed or were declared by it: it opens its next epoch, within the wire's
\* width, with any configuration the checker accepts under every failure it knows of.
BecomeMaster(n) ==
    /\ Alive(n) /\ ~IsMaster(n)
    /\ NextEpoch(n) <= MaxEpoch
    /\ \A e \in view[n].epoch..(NextEpoch(n) - 1) : Owner(e) \in failed \cup declared[n]
    /\ view[n].master \in failed \cup declared[n]
    /\ LET F == view[n].failed \cup failed \cup declared[n]
       IN  \E c \in Targets(n, F) :
              Switch(n, [epoch |-> NextEpoch(n), seq |-> 0, master |-> n, failed |-> F,
                         config |-> c])

\* env: node n crashes: it runs nothing from now on. The liar does not crash.
Crash(n) ==
    /\ n \notin failed \cup {Liar}
    /\ Cardinality(failed) < MaxCrashes
    /\ failed' = failed \cup {n}
    /\ active' = IF n \in Followers THEN [active EXCEPT ![n] = {}] ELSE active
    /\ UNCHANGED <<view, stage, declared, msgs, acks>>

NextBy(MayCommandOp(_, _), CheckedOp(_), BackedOp(_, _), PeersPreparedOp(_)) ==
    \* Receivers
    \/ \E n \in Followers, msg \in msgs :
          ReceiveCommand(MayCommandOp, CheckedOp, BackedOp, n, msg.from, msg.view)
    \/ \E n \in Followers, id \in LiarIds :
          /\ Newer([epoch |-> id[1], seq |-> id[2]], view[n])
          /\ \E v \in LiarCommandsById[id] :
                ReceiveCommand(MayCommandOp, CheckedOp, BackedOp, n, Liar, v)
    \/ \E n \in Followers : Activate(PeersPreparedOp, n)
    \* Correct Masters
    \/ \E m \in Followers, f \in Nodes : Exclude(m, f)
    \/ \E n \in Followers : BecomeMaster(n)
    \* Environment
    \/ \E n \in Nodes : Crash(n)

Next == NextBy(MayCommand, Checked, Backed, PeersPrepared)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* The correct nodes that follow views of one epoch agree on its master.
OneMasterPerEpochInv ==
    \A n, m \in Followers : view[n].epoch = view[m].epoch => view[n].master = view[m].master

\* No task runs on two correct nodes at once (a crashed node runs nothing).
NoDoubleActivationInv ==
    \A t \in Tasks, n, m \in Followers : (t \in active[n] /\ t \in active[m]) => n = m

\* Every view a correct node switched to passes the checker under the failed set it was
\* switched to, that failed set names only crashed nodes and the liar, and the node runs
\* only the tasks that view places on it.
ValidConfigInv ==
    \A n \in Followers :
        /\ Checked(view[n])
        /\ view[n].failed \subseteq failed \cup {Liar}
        /\ active[n] \subseteq TasksOn(view[n], n)

\* No correct node refuses a correct Master's Command: none declares a correct node failed.
NoHonestRefusalInv == \A n \in Followers : declared[n] \subseteq {Liar}
=============================================================================
