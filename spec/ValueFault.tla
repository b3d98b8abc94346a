------------------------------ MODULE ValueFault ------------------------------
(***************************************************************************)
(* HEADER                                                                  *)
(***************************************************************************)
EXTENDS Naturals, FiniteSets, Sequences

CONSTANTS
    Nodes,            \* every node: the processing nodes, the Storage node, interface nodes
    Priority,         \* the processing nodes in succession order; Priority[1] is the first
                      \*   Master, and Owner(e) the one node that may be Master in epoch e
    Storage,          \* the Storage node: keeps the checkpoints, owns no epoch
    Liar,             \* the value-faulty node (any node); every other node is correct
    Tasks,            \* the application tasks (all checkpointed)
    Essential,        \* the tasks safe mode runs, all on its view's master
    ConfigIds,        \* the configurations of the decision graph
    Safe,             \* the id of safe mode (not one of ConfigIds)
    BadConfig,        \* a configuration id beyond the mission's count (only on the wire)
    BadTask,          \* a task id beyond the mission's count (only on the wire)
    InitialConfig,    \* the configuration the cluster starts in
    ConfigMaster(_),  \* ConfigMaster(c): the master of configuration c
    Host(_, _),       \* Host(c, t): the node configuration c places task t on
    OnFailure(_, _),  \* OnFailure(c, f): the graph's edge from c when processing node f
                      \*   fails (a configuration, Safe, or c itself when f does not matter)
    OnPhase(_),       \* OnPhase(c): the configurations a planned phase change leads to
                      \*   from c (none from Safe)
    MaxEpoch,         \* the wire's epoch width: the largest epoch a message may carry
    MaxVersion,       \* the wire's version width: the largest checkpoint version
    MaxSeq,           \* the liar's switch numbers are at most this (a bound on the model)
    MaxPhaseChanges   \* at most this many planned switches

ProcessingNodes == {Priority[i] : i \in 1..Len(Priority)}
N == Len(Priority)

\* Where a view places a task of no configuration (a task safe mode does not run).
Unplaced == "unplaced"

ASSUME NodesAssumption ==
    /\ Cardinality(ProcessingNodes) = N /\ N >= 1
    /\ ProcessingNodes \subseteq Nodes
    /\ Storage \in Nodes \ ProcessingNodes
    /\ Liar \in Nodes
ASSUME ConfigAssumption ==
    /\ InitialConfig \in ConfigIds
    /\ {Safe, BadConfig} \cap ConfigIds = {} /\ Safe # BadConfig
    /\ BadTask \notin Tasks
    /\ Essential \subseteq Tasks
    /\ \A c \in ConfigIds :
          /\ ConfigMaster(c) \in ProcessingNodes
          /\ \A t \in Tasks : Host(c, t) \in ProcessingNodes \cup {Unplaced}
          /\ OnPhase(c) \subseteq ConfigIds
          /\ \A d \in OnPhase(c) : ConfigMaster(d) = ConfigMaster(c)
          /\ \A f \in ProcessingNodes :
                /\ OnFailure(c, f) \in ConfigIds \cup {Safe}
                \* An edge for another node's failure keeps the master.
                /\ (f # ConfigMaster(c) /\ OnFailure(c, f) # Safe)
                      => ConfigMaster(OnFailure(c, f)) = ConfigMaster(c)
    /\ OnPhase(Safe) = {}
ASSUME BudgetAssumption ==
    /\ {MaxEpoch, MaxVersion, MaxSeq, MaxPhaseChanges} \subseteq Nat
    /\ MaxEpoch >= 1

(***************************************************************************)
(* Views, epochs and the decision graph                                    *)
(***************************************************************************)

\* A view, as a Command carries it: its id <<epoch, seq>>, its configuration, its master
\* and the processing nodes it excludes.
Views == [epoch : Nat, seq : Nat, config : ConfigIds \cup {Safe, BadConfig},
          master : Nodes, failed : SUBSET ProcessingNodes]

\* The owner of epoch e >= 1, and a node's place in the succession.
Owner(e) == Priority[((e - 1) % N) + 1]
Rank(n) == CHOOSE i \in 1..N : Priority[i] = n

\* View v is newer than view w: the total order of switches.
Newer(v, w) == v.epoch > w.epoch \/ (v.epoch = w.epoch /\ v.seq > w.seq)

\* The node view v places task t on: safe mode runs the essential tasks on its master.
PlacedOn(v, t) ==
    IF v.config = Safe THEN IF t \in Essential THEN v.master ELSE Unplaced
    ELSE Host(v.config, t)
TasksOn(v, n) == {t \in Tasks : PlacedOn(v, t) = n}

\* The nodes the mission may ever place task t on: its host in any configuration and, for
\* an essential task, every node that may become Master (Topology::may_host).
MayHost(t) ==
    ({Host(c, t) : c \in ConfigIds} \ {Unplaced})
        \cup (IF t \in Essential THEN ProcessingNodes ELSE {})

\* The walk of the decision graph from c through the failed nodes F, in succession order,
\* one edge per failure (a failure that does not matter keeps the configuration); and the
\* configuration it ends in, or Safe when that one's master or a task's host is among
\* all, the view's failed nodes (Topology::walk).
RECURSIVE Walk(_, _)
Walk(c, F) ==
    IF F = {} \/ c = Safe THEN c
    ELSE LET f == CHOOSE x \in F : \A y \in F : Rank(x) <= Rank(y)
         IN  Walk(OnFailure(c, f), F \ {f})
Target(c, F, all) ==
    LET w == Walk(c, F)
    IN  IF w = Safe \/ ConfigMaster(w) \in all \/ \E t \in Tasks : Host(w, t) \in all
        THEN Safe ELSE w

\* Rule 3's structural validity: a configuration of the graph or Safe, whose master (out
\* of Safe) is the view's master, which the view does not exclude, nor any task's host.
Valid(v) ==
    /\ v.config \in ConfigIds \cup {Safe}
    /\ v.config # Safe => ConfigMaster(v.config) = v.master
    /\ v.master \notin v.failed
    /\ \A t \in Tasks : PlacedOn(v, t) \notin v.failed

(***************************************************************************)
(* What the liar may send. It sends any message its role's writers can     *)
(* carry, with any value the wire admits and some it does not, under its   *)
(* own identity, at any time: since the channel may delay, reorder and     *)
(* duplicate, its messages are taken to be on the wire from the start      *)
(* (a liar that waits to see what to send adds no behaviour: the channel   *)
(* can hold back any message it sent early). A Command carrying more than  *)
(* one defect (an epoch beyond the wire, an epoch the liar does not own, a *)
(* master other than the liar, a view that is not structurally valid) is   *)
(* left out: the rules drop it without evidence, as they drop one of its   *)
(* defects alone, so it adds no state.                                     *)
(***************************************************************************)
WireEpochs == 1..(MaxEpoch + 1)
WireVersions == 0..(MaxVersion + 1)
WireViews == [epoch : WireEpochs, seq : 1..MaxSeq, config : ConfigIds \cup {Safe, BadConfig},
              master : Nodes, failed : SUBSET ProcessingNodes]
Defects(v) ==
    (IF v.epoch <= MaxEpoch THEN 0 ELSE 1) + (IF Owner(v.epoch) = Liar THEN 0 ELSE 1)
        + (IF v.master = Liar THEN 0 ELSE 1) + (IF Valid(v) THEN 0 ELSE 1)
LiarCommands == {v \in WireViews : Defects(v) <= 1}
LiarActivates == [epoch : WireEpochs, seq : 0..MaxSeq]
LiarCheckpointAcks == [task : Tasks \cup {BadTask}, version : WireVersions]
LiarWrites == [from : {Liar}, task : Tasks \cup {BadTask}, version : WireVersions]

(***************************************************************************)
(* State                                                                   *)
(***************************************************************************)

\* The correct processing nodes: they follow views, run tasks, and may become Master.
Followers == ProcessingNodes \ {Liar}

VARIABLES
    view,          \* [Followers -> Views]: the view the node follows (the newest it adopted)
    stage,         \* [Followers -> Stages]: the node's progress in that view's switch
    active,        \* [Followers -> SUBSET Tasks]: tasks running on the node
    unflushed,     \* [Followers -> SUBSET Tasks]: stopped, final checkpoint not acknowledged
    version,       \* [Followers -> [Tasks -> WireVersions]]: the state of each task it holds
    fromLiar,      \* ghost [Followers -> [Tasks -> BOOLEAN]]: that state is the liar's
                   \*   (restored from its reply, or from a checkpoint it wrote)
    declared,      \* [Followers -> SUBSET Nodes]: nodes it declared failed on evidence (a
                   \*   Command it refused), for good
    masterStage,   \* [Followers -> MasterStages]: the switch the node drives as Master
    stored,        \* [Tasks -> WireVersions]: the Storage node's checkpoint (when correct)
    storedByLiar,  \* ghost [Tasks -> BOOLEAN]: that checkpoint is one the liar wrote
    honestStored,  \* ghost [Tasks -> WireVersions]: the newest version a correct node
                   \*   wrote that the Storage node took as its checkpoint
    msgs,          \* env: the correct Masters' Commands and Activates
    acks,          \* env: the correct nodes' "Prepared" and "Activated" acks
    writes,        \* env: the correct nodes' final checkpoint writes
    phaseChanges   \* planned switches so far

vars == <<view, stage, active, unflushed, version, fromLiar, declared, masterStage,
          stored, storedByLiar, honestStored, msgs, acks, writes, phaseChanges>>

Stages == {"Stable", "Deactivating", "Prepared", "Activating"}
MasterStages == {"Idle", "Preparing", "Activating"}

InitialView == [epoch |-> 1, seq |-> 0, config |-> InitialConfig, master |-> Priority[1],
                failed |-> {}]

IsMaster(n) == view[n].master = n

CommandMsg(m, v) == [kind |-> "Command", from |-> m, view |-> v]
ActivateMsg(m, v) == [kind |-> "Activate", from |-> m, epoch |-> v.epoch, seq |-> v.seq]
AckMsg(k, n, v) == [kind |-> k, from |-> n, epoch |-> v.epoch, seq |-> v.seq]

TypeOK ==
    /\ view \in [Followers -> Views]
    /\ stage \in [Followers -> Stages]
    /\ active \in [Followers -> SUBSET Tasks]
    /\ unflushed \in [Followers -> SUBSET Tasks]
    /\ version \in [Followers -> [Tasks -> WireVersions]]
    /\ fromLiar \in [Followers -> [Tasks -> BOOLEAN]]
    /\ declared \in [Followers -> SUBSET Nodes]
    /\ masterStage \in [Followers -> MasterStages]
    /\ stored \in [Tasks -> WireVersions]
    /\ storedByLiar \in [Tasks -> BOOLEAN]
    /\ honestStored \in [Tasks -> WireVersions]
    /\ writes \subseteq [from : Followers, task : Tasks, version : WireVersions]
    /\ phaseChanges \in 0..MaxPhaseChanges

\* The cluster runs the initial configuration: every node follows the initial view, each
\* task runs on its host there from version 0.
Init ==
    /\ view = [n \in Followers |-> InitialView]
    /\ stage = [n \in Followers |-> "Stable"]
    /\ active = [n \in Followers |-> TasksOn(InitialView, n)]
    /\ unflushed = [n \in Followers |-> {}]
    /\ version = [n \in Followers |-> [t \in Tasks |-> 0]]
    /\ fromLiar = [n \in Followers |-> [t \in Tasks |-> FALSE]]
    /\ declared = [n \in Followers |-> {}]
    /\ masterStage = [n \in Followers |-> "Idle"]
    /\ stored = [t \in Tasks |-> 0]
    /\ storedByLiar = [t \in Tasks |-> FALSE]
    /\ honestStored = [t \in Tasks |-> 0]
    /\ msgs = {}
    /\ acks = {}
    /\ writes = {}
    /\ phaseChanges = 0

(***************************************************************************)
(* The receiver rules, one operator each, so that a mutant removes one     *)
(* (NextBy takes them as parameters).                                      *)
(***************************************************************************)

\* Rule 1, bounds: an epoch the wire's width carries, a version within its width. (Ids are
\* checked too, by the actions: a configuration or task id beyond the mission's count is
\* dropped; without that check a receiver would index past its tables.)
EpochInBounds(e) == e \in 1..MaxEpoch
VersionInBounds(v) == v \in 0..MaxVersion

\* Rule 2, authority by role, decided in the receiver's own view:
\* a Command's view comes from its master, the owner of its epoch, which is not stale and
\* at most one lap of the succession above the receiver's epoch;
MayCommand(n, s, v) ==
    /\ s = v.master
    /\ Owner(v.epoch) = s
    /\ view[n].epoch <= v.epoch
    /\ v.epoch <= view[n].epoch + N
\* an Activate comes from the master of the receiver's view;
MayActivate(n, s) == s = view[n].master
\* a checkpoint acknowledgement from the Storage node;
MayAck(s) == s = Storage
\* a restore reply from the Storage node or a node the mission may place the task on;
MayReply(s, t) == s = Storage \/ s \in MayHost(t)
\* the Storage node stores a write only from a node the mission may place the task on.
MayWrite(s, t) == s \in MayHost(t)

\* Rule 3, receivers check the Master: the view is structurally valid, and the next switch
\* of the receiver's own view follows the graph's edge for the nodes it adds to the failed
\* set (Walk), or a phase edge with the same failed set.
IsNextSwitch(n, v) == v.epoch = view[n].epoch /\ v.seq = view[n].seq + 1
OnEdge(n, v) ==
    IsNextSwitch(n, v) =>
        \/ /\ view[n].failed \subseteq v.failed /\ view[n].failed # v.failed
           /\ v.config = Target(view[n].config, v.failed \ view[n].failed, v.failed)
        \/ /\ v.failed = view[n].failed
           /\ v.config \in OnPhase(view[n].config)
Checked(n, v) == Valid(v) /\ OnEdge(n, v)

(***************************************************************************)
(* Receivers                                                               *)
(***************************************************************************)

\* Node n takes a Command from s whose view v is in bounds, comes with authority and is
\* newer than its own view: if v passes the checks, n adopts it (a Master of an older view
\* steps down) and starts the switch.
ReceiveCommand(EpochOk(_), MayCommandOp(_, _, _), CheckedOp(_, _), n, s, v) ==
    /\ EpochOk(v.epoch) /\ v.config \in ConfigIds \cup {Safe}
    /\ MayCommandOp(n, s, v)
    /\ Newer(v, view[n])
    /\ CheckedOp(n, v)
    /\ view' = [view EXCEPT ![n] = v]
    /\ stage' = [stage EXCEPT ![n] = "Deactivating"]
    /\ masterStage' = [masterStage EXCEPT ![n] = "Idle"]
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, stored, storedByLiar,
                   honestStored, msgs, acks, writes, phaseChanges>>

\* ... if v fails the checks, n refuses it and declares s failed, for good: the refused
\* Command is evidence against its sender (a declaration no later message withdraws).
RefuseCommand(EpochOk(_), MayCommandOp(_, _, _), CheckedOp(_, _), n, s, v) ==
    /\ EpochOk(v.epoch) /\ v.config \in ConfigIds \cup {Safe}
    /\ MayCommandOp(n, s, v)
    /\ Newer(v, view[n])
    /\ ~CheckedOp(n, v)
    /\ s \notin declared[n]
    /\ declared' = [declared EXCEPT ![n] = @ \cup {s}]
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, writes, phaseChanges>>

\* Node n stops task t, which its view places elsewhere, and sends its final checkpoint.
Deactivate(n, t) ==
    /\ stage[n] = "Deactivating"
    /\ t \in active[n]
    /\ PlacedOn(view[n], t) # n
    /\ active' = [active EXCEPT ![n] = @ \ {t}]
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \cup {t}]
    /\ writes' = writes \cup {[from |-> n, task |-> t, version |-> version[n][t]]}
    /\ UNCHANGED <<view, stage, version, fromLiar, declared, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, phaseChanges>>

\* The Storage node takes write w as its checkpoint when it is in bounds, from a writer
\* with authority, and newer than the one it holds (the newest is kept).
StoreWrite(VersionOk(_), MayWriteOp(_, _), w) ==
    /\ Storage # Liar
    /\ w.task \in Tasks
    /\ VersionOk(w.version)
    /\ MayWriteOp(w.from, w.task)
    /\ IF w.version > stored[w.task]
       THEN /\ stored' = [stored EXCEPT ![w.task] = w.version]
            /\ storedByLiar' = [storedByLiar EXCEPT ![w.task] = (w.from = Liar)]
            /\ honestStored' = IF w.from = Liar THEN honestStored
                               ELSE [honestStored EXCEPT ![w.task] = w.version]
       ELSE UNCHANGED <<stored, storedByLiar, honestStored>>

\* The correct Storage node receives n's final checkpoint of t and acknowledges it (one
\* step: the acknowledgement carries the version it holds, at least n's).
FlushCheckpoint(VersionOk(_), MayWriteOp(_, _), n, t) ==
    /\ t \in unflushed[n]
    /\ StoreWrite(VersionOk, MayWriteOp, [from |-> n, task |-> t, version |-> version[n][t]])
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \ {t}]
    /\ UNCHANGED <<view, stage, active, version, fromLiar, declared, masterStage, msgs, acks,
                   writes, phaseChanges>>

\* The Storage node receives a write again (the channel duplicates), or one whose
\* acknowledgement its writer took from elsewhere, or one of the liar's.
StoreCheckpoint(VersionOk(_), MayWriteOp(_, _), w) ==
    /\ StoreWrite(VersionOk, MayWriteOp, w)
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, declared, masterStage,
                   msgs, acks, writes, phaseChanges>>

\* Node n takes an acknowledgement from s of its final checkpoint of t, for version v (an
\* acknowledgement below n's version is one of an older write).
ReceiveCheckpointAck(VersionOk(_), MayAckOp(_), n, s, t, v) ==
    /\ t \in Tasks
    /\ VersionOk(v)
    /\ MayAckOp(s)
    /\ t \in unflushed[n]
    /\ v >= version[n][t]
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \ {t}]
    /\ UNCHANGED <<view, stage, active, version, fromLiar, declared, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, writes, phaseChanges>>

\* Every task leaving n is stopped and acknowledged (phase 1 done), or every task placed
\* on n runs (phase 2 done): n acks.
ReadyToAck(n, kind) ==
    IF kind = "Prepared"
    THEN /\ stage[n] = "Deactivating"
         /\ \A t \in active[n] : PlacedOn(view[n], t) = n
         /\ unflushed[n] = {}
    ELSE /\ stage[n] = "Activating"
         /\ TasksOn(view[n], n) \subseteq active[n]

Ack(n, kind) ==
    /\ ReadyToAck(n, kind)
    /\ stage' = [stage EXCEPT ![n] = IF kind = "Prepared" THEN "Prepared" ELSE "Stable"]
    /\ acks' = acks \cup {AckMsg(kind, n, view[n])}
    /\ UNCHANGED <<view, active, unflushed, version, fromLiar, declared, masterStage, stored,
                   storedByLiar, honestStored, msgs, writes, phaseChanges>>

\* Node n takes the Activate of its view's switch from s.
ReceiveActivate(EpochOk(_), MayActivateOp(_, _), n, s, e, q) ==
    /\ stage[n] = "Prepared"
    /\ EpochOk(e)
    /\ MayActivateOp(n, s)
    /\ e = view[n].epoch /\ q = view[n].seq
    /\ stage' = [stage EXCEPT ![n] = "Activating"]
    /\ UNCHANGED <<view, active, unflushed, version, fromLiar, declared, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, writes, phaseChanges>>

\* Node n starts task t, which its view places on it, from s's restore reply for its
\* view's switch, carrying version v.
Activate(VersionOk(_), MayReplyOp(_, _), n, t, s, v) ==
    /\ stage[n] = "Activating"
    /\ PlacedOn(view[n], t) = n
    /\ t \notin active[n]
    /\ VersionOk(v)
    /\ MayReplyOp(s, t)
    /\ active' = [active EXCEPT ![n] = @ \cup {t}]
    /\ version' = [version EXCEPT ![n][t] = v]
    /\ fromLiar' = [fromLiar EXCEPT ![n][t] = IF s = Liar THEN TRUE ELSE storedByLiar[t]]
    /\ UNCHANGED <<view, stage, unflushed, declared, masterStage, stored, storedByLiar,
                   honestStored, msgs, acks, writes, phaseChanges>>

(***************************************************************************)
(* Masters (correct ones)                                                  *)
(***************************************************************************)

\* Master m starts the switch to view v: it broadcasts the Command and applies it at once.
StartSwitch(m, v) ==
    /\ view' = [view EXCEPT ![m] = v]
    /\ stage' = [stage EXCEPT ![m] = "Deactivating"]
    /\ masterStage' = [masterStage EXCEPT ![m] = "Preparing"]
    /\ msgs' = msgs \cup {CommandMsg(m, v)}

\* Master m declared f failed on evidence: it switches along the graph's edge.
DeclareFailed(m, f) ==
    /\ IsMaster(m)
    /\ f \in declared[m] \ view[m].failed
    /\ f \in ProcessingNodes
    /\ LET F == view[m].failed \cup {f}
       IN  StartSwitch(m, [epoch |-> view[m].epoch, seq |-> view[m].seq + 1,
                           config |-> Target(view[m].config, {f}, F), master |-> m,
                           failed |-> F])
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, stored, storedByLiar,
                   honestStored, acks, writes, phaseChanges>>

\* Master m starts a planned switch to c (a mission-phase change), between switches.
RequestPhase(m, c) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Idle"
    /\ phaseChanges < MaxPhaseChanges
    /\ c \in OnPhase(view[m].config)
    /\ phaseChanges' = phaseChanges + 1
    /\ StartSwitch(m, [view[m] EXCEPT !.seq = @ + 1, !.config = c])
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, stored, storedByLiar,
                   honestStored, acks, writes>>

\* Every correct node the view does not exclude acked kind for m's switch (the liar, if
\* the view does not exclude it, may ack anything at any time: its acks are taken as sent).
AllAcked(m, kind) ==
    \A n \in Followers \ view[m].failed : AckMsg(kind, n, view[m]) \in acks

BroadcastActivate(m) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Preparing"
    /\ AllAcked(m, "Prepared")
    /\ masterStage' = [masterStage EXCEPT ![m] = "Activating"]
    /\ msgs' = msgs \cup {ActivateMsg(m, view[m])}
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, declared, stored,
                   storedByLiar, honestStored, acks, writes, phaseChanges>>

CompleteSwitch(m) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Activating"
    /\ AllAcked(m, "Activated")
    /\ masterStage' = [masterStage EXCEPT ![m] = "Idle"]
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, declared, stored,
                   storedByLiar, honestStored, msgs, acks, writes, phaseChanges>>

\* The first epoch after n's that n owns, and the owners of the epochs in between.
NextEpoch(n) ==
    LET e == view[n].epoch IN e + 1 + ((Rank(n) - ((e % N) + 1)) % N)
Ahead(n) == {Owner(e) : e \in (view[n].epoch + 1)..(NextEpoch(n) - 1)} \ {n}

\* Node n takes over (MasterElection's BecomeMaster): it declared the master of its view
\* and every owner of the epochs before its next one. It claims that epoch, if the wire
\* carries it, and switches to the graph's configuration without them (Safe if that one's
\* master is another node).
BecomeMaster(n) ==
    /\ ~IsMaster(n)
    /\ n \notin view[n].failed
    /\ view[n].master \in declared[n]
    /\ Ahead(n) \subseteq declared[n]
    /\ NextEpoch(n) <= MaxEpoch
    /\ LET F == view[n].failed \cup {view[n].master} \cup Ahead(n)
           w == Target(view[n].config, F \ view[n].failed, F)
       IN  StartSwitch(n, [epoch |-> NextEpoch(n), seq |-> 1,
                           config |-> IF w # Safe /\ ConfigMaster(w) = n THEN w ELSE Safe,
                           master |-> n, failed |-> F])
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, stored, storedByLiar,
                   honestStored, acks, writes, phaseChanges>>

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* Task t runs one step on n.
Execute(n, t) ==
    /\ t \in active[n]
    /\ version[n][t] < MaxVersion
    /\ version' = [version EXCEPT ![n][t] = @ + 1]
    /\ UNCHANGED <<view, stage, active, unflushed, fromLiar, declared, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, writes, phaseChanges>>

(***************************************************************************)
(* Next-state relation                                                     *)
(***************************************************************************)

\* Every Command on the wire, as <<sender, view>>: the correct Masters' and the liar's.
Commands == {<<msg.from, msg.view>> : msg \in {x \in msgs : x.kind = "Command"}}
                \cup {<<Liar, v>> : v \in LiarCommands}
Activates == {<<msg.from, msg.epoch, msg.seq>> : msg \in {x \in msgs : x.kind = "Activate"}}
                \cup {<<Liar, a.epoch, a.seq>> : a \in LiarActivates}

NextBy(EpochOk(_), VersionOk(_), MayCommandOp(_, _, _), CheckedOp(_, _),
       MayActivateOp(_, _), MayAckOp(_), MayReplyOp(_, _), MayWriteOp(_, _)) ==
    \/ \E n \in Followers, c \in Commands :
          \/ ReceiveCommand(EpochOk, MayCommandOp, CheckedOp, n, c[1], c[2])
          \/ RefuseCommand(EpochOk, MayCommandOp, CheckedOp, n, c[1], c[2])
    \/ \E n \in Followers, a \in Activates :
          ReceiveActivate(EpochOk, MayActivateOp, n, a[1], a[2], a[3])
    \/ \E n \in Followers, t \in Tasks : Deactivate(n, t)
    \/ \E n \in Followers, t \in Tasks : FlushCheckpoint(VersionOk, MayWriteOp, n, t)
    \/ \E w \in writes \cup LiarWrites : StoreCheckpoint(VersionOk, MayWriteOp, w)
    \/ \E n \in Followers, a \in LiarCheckpointAcks :
          ReceiveCheckpointAck(VersionOk, MayAckOp, n, Liar, a.task, a.version)
    \/ \E n \in Followers, k \in {"Prepared", "Activated"} : Ack(n, k)
    \/ \E n \in Followers, t \in Tasks :
          \/ Storage # Liar /\ Activate(VersionOk, MayReplyOp, n, t, Storage, stored[t])
          \/ \E v \in WireVersions : Activate(VersionOk, MayReplyOp, n, t, Liar, v)
    \/ \E m \in Followers, f \in Nodes : DeclareFailed(m, f)
    \/ \E m \in Followers, c \in ConfigIds : RequestPhase(m, c)
    \/ \E m \in Followers : BroadcastActivate(m)
    \/ \E m \in Followers : CompleteSwitch(m)
    \/ \E n \in Followers : BecomeMaster(n)
    \/ \E n \in Followers, t \in Tasks : Execute(n, t)

Next == NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked, MayActivate, MayAck,
               MayReply, MayWrite)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* (a) The correct nodes that follow views of one epoch agree on its master: no two nodes
\* run as Master in one epoch, nor in one view.
OneMasterPerEpochInv ==
    \A n, m \in Followers : view[n].epoch = view[m].epoch => view[n].master = view[m].master

\* (b) No task runs on two correct nodes at once.
NoDoubleActivationInv ==
    \A t \in Tasks, n, m \in Followers : (t \in active[n] /\ t \in active[m]) => n = m

\* (c) Every correct node follows a structurally valid view of the graph (or Safe), and
\* out of a switch's first phase runs only the tasks that view places on it.
ValidConfigInv ==
    \A n \in Followers :
        /\ Valid(view[n])
        /\ stage[n] # "Deactivating" => active[n] \subseteq TasksOn(view[n], n)

\* (d) With a correct Storage node, no correct node runs a task below the newest version a
\* correct node wrote and the Storage node took (no regression) ...
NoRegressionInv ==
    Storage # Liar =>
        \A n \in Followers, t \in Tasks : t \in active[n] => version[n][t] >= honestStored[t]

\* ... nor from a state the liar made, unless the mission may place the task on the liar
\* (a state within its own authority, which fault model 3 does not cover).
NoForeignStateInv ==
    Storage # Liar =>
        \A n \in Followers, t \in Tasks :
            (t \in active[n] /\ fromLiar[n][t]) => Liar \in MayHost(t)

\* (e) No correct node's epoch exceeds the wire's width; nor does a version it runs or the
\* correct Storage node holds.
EpochBoundInv == \A n \in Followers : view[n].epoch <= MaxEpoch
VersionBoundInv ==
    /\ \A n \in Followers, t \in Tasks : version[n][t] <= MaxVersion
    /\ Storage # Liar => \A t \in Tasks : stored[t] <= MaxVersion

=============================================================================
