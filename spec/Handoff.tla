------------------------------- MODULE Handoff -------------------------------
(***************************************************************************)
(* State without the Storage node (fault model 2, item 4: no silent state  *)
(* loss).                                                                  *)
(*                                                                         *)
(* ConfigSwitch.tla takes the Storage node to be reliable: a node that     *)
(* deactivates a task flushes its final checkpoint there before it acks    *)
(* "Prepared", and the task's new host starts it from `stored`. Here the   *)
(* Storage node fails (crashes, or is paused) and the Master declares it   *)
(* failed like any node: the decision graph switches to a configuration    *)
(* whose view excludes it. What the nodes then do:                         *)
(*  - Hand-off. A node that deactivates a task while it is a member of its *)
(*    view (its view does not exclude it) keeps the task's state and       *)
(*    version: it holds a hand-off of the task (`handoff`) until it        *)
(*    activates the task again. With the Storage node excluded in its view *)
(*    it flushes nothing (there is nothing to flush to) and may ack        *)
(*    "Prepared" at once; the hand-off is unstored (`unstored`). A node    *)
(*    that adopts a view excluding the Storage node drops its pending      *)
(*    final flushes (nothing can take them), and the hand-offs they        *)
(*    carried become unstored too.                                         *)
(*  - Flush on return. A node that adopts a view which includes the        *)
(*    Storage node sends it a final checkpoint of each unstored hand-off   *)
(*    and acks "Prepared" only once the Storage node has acknowledged them *)
(*    (they join `unflushed`): whoever starts the task next from the       *)
(*    Storage node (after a readmission, or under a Master whose view      *)
(*    predates the exclusion) reads them. The acknowledgement, or          *)
(*    activating the task on the node, clears a hand-off's unstored mark.  *)
(*  - Fenced out. A node that deactivates a task because its view excludes *)
(*    the node itself holds no hand-off of it, and a node that adopts a    *)
(*    view excluding itself drops all its hand-offs: its lineage of a task *)
(*    may be one the cluster abandoned.                                    *)
(*  - Gathering. The new host of a task, at Activate, when its view        *)
(*    excludes the Storage node, asks every other member of its view for   *)
(*    its hand-off (AskHolders), waits for all of them, and starts from    *)
(*    the newest hand-off, its own included. A member answers "found" only *)
(*    for a hand-off it holds of a task it is not running; a node excluded *)
(*    by its own view answers nothing. The gathering is one step here: it  *)
(*    reads the hand-offs of the members that answer (alive, not excluded  *)
(*    by their own view) at once, as the runtime's answers would give them *)
(*    (a hand-off changes only when its holder activates or deactivates    *)
(*    the task, which it cannot do while another node activates it). The   *)
(*    runtime waits for a member that never answers (a crashed one) until  *)
(*    a newer switch; here the activation may go on without it, which only *)
(*    adds behaviours.                                                     *)
(*  - Unrecoverable start. If no member holds a hand-off, the new host     *)
(*    starts the task from version 0. When the view the host left placed   *)
(*    the task (it was not the initial view: the task has run) and either  *)
(*    no member held a hand-off or the node that view placed the task on   *)
(*    is excluded now (what it ran since its last hand-off is gone), the   *)
(*    start is an unrecoverable start: the task's newest state is out of   *)
(*    reach (on the excluded Storage node, on crashed nodes), and the host *)
(*    reports it (StateOutOfReach, with the version it starts from) and    *)
(*    counts it (`unrecoverable`).                                         *)
(*  - Lineages. A start without the Storage node may abandon the task's   *)
(*    newest state, which may still be on the Storage node (out of reach,  *)
(*    not lost): an unrecoverable start does, and so does a start from a   *)
(*    hand-off when the node that ran the task after that hand-off is gone *)
(*    more than one view back (the runtime cannot tell: see                *)
(*    LossReportedInv). So every start without the Storage node but from   *)
(*    nothing in the initial view opens a new lineage of the task, named   *)
(*    by the starting node's view (<<epoch, seq>>, the total order of      *)
(*    switches), and a state is its lineage and its count of steps,        *)
(*    compared lineage first. The Storage node keeps the newest state in   *)
(*    that order, so the lineage the cluster went on with replaces the     *)
(*    abandoned one however many steps that one had run, and a start from  *)
(*    the Storage node never restores an abandoned lineage. (Compared by   *)
(*    counts alone, TLC finds it in MCHandoffLineage: PN3 runs t1 to       *)
(*    version 1, stored, and crashes; the Storage node is paused and       *)
(*    excluded; PN1 starts t1 from PN2's older hand-off, version 0; the    *)
(*    Storage node is readmitted, keeps its version 1, and PN1 runs t1     *)
(*    below it: mutant HandoffVersionsByCount.) A start from the Storage   *)
(*    node keeps the stored state's lineage.                               *)
(*  - With the Storage node in its view, a node does what ConfigSwitch     *)
(*    says: the final flush before "Prepared", the start from `stored`,    *)
(*    both waiting while the Storage node is down and not yet declared.    *)
(*  - Checkpoints between switches are modelled here (ConfigSwitch leaves  *)
(*    them out): each Execute writes the task's new version to the Storage *)
(*    node when the running node's view includes it and it is up. What the *)
(*    Storage node holds when it is excluded is then what is out of reach. *)
(*  - The Storage node keeps the newest version it is sent                 *)
(*    (CheckpointStore::receive_write), also while it is down: when it     *)
(*    runs again (a pause ends, a restart; if StorageReturns) it holds     *)
(*    what it stored. The Master may readmit it (at most MaxReadmissions   *)
(*    times): a switch to OnReadmit(c, Storage), whose view includes it    *)
(*    again; checkpoint writes then resume.                                *)
(*                                                                         *)
(* The module EXTENDS ConfigSwitch: the Master's steps, the acks, the      *)
(* Activate broadcast, the take-over, crashes and late boots are           *)
(* ConfigSwitch's actions, each conjoined with what it leaves of the new   *)
(* variables. The steps the Storage node's exclusion changes are written   *)
(* anew, since ConfigSwitch's actions fix their UNCHANGED lists and a      *)
(* conjunction cannot change what they keep: ReceiveCommand (a view that   *)
(* excludes the Storage node drops the pending flushes, their hand-offs    *)
(* becoming unstored, one that includes it queues the unstored hand-offs,  *)
(* one that excludes the node drops its hand-offs), Deactivate (the        *)
(* hand-off; the flush only with the Storage node), FlushCheckpoint (only  *)
(* to a Storage node in the view and up), Activate (the gathering) and     *)
(* Execute (the checkpoint write); the Master's own switches do what       *)
(* ReceiveCommand does: DeclareStorageFailed makes its pending flushes'    *)
(* hand-offs unstored, ReadmitStorage queues its unstored hand-offs (its   *)
(* other switches do not change whether its view excludes the Storage      *)
(* node). The view's failed set, which the C++ View carries and            *)
(* ConfigSwitch keeps inside its configuration ids, is the constant        *)
(* ViewFailed(c).                                                          *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - NoDoubleActivationInv (ConfigSwitch's).                              *)
(*  - NoStateLossInv: a task never starts below the newest state within    *)
(*    its new host's reach: the hand-off of any alive member of the host's *)
(*    view, and `stored` when that view includes the Storage node.         *)
(*  - UnrecoverableReportedInv: a start from nothing that is not reported  *)
(*    loses nothing (no state of the task had been saved).                 *)
(*  - LossReportedInv (not checked in CI, see below): a task starts below  *)
(*    the newest state saved for it (a checkpoint the Storage node took,   *)
(*    or a hand-off made in its place while it was excluded, since the     *)
(*    task's last unrecoverable start) only by an unrecoverable start.     *)
(*  - HResumeLatestCheckpointInv: ConfigSwitch's ResumeLatestCheckpointInv *)
(*    for the nodes whose view includes the Storage node.                  *)
(*  - StoredMonotoneProp: what the Storage node holds never falls.         *)
(*  - SwitchConverges (ConfigSwitch's), under HFairness.                   *)
(* The properties of starts read ghost variables: `start` keeps each       *)
(* task's last start (its version, the newest state within reach, the      *)
(* newest saved, where the state came from), `saved` the newest state      *)
(* saved for each task.                                                    *)
(*                                                                         *)
(* Without the flush on return, TLC finds starts from the Storage node     *)
(* below a hand-off, where a view that includes the Storage node follows   *)
(* one that excluded it: after a take-over by a Master whose view predates *)
(* the exclusion (MCHandoffReturn: t1 runs on PN3 after the phase change;  *)
(* the Storage node's exclusion moves it to PN1, PN3 holding version 1 as  *)
(* a hand-off; PN1 crashes and PN2, which had not adopted the exclusion,   *)
(* takes over from its own view and puts t1 back on PN3, which starts it   *)
(* from the Storage node at version 0: mutant HandoffNotFlushedOnReturn),  *)
(* and after a readmission. Without the rule that a dropped final flush    *)
(* leaves its hand-off unstored, the readmission case remains              *)
(* (MCHandoffReadmit: mutant HandoffPendingFlushLost): after the phase     *)
(* change PN2 still runs t1 (P2 places it on PN3) and the Storage node is  *)
(* paused, not yet declared; PN1 declares it; PN2 runs t1 to version 1     *)
(* (written nowhere: the Storage node is down), deactivates it with the    *)
(* Storage node still in its view (a hand-off, its final flush pending),   *)
(* then adopts the exclusion, which drops the pending flush; the Storage   *)
(* node runs again and is readmitted, PN2 has nothing unstored to flush,   *)
(* and PN3 starts t1 from the Storage node at version 0. With both rules   *)
(* TLC finds no violation in MCHandoffReturn and MCHandoffReadmit.         *)
(* The fenced-out rule changes no behaviour of these models: the Master    *)
(* declares only a node that is down, a crashed node never runs again (its *)
(* hand-offs die with it), and a node that boots late, in a view that      *)
(* excludes it, has held nothing.                                          *)
(* LossReportedInv does not hold in MCHandoff itself: after the phase      *)
(* change PN2 holds a hand-off of t1 at version 0; PN3 runs t1 to version  *)
(* 1, which the Storage node takes, and crashes; the Master's switch for   *)
(* PN3's failure places t1 on PN1, and before PN1 has started it the       *)
(* Storage node fails and is excluded; PN1 starts t1 from PN2's hand-off   *)
(* at version 0. That start is below a saved state and is not counted:     *)
(* the view PN1 left placed t1 on PN1 itself, and that the node which      *)
(* last ran it is excluded is seen one view back only (host_lost_).        *)
(* UnrecoverableReportedInv, which holds, is what the runtime does         *)
(* report: every start from nothing of a task that had a saved state.      *)
(***************************************************************************)
EXTENDS ConfigSwitch

CONSTANTS
    ViewFailed(_),    \* ViewFailed(c): the nodes view c excludes (the Storage node too)
    OnReadmit(_, _),  \* OnReadmit(c, x): the configuration after c when x is readmitted
    MaxStorageFaults, \* environment: the Storage node fails at most this many times
    StorageReturns,   \* environment: whether a failed Storage node may run again
    MaxReadmissions   \* the Master readmits the Storage node at most this many times

ASSUME HandoffConfigAssumption ==
    /\ \A c \in ConfigIds : ViewFailed(c) \subseteq Nodes \cup {Storage}
    /\ \A c \in ConfigIds, t \in Tasks : Placement(c, t) \notin ViewFailed(c)
    /\ \A c \in ConfigIds, f \in Nodes \cup {Storage} : f \in ViewFailed(OnFailure(c, f))
    \* Only the Storage node's own declaration and readmission change whether a view
    \* excludes it.
    /\ \A c \in ConfigIds, f \in Nodes :
          (Storage \in ViewFailed(OnFailure(c, f))) = (Storage \in ViewFailed(c))
    /\ \A c \in ConfigIds : \A d \in OnPhase(c) :
          (Storage \in ViewFailed(d)) = (Storage \in ViewFailed(c))
    /\ \A c \in ConfigIds :
          /\ OnReadmit(c, Storage) \in ConfigIds
          /\ Storage \notin ViewFailed(OnReadmit(c, Storage))
ASSUME HandoffBudgetAssumption ==
    /\ {MaxStorageFaults, MaxReadmissions} \subseteq Nat
    /\ StorageReturns \in BOOLEAN

VARIABLES
    handoff,       \* [Nodes -> SUBSET Tasks]: tasks n handed off (state: version[n][t])
    lineage,       \* [Nodes -> [Tasks -> Lineages]]: the lineage of n's version of t
    storedLineage, \* [Tasks -> Lineages]: the lineage of the Storage node's checkpoint
    unstored,      \* [Nodes -> SUBSET Tasks]: hand-offs n made while its view excluded
                   \*   the Storage node, not yet acknowledged by it (the runtime's
                   \*   unstored_)
    storageUp,     \* env: BOOLEAN, the Storage node runs
    placedBefore,  \* [Nodes -> BOOLEAN]: the view n left for its current one placed the
                   \*   tasks (it was not the initial view)
    hostLost,      \* [Nodes -> SUBSET Tasks]: tasks that view placed on another node,
                   \*   one n's current view excludes
    storageFaults, \* env: number of Storage node failures so far
    readmissions,  \* number of readmissions of the Storage node so far
    unrecoverable, \* Nat: unrecoverable starts so far (unrecoverable_starts())
    start,         \* ghost: [Tasks -> StartRecord], each task's last start
    saved          \* ghost: [Tasks -> 0..MaxVersion], newest state saved for the task
                   \*   (see LossReportedInv)

handoffVars == <<handoff, lineage, storedLineage, unstored, storageUp, placedBefore, hostLost, storageFaults,
                 readmissions, unrecoverable, start, saved>>
everything == <<vars, handoffVars>>

\* How a task's last start got its state: from the Storage node, from another node's
\* hand-off, from the starting node's own hand-off, from nothing (afresh, not counted),
\* from nothing as an unrecoverable start; "Never": not started yet.
Sources == {"Storage", "Holder", "Own", "Afresh", "Lost", "Never"}
\* A state of a task: its lineage (a switch id <<epoch, seq>>, <<0, 0>> the initial one)
\* and its count of steps, as the triple <<epoch, seq, count>>, ordered lexicographically.
Lineages == Nat \X Nat
InitialLineage == <<0, 0>>
States == Nat \X Nat \X (0..MaxVersion)
Zero == <<0, 0, 0>>
State(l, c) == <<l[1], l[2], c>>
StateOf(n, t) == State(lineage[n][t], version[n][t])
StoredOf(t) == State(storedLineage[t], stored[t])
Geq(a, b) ==
    \/ a[1] > b[1]
    \/ a[1] = b[1] /\ a[2] > b[2]
    \/ a[1] = b[1] /\ a[2] = b[2] /\ a[3] >= b[3]
Gt(a, b) == Geq(a, b) /\ a # b
Newest(S) == CHOOSE x \in S : \A y \in S : Geq(x, y)

StartRecords == [version : States, reach : States, saved : States, opened : Lineages,
                 how : Sources]
NeverStarted == [version |-> Zero, reach |-> Zero, saved |-> Zero,
                 opened |-> InitialLineage, how |-> "Never"]


\* Whether node n's view includes the Storage node, and n itself.
StorageAvailable(n) == Storage \notin ViewFailed(config[n])
Member(n) == n \notin ViewFailed(config[n])
\* A checkpoint write from n reaches the Storage node.
Writable(n) == StorageAvailable(n) /\ storageUp
\* The Storage node keeps the newest state it is sent, lineage first, then count:
\* whether it takes state w of task t. (A parameter of the steps that write to it, for the
\* mutant that compares counts alone.)
StoresNewest(w, t) == Gt(w, StoredOf(t))
\* The Storage node is sent state w of task t: it keeps it if Takes(w, t).
StoreState(t, w, Takes(_, _)) ==
    /\ stored' = IF Takes(w, t) THEN [stored EXCEPT ![t] = w[3]] ELSE stored
    /\ storedLineage' = IF Takes(w, t) THEN [storedLineage EXCEPT ![t] = <<w[1], w[2]>>]
                        ELSE storedLineage

\* Node x answers a gathering (it runs and its own view does not exclude it).
Answers(x) == alive[x] /\ Member(x)
\* The members of n's view that answer "found" for t: they hold a hand-off of t and do not
\* run it. n is one of them when it holds a hand-off of t itself.
Holders(n, t) ==
    {x \in Nodes : x \notin ViewFailed(config[n]) /\ Answers(x)
                   /\ t \in handoff[x] /\ t \notin active[x]}

\* The newest state of t within n's reach: the hand-off of every alive member of n's view,
\* and the Storage node's checkpoint if n's view includes it.
Reach(n, t) ==
    Newest({StateOf(x, t) : x \in {y \in Nodes : alive[y] /\ y \notin ViewFailed(config[n])
                                                /\ t \in handoff[y]}}
           \cup (IF StorageAvailable(n) THEN {StoredOf(t)} ELSE {})
           \cup {Zero})

\* The view n is leaving placed every task unless it is the initial view (epoch 1, seq 0):
\* the runtime's placed_before_, computed when a node adopts a newer view.
LeftPlaced(n) == epoch[n] > 1 \/ seq[n] > 0

\* Conjoined, last, with every step that may change a node's switch id (a Command
\* received, a Master's own switch): a node that moves to a newer view records whether
\* the one it left placed the tasks, and which of them it placed on another node that
\* the new view excludes (the runtime's host_lost_).
Adopts(n) == epoch'[n] # epoch[n] \/ seq'[n] # seq[n]
TrackPlaced ==
    /\ placedBefore' = [n \in Nodes |->
                          IF Adopts(n) THEN LeftPlaced(n) ELSE placedBefore[n]]
    /\ hostLost' = [n \in Nodes |->
                      IF ~Adopts(n) THEN hostLost[n]
                      ELSE IF ~LeftPlaced(n) THEN {}
                      ELSE {t \in Tasks :
                              LET h == Placement(config[n], t)
                              IN  h # n /\ h \in ViewFailed(config'[n])}]

\* The lineage an unrecoverable start on n opens: its view's switch id, newer than the
\* view of every state the cluster had.
ViewLineage(n) == <<epoch[n], seq[n]>>

\* The counting rule's condition on the view n left (a parameter of HActivateBy, so that
\* a mutant can count otherwise).
PlacedBefore(n) == placedBefore[n]

HTypeOK ==
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
    /\ failed \in [Nodes -> SUBSET (Nodes \cup {Storage})]
    /\ crashes \in 0..MaxCrashes
    /\ phaseChanges \in 0..MaxPhaseChanges
    /\ unbooted \subseteq Nodes \ {Priority[1]}
    /\ handoff \in [Nodes -> SUBSET Tasks]
    /\ lineage \in [Nodes -> [Tasks -> Lineages]]
    /\ storedLineage \in [Tasks -> Lineages]
    /\ unstored \in [Nodes -> SUBSET Tasks]
    /\ storageUp \in BOOLEAN
    /\ placedBefore \in [Nodes -> BOOLEAN]
    /\ hostLost \in [Nodes -> SUBSET Tasks]
    /\ storageFaults \in 0..MaxStorageFaults
    /\ readmissions \in 0..MaxReadmissions
    /\ unrecoverable \in Nat
    /\ start \in [Tasks -> StartRecords]
    /\ saved \in [Tasks -> States]

HInit ==
    /\ Init
    /\ handoff = [n \in Nodes |-> {}]
    /\ lineage = [n \in Nodes |-> [t \in Tasks |-> InitialLineage]]
    /\ storedLineage = [t \in Tasks |-> InitialLineage]
    /\ unstored = [n \in Nodes |-> {}]
    /\ storageUp = TRUE
    /\ placedBefore = [n \in Nodes |-> FALSE]
    /\ hostLost = [n \in Nodes |-> {}]
    /\ storageFaults = 0
    /\ readmissions = 0
    /\ unrecoverable = 0
    /\ start = [t \in Tasks |-> NeverStarted]
    /\ saved = [t \in Tasks |-> Zero]

\* The new variables a step of ConfigSwitch leaves alone.
handoffState == <<handoff, lineage, storedLineage, unstored, storageUp, storageFaults, readmissions,
                  unrecoverable, start, saved>>

\* Node n adopts a view that excludes the Storage node while final flushes of its
\* hand-offs are pending (deactivated with the Storage node in its view, not yet
\* acknowledged): the view drops the flushes (nothing can take them), and those
\* hand-offs become unstored instead, to be flushed when a view includes the Storage node
\* again (the runtime's unstored_ |= unflushed_ & handed_off_ in receive_command, which
\* the Master's own switches go through too). Such a hand-off now stands in for the
\* Storage node: a saved state. The caller sets unflushed'.
KeepUnflushed(n) ==
    /\ unstored' = [unstored EXCEPT ![n] = @ \cup (unflushed[n] \cap handoff[n])]
    /\ saved' = [t \in Tasks |->
                   IF t \in unflushed[n] \cap handoff[n]
                   THEN Newest({saved[t], StateOf(n, t)}) ELSE saved[t]]

(***************************************************************************)
(* Master                                                                  *)
(***************************************************************************)

\* ConfigSwitch's steps of the Master, unchanged. Each may start a switch, which applies
\* to the Master at once.
HBootSwitch(m) == BootSwitch(m) /\ TrackPlaced /\ UNCHANGED handoffState
HExclude(m, f) == Exclude(m, f) /\ TrackPlaced /\ UNCHANGED handoffState
HRequestPhase(m, c) == RequestPhase(m, c) /\ TrackPlaced /\ UNCHANGED handoffState
HBecomeMaster(n) == BecomeMaster(n) /\ TrackPlaced /\ UNCHANGED handoffState
HBroadcastActivate(m) ==
    BroadcastActivate(m) /\ UNCHANGED <<placedBefore, hostLost, handoffState>>
HCompleteSwitch(m) ==
    CompleteSwitch(m) /\ UNCHANGED <<placedBefore, hostLost, handoffState>>

\* Master m learns that the Storage node failed and switches along the decision graph.
\* The switch applies to m at once (StartSwitch), as HReceiveCommandBy: its pending
\* flushes are dropped, and if `keep` those of its hand-offs become unstored
\* (KeepUnflushed). Not `keep`: a mutant.
DeclareStorageFailedBy(m, keep) ==
    /\ IsMaster(m)
    /\ masterSeq[m] > 0
    /\ ~storageUp
    /\ Storage \notin failed[m]
    /\ failed' = [failed EXCEPT ![m] = @ \cup {Storage}]
    /\ LET c == OnFailure(masterConfig[m], Storage) IN
        IF c # masterConfig[m]
        THEN /\ StartSwitch(m, c)
             /\ unflushed' = [unflushed EXCEPT ![m] = {}]
             /\ IF keep THEN KeepUnflushed(m) ELSE UNCHANGED <<unstored, saved>>
        ELSE UNCHANGED <<masterSeq, masterConfig, masterStage, msgs, seq, config, stage,
                         unflushed, unstored, saved>>
    /\ UNCHANGED <<alive, role, epoch, active, version, stored, acks, crashes,
                   phaseChanges, unbooted>>
    /\ UNCHANGED <<handoff, lineage, storedLineage, storageUp, storageFaults, readmissions,
                   unrecoverable, start>>
    /\ TrackPlaced

DeclareStorageFailed(m) == DeclareStorageFailedBy(m, TRUE)

\* Master m hears the Storage node again and readmits it: a switch to a configuration
\* whose view includes it. The switch applies to m at once: if `flush` (as
\* HReceiveCommandBy), m's hand-offs made without the Storage node join its pending
\* flushes.
ReadmitStorageBy(m, flush) ==
    /\ IsMaster(m)
    /\ masterSeq[m] > 0
    /\ storageUp
    /\ Storage \in ViewFailed(masterConfig[m])
    /\ readmissions < MaxReadmissions
    /\ readmissions' = readmissions + 1
    /\ failed' = [failed EXCEPT ![m] = @ \ {Storage}]
    /\ StartSwitch(m, OnReadmit(masterConfig[m], Storage))
    /\ unflushed' = IF flush THEN [unflushed EXCEPT ![m] = @ \cup unstored[m]]
                             ELSE unflushed
    /\ UNCHANGED <<alive, role, epoch, active, version, stored, acks, crashes,
                   phaseChanges, unbooted>>
    /\ UNCHANGED <<handoff, lineage, storedLineage, unstored, storageUp, storageFaults,
                   unrecoverable, start, saved>>
    /\ TrackPlaced

ReadmitStorage(m) == ReadmitStorageBy(m, TRUE)

(***************************************************************************)
(* Nodes                                                                   *)
(***************************************************************************)

\* ConfigSwitch's steps of a node that the Storage node's exclusion leaves as they are.
HAck(n, kind) == Ack(n, kind) /\ UNCHANGED <<placedBefore, hostLost, handoffState>>
HReceiveActivate(n, msg) ==
    ReceiveActivate(n, msg) /\ UNCHANGED <<placedBefore, hostLost, handoffState>>

\* ConfigSwitch's ReceiveCommand, with what the new view says of the Storage node and
\* of n:
\*  - a view that excludes n itself (n is fenced out): n drops its pending flushes and all
\*    its hand-offs (it may hold a lineage of a task the cluster abandoned);
\*  - a view that excludes the Storage node: n drops its pending flushes (nothing can
\*    take them) and keeps its hand-offs; if `keep`, the hand-offs whose flushes it
\*    drops become unstored (KeepUnflushed);
\*  - a view that includes the Storage node: if `flush`, the hand-offs n made while the
\*    Storage node was excluded join its pending flushes, so that n acks "Prepared" only
\*    once the Storage node holds them (whoever starts the task next from the Storage
\*    node then reads them).
\* Not `flush`, not `keep`: mutants.
HReceiveCommandBy(n, msg, flush, keep) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.kind = "Command"
    /\ Newer(msg.epoch, msg.seq, epoch[n], seq[n])
    /\ epoch' = [epoch EXCEPT ![n] = msg.epoch]
    /\ seq' = [seq EXCEPT ![n] = msg.seq]
    /\ config' = [config EXCEPT ![n] = msg.config]
    /\ stage' = [stage EXCEPT ![n] = "Deactivating"]
    /\ IF n \in ViewFailed(msg.config)
       THEN /\ unflushed' = [unflushed EXCEPT ![n] = {}]
            /\ handoff' = [handoff EXCEPT ![n] = {}]
            /\ unstored' = [unstored EXCEPT ![n] = {}]
            /\ UNCHANGED saved
       ELSE IF Storage \in ViewFailed(msg.config)
       THEN /\ unflushed' = [unflushed EXCEPT ![n] = {}]
            /\ IF keep THEN KeepUnflushed(n) ELSE UNCHANGED <<unstored, saved>>
            /\ UNCHANGED handoff
       ELSE /\ unflushed' = IF flush THEN [unflushed EXCEPT ![n] = @ \cup unstored[n]]
                                     ELSE unflushed
            /\ UNCHANGED <<handoff, unstored, saved>>
    /\ UNCHANGED <<alive, role, active, version, stored, masterStage, masterConfig,
                   masterSeq, failed, msgs, acks, crashes, phaseChanges, unbooted>>
    /\ UNCHANGED <<lineage, storedLineage, storageUp, storageFaults, readmissions,
                   unrecoverable, start>>
    /\ TrackPlaced

HReceiveCommand(n, msg) == HReceiveCommandBy(n, msg, TRUE, TRUE)

\* Node n stops task t, which its target configuration places elsewhere. A member of its
\* view keeps the task's state as a hand-off, and flushes it to the Storage node if its
\* view includes it, or else records it as unstored (to be flushed when a view includes
\* the Storage node again); a node its view excludes holds no hand-off.
HDeactivate(n, t) ==
    /\ alive[n]
    /\ stage[n] = "Deactivating"
    /\ t \in active[n]
    /\ Placement(config[n], t) # n
    /\ active' = [active EXCEPT ![n] = @ \ {t}]
    /\ handoff' = IF Member(n) THEN [handoff EXCEPT ![n] = @ \cup {t}]
                                ELSE [handoff EXCEPT ![n] = @ \ {t}]
    /\ unstored' = IF Member(n) /\ ~StorageAvailable(n)
                   THEN [unstored EXCEPT ![n] = @ \cup {t}]
                   ELSE [unstored EXCEPT ![n] = @ \ {t}]
    \* A hand-off in place of the Storage node is a saved state.
    /\ saved' = IF Member(n) /\ ~StorageAvailable(n)
                THEN [saved EXCEPT ![t] = Newest({@, StateOf(n, t)})]
                ELSE saved
    /\ unflushed' = IF Member(n) /\ StorageAvailable(n)
                    THEN [unflushed EXCEPT ![n] = @ \cup {t}]
                    ELSE unflushed
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>
    /\ UNCHANGED <<lineage, storedLineage, placedBefore, hostLost, storageUp, storageFaults,
                   readmissions, unrecoverable, start>>

\* Node n writes the final checkpoint of t to the Storage node, which its view includes
\* and which is up (the write and its acknowledgement as one step). The acknowledgement
\* clears an unstored hand-off of t. The Storage node keeps the state if Takes says so.
HFlushCheckpointBy(n, t, Takes(_, _)) ==
    /\ alive[n]
    /\ t \in unflushed[n]
    /\ Writable(n)
    /\ StoreState(t, StateOf(n, t), Takes)
    /\ saved' = [saved EXCEPT ![t] = Newest({@, StateOf(n, t)})]
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \ {t}]
    /\ unstored' = [unstored EXCEPT ![n] = @ \ {t}]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, version, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>
    /\ UNCHANGED <<handoff, lineage, placedBefore, hostLost, storageUp, storageFaults,
                   readmissions, unrecoverable, start>>

HFlushCheckpoint(n, t) == HFlushCheckpointBy(n, t, StoresNewest)

\* Node n starts task t. With the Storage node in its view: from `stored` (once the
\* Storage node answers: it is up). Without it, if `gather`: from the newest hand-off of
\* the members of its view (AskHolders), or from version 0 when none holds one; an
\* unrecoverable start (StateOutOfReach) if the view n left placed t (Placed(n)) and
\* either none held one or t's host in that view is excluded now. If not `gather` (a
\* mutant): from version 0. Activating clears n's own hand-off of t (unstored or not). A
\* start without the Storage node from a hand-off, or an unrecoverable one, keeps the count
\* of the state it starts from and opens a new lineage, ViewLineage(n); a start from the
\* Storage node keeps the stored state's lineage, and a start from nothing that loses
\* nothing (Afresh) the initial one.
HActivateBy(n, t, gather, Placed(_)) ==
    /\ alive[n]
    /\ stage[n] = "Activating"
    /\ Placement(config[n], t) = n
    /\ t \notin active[n]
    /\ StorageAvailable(n) => storageUp
    /\ LET H == Holders(n, t)
           best == Newest({StateOf(x, t) : x \in H} \cup {Zero})
           w == IF StorageAvailable(n) THEN StoredOf(t)
                ELSE IF gather THEN best ELSE Zero
           how == IF StorageAvailable(n) THEN "Storage"
                  ELSE IF ~gather THEN "Afresh"
                  ELSE IF Placed(n) /\ (H = {} \/ t \in hostLost[n]) THEN "Lost"
                  ELSE IF H = {} THEN "Afresh"
                  ELSE IF \E x \in H \ {n} : StateOf(x, t) = best THEN "Holder"
                  ELSE "Own"
           l == IF how \in {"Holder", "Own", "Lost"} THEN ViewLineage(n) ELSE <<w[1], w[2]>>
       IN /\ active' = [active EXCEPT ![n] = @ \cup {t}]
          /\ version' = [version EXCEPT ![n][t] = w[3]]
          /\ lineage' = [lineage EXCEPT ![n][t] = l]
          /\ handoff' = [handoff EXCEPT ![n] = @ \ {t}]
          /\ unstored' = [unstored EXCEPT ![n] = @ \ {t}]
          /\ unrecoverable' = IF how = "Lost" THEN unrecoverable + 1 ELSE unrecoverable
          /\ start' = [start EXCEPT ![t] = [version |-> w, reach |-> Reach(n, t),
                                             saved |-> saved[t], opened |-> l, how |-> how]]
          \* An unrecoverable start begins a new lineage of the task.
          /\ saved' = [saved EXCEPT ![t] = IF how = "Lost" THEN State(l, w[3])
                                             ELSE Newest({@, w})]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, unflushed, stored, storedLineage,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>
    /\ UNCHANGED <<placedBefore, hostLost, storageUp, storageFaults, readmissions>>

HActivate(n, t) == HActivateBy(n, t, TRUE, PlacedBefore)

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* Task t runs one step on n; the step's checkpoint goes to the Storage node when n's view
\* includes it and it is up (which keeps it if Takes says so).
HExecuteBy(n, t, Takes(_, _)) ==
    /\ alive[n]
    /\ t \in active[n]
    /\ version[n][t] < MaxVersion
    /\ version' = [version EXCEPT ![n][t] = @ + 1]
    /\ LET w == State(lineage[n][t], version[n][t] + 1) IN
        IF Writable(n)
        THEN /\ StoreState(t, w, Takes)
             /\ saved' = [saved EXCEPT ![t] = Newest({@, w})]
        ELSE UNCHANGED <<stored, storedLineage, saved>>
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>
    /\ UNCHANGED <<handoff, lineage, unstored, placedBefore, hostLost, storageUp, storageFaults,
                   readmissions, unrecoverable, start>>

HExecute(n, t) == HExecuteBy(n, t, StoresNewest)

\* Node n crashes: its hand-offs are lost with it.
HCrash(n) ==
    /\ Crash(n)
    /\ handoff' = [handoff EXCEPT ![n] = {}]
    /\ unstored' = [unstored EXCEPT ![n] = {}]
    /\ UNCHANGED <<lineage, storedLineage, placedBefore, hostLost, storageUp, storageFaults,
                   readmissions, unrecoverable, start, saved>>

HBoot(n) == Boot(n) /\ UNCHANGED <<placedBefore, hostLost, handoffState>>

\* The Storage node fails (crashes, or is paused): it stores and answers nothing.
StorageFail ==
    /\ storageUp
    /\ storageFaults < MaxStorageFaults
    /\ storageUp' = FALSE
    /\ storageFaults' = storageFaults + 1
    /\ UNCHANGED vars
    /\ UNCHANGED <<handoff, lineage, storedLineage, unstored, placedBefore, hostLost,
                   readmissions, unrecoverable, start, saved>>

\* The Storage node runs again (a pause ends, or it restarts), holding what it stored.
StorageResume ==
    /\ StorageReturns
    /\ ~storageUp
    /\ storageUp' = TRUE
    /\ UNCHANGED vars
    /\ UNCHANGED <<handoff, lineage, storedLineage, unstored, placedBefore, hostLost,
                   storageFaults, readmissions, unrecoverable, start, saved>>

\* The protocol's steps but the activation, which mutants replace; the Storage node
\* keeps what Takes says (StoresNewest; a mutant compares otherwise).
HSwitchNextBy(Takes(_, _)) ==
    \/ \E m \in Nodes : HBootSwitch(m)
    \/ \E m, f \in Nodes : HExclude(m, f)
    \/ \E m \in Nodes : DeclareStorageFailed(m)
    \/ \E m \in Nodes : ReadmitStorage(m)
    \/ \E m \in Nodes : HBroadcastActivate(m)
    \/ \E m \in Nodes : HCompleteSwitch(m)
    \/ \E n \in Nodes : HBecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : HReceiveCommand(n, msg)
    \/ \E n \in Nodes, t \in Tasks : HDeactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : HFlushCheckpointBy(n, t, Takes)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : HAck(n, k)
    \/ \E n \in Nodes, msg \in msgs : HReceiveActivate(n, msg)

HSwitchNext == HSwitchNextBy(StoresNewest)

HProtocolNext ==
    \/ HSwitchNext
    \/ \E n \in Nodes, t \in Tasks : HActivate(n, t)

HPlannedNext == \E m \in Nodes, c \in ConfigIds : HRequestPhase(m, c)

HEnvironmentNextBy(Takes(_, _)) ==
    \/ \E n \in Nodes, t \in Tasks : HExecuteBy(n, t, Takes)
    \/ \E n \in Nodes : HCrash(n)
    \/ \E n \in Nodes : HBoot(n)
    \/ StorageFail
    \/ StorageResume

HEnvironmentNext == HEnvironmentNextBy(StoresNewest)

HNext == HProtocolNext \/ HPlannedNext \/ HEnvironmentNext

\* ConfigSwitch's fairness over the new protocol steps.
HFairness == WF_everything(HProtocolNext) /\ \A n \in Nodes : WF_everything(HBoot(n))

HSpec == HInit /\ [][HNext]_everything
HFairSpec == HSpec /\ HFairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* No task starts below the newest state within its starting node's reach when it
\* started: the hand-off of every alive member of that node's view (its own included),
\* and the Storage node's checkpoint if its view includes the Storage node. (keel-sim's
\* NoStateLossInv checks, at every Activate of the runtime but a lease resume, the
\* hand-offs of the other members.) The ghost `start` records the start, so the property
\* is about the start itself, not about what the task reached since.
NoStateLossInv == \A t \in Tasks : Geq(start[t].version, start[t].reach)

\* A task starts below the newest state saved for it only by an unrecoverable start,
\* which the starting node reports and counts. Saved: taken by the Storage node, or
\* handed off by a node whose view excludes the Storage node (the hand-off stands in for
\* it), since the task's last unrecoverable start. A state that never reached either (a
\* host's progress since its last checkpoint write, a hand-off still to be flushed) is
\* lost when its node crashes, as in ConfigSwitch; that is not a start below `saved`.
LossReportedInv ==
    \A t \in Tasks : ~Geq(start[t].version, start[t].saved) => start[t].how = "Lost"

\* A start from nothing that is not reported (not an unrecoverable start: the view the
\* new host left was the initial one) loses nothing: no state of the task had been saved.
\* (LossReportedInv asks more, and does not hold: see the header.)
UnrecoverableReportedInv == \A t \in Tasks : start[t].how = "Afresh" => start[t].saved = Zero

\* ConfigSwitch's ResumeLatestCheckpointInv, for the nodes whose view includes the Storage
\* node: a task they run is never older than the Storage node's checkpoint, lineage first
\* (an abandoned lineage is older than the one that replaced it). (Without the Storage
\* node a task may run below a checkpoint that is out of reach.)
HResumeLatestCheckpointInv ==
    \A n \in Nodes, t \in Tasks :
        (alive[n] /\ t \in active[n] /\ StorageAvailable(n)) => Geq(StateOf(n, t), StoredOf(t))

\* What the Storage node holds never falls, lineage first, across its failures and
\* readmissions too.
StoredMonotoneProp ==
    [][\A t \in Tasks : Geq(State(storedLineage'[t], stored'[t]), StoredOf(t))]_everything
=============================================================================
