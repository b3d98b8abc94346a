--------------------------- MODULE MasterElection ---------------------------
(***************************************************************************)
(* Master election of the OBC-NG middleware: when the Master fails, the    *)
(* Observers take over in priority order (the paper's higher- and lower-   *)
(* priority Observers), fenced by epochs.                                  *)
(*                                                                         *)
(* Priority lists the processing nodes in order of succession: the         *)
(* initial Master, the Observers from higher to lower priority, then the   *)
(* Workers. Epochs are numbered 1, 2, ... and each epoch has one owner,    *)
(* going round Priority: Owner(1) is the initial Master, Owner(2) the      *)
(* higher-priority Observer, and so on. A node may only be Master in an    *)
(* epoch it owns. Node n, which last saw epoch[n], claims NextEpoch(n),    *)
(* the first later epoch it owns, once the Master of epoch[n] is gone      *)
(* (declared failed, or it is no longer Master of that epoch: an          *)
(* abstraction; the runtime's heartbeats carry the epoch, not the role,   *)
(* and ElectionLiar.tla states its guard) and it has declared failed the  *)
(* owners of every epoch in between (everyone ahead of it in succession);  *)
(* so the higher-priority Observer takes over first, the lower-priority    *)
(* one only if the higher-priority one has failed too, and a Worker only   *)
(* when every Observer is gone. The new Master broadcasts its epoch.       *)
(*                                                                         *)
(* Every command carries the epoch of the Master that sent it. A node      *)
(* obeys a command whose epoch is at least the highest it has seen, and    *)
(* rejects the others: stale epochs are rejected in this one place. A      *)
(* Master that learns of a higher epoch steps down.                        *)
(*                                                                         *)
(* A crash loses the node's volatile state; its epoch is persisted. A      *)
(* restarted node rejoins as a Worker. Before it acts it listens for one   *)
(* heartbeat period (heartbeats carry the sender's epoch) and adopts the   *)
(* highest epoch among its persisted one and those of the running nodes,  *)
(* so it can become Master again only by claiming a newer epoch. A reboot *)
(* is assumed to take longer than failure detection: a node restarts only *)
(* after every running processing node has declared it failed.            *)
(*                                                                         *)
(* A restarted node waits to be commanded (leader NoNode, and its          *)
(* heartbeats say so) and never claims an epoch while it waits: a         *)
(* restarted former Master must not resume. Only when every node waits (a  *)
(* whole-cluster power cycle: no node is Master, and none will be          *)
(* otherwise) does one node take the first epoch it owns above every epoch *)
(* (WarmBoot; the runtime's is the first of the succession, the initial   *)
(* Master) and command, so the cluster recovers by itself. The last node  *)
(* to go down takes the messages in flight with it: none outlives an       *)
(* instant when every node is down (keel-sim: delays of at most a third of *)
(* a period, restarts after 50 ms or more).                               *)
(*                                                                         *)
(* A Master m may hand its mastership over to another running node r     *)
(* (HandOver; the runtime does when the cluster returns to a              *)
(* configuration whose master is r, e.g. after readmitting r): it sends r  *)
(* a hand-over for r's next epoch above its own, adopts that epoch itself  *)
(* (r's Observer or Worker, obeying r) and so stops being Master at once,  *)
(* and the hand-over stays deliverable (the runtime repeats it until r     *)
(* commands). m hands over only to a node whose heartbeats show no epoch   *)
(* above its own: one that does tells m that it is deposed, and the        *)
(* runtime hands over only to a node it readmits, which has adopted m's    *)
(* epoch. A hand-over names the boot of its receiver as m hears it in r's  *)
(* heartbeats; every restart gives a node a new boot. r takes a hand-over  *)
(* (TakeHandOver: it becomes Master of that epoch, then commands) only if  *)
(* it is fresh and names r's current boot. One meant for a boot that       *)
(* ended (r restarted within the repeats) is dropped, and the restarted    *)
(* node waits to be commanded as any restarted node does: taking it would  *)
(* make r Master of an epoch m held when r restarted. The runtime also     *)
(* sends the first copy to every other node of the view, which adopt it    *)
(* as from r; the spec leaves those copies out (as if lost), so the others *)
(* learn r's epoch from r's commands. MaxHandOvers bounds the hand-overs   *)
(* of a behaviour (0 unless a model says otherwise).                       *)
(*                                                                         *)
(* A running Master m may exclude a running node n from its view (Fence:   *)
(* the runtime's exclusion of a live node, after heartbeat loss beyond the *)
(* accuracy bound or by a value-faulty Master's lie; declaring n and       *)
(* excluding it are one step, counted by MaxFences, not                    *)
(* MaxFalseSuspicions). n receives that view, a command of m's epoch that  *)
(* must be fresh for it: it adopts the epoch as a Worker obeying m and     *)
(* knows itself fenced (fenced[n]). A fenced node runs nothing, never      *)
(* claims an epoch (BecomeMaster needs ~fenced[n]) and waits for a Master  *)
(* to readmit it. It obeys fresh commands as a Worker and stays fenced: a  *)
(* later Master's view descends from the one that excluded it. Its         *)
(* heartbeats say it is excluded, so a node that hears one declares it     *)
(* failed on its own word (SuspectFenced: no false declaration, and as     *)
(* fair as declaring a crashed node) and passes it over in the succession, *)
(* as the runtime passes over a node its view excludes. A running Master   *)
(* readmits a fenced node (Readmit: a command whose view includes it,      *)
(* which every node adopts in the same step, forgetting its declaration of *)
(* it; when the runtime readmits is spec Rejoin's). The view is persisted: *)
(* a fenced node stays fenced across a restart (and waits as well). A      *)
(* Master is never fenced: a hand-over's view never excludes its receiver, *)
(* nor a warm boot's anyone (the spec does not tell a warm boot's command  *)
(* from another, so the other fenced nodes wait for a Readmit). The warm   *)
(* boot counts a running fenced node as idle, as it does one that waits    *)
(* (Idle), and a fenced node may warm-boot (the runtime's initial Master   *)
(* may when it is fenced itself): otherwise a Master that fenced every     *)
(* other node, then crashed and restarted, leaves no Master for good,      *)
(* itself waiting and the others waiting to be readmitted (mutant          *)
(* ElectionWarmBootWaitingOnly, MCMasterElectionFenced; keel-sim --mutant  *)
(* warm-boot-waiting-only). MaxFences bounds the fences of a behaviour (0  *)
(* unless a model says otherwise: then no node is ever fenced, and the     *)
(* state space is the one without fences).                                 *)
(*                                                                         *)
(* The failure detector (spec Heartbeat) is abstracted as Suspect:         *)
(* always possible for a crashed node (completeness), and possible for a   *)
(* running node at most MaxFalseSuspicions times (heartbeat loss beyond   *)
(* MissLimit - 1, which Heartbeat's accuracy does not cover). Messages may *)
(* be lost, duplicated and reordered: msgs only grows, and a receiver may  *)
(* take any message in it, any number of times, or never.                 *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - OneMasterPerEpochInv: no two nodes are Master in the same epoch.     *)
(*  - MasterOwnsEpochInv: a Master's epoch is one it owns.                 *)
(*  - EpochMonotoneProp: a node's epoch never decreases.                   *)
(*  - StaleCommandRejectedProp: a node obeys a command only if its epoch   *)
(*    is at least the highest the node has seen.                          *)
(*  - NoStaleMastershipInv: a restarted node is Master only in an epoch    *)
(*    newer than every epoch a running node held when it restarted; so a   *)
(*    hand-over meant for an earlier boot of a node never makes it Master  *)
(*    (mutant ElectionHandOverAnyBoot, MCMasterElectionHandOver).          *)
(*  - MasterLiveness: under fairness, if some processing node stays alive, *)
(*    eventually there is always a running Master.                        *)
(*  - RecoveryLiveness: under fairness, if every node is eventually alive  *)
(*    for good, eventually there is always a running Master, also after    *)
(*    every node crashed and restarted (MCMasterElectionPowerCycle) and    *)
(*    after a Master fenced every other node, crashed and restarted        *)
(*    (MCMasterElectionFenced). A node that never comes back after a       *)
(*    whole-cluster power cycle leaves the others waiting: WarmBoot needs  *)
(*    every node. With fences MasterLiveness does not hold: a Master that  *)
(*    fenced every other node and crashed for good leaves them fenced, and *)
(*    no Master readmits them.                                             *)
(***************************************************************************)
EXTENDS Naturals, Sequences, FiniteSets

CONSTANTS
    Priority,             \* sequence of distinct processing nodes, in succession order
    NumObservers,         \* how many nodes after the Master are Observers
    MaxCrashes,           \* environment: at most this many crashes in a behaviour
    MaxRestarts,          \* environment: at most this many restarts in a behaviour
    MaxFalseSuspicions,   \* environment: at most this many running nodes declared failed
    NoNode                \* a value that is not a node: "no leader known"

Nodes == {Priority[i] : i \in 1..Len(Priority)}
N == Len(Priority)

ASSUME PriorityAssumption == Len(Priority) >= 1 /\ Cardinality(Nodes) = Len(Priority)
ASSUME BudgetAssumption ==
    {MaxCrashes, MaxRestarts, MaxFalseSuspicions} \subseteq Nat
ASSUME NoNodeAssumption == NoNode \notin Nodes
ASSUME ObserverAssumption == NumObservers \in 0..(Len(Priority) - 1)

\* At most this many hand-overs in a behaviour. A definition, not a CONSTANT, so that the
\* models without hand-overs (and the trace and mission models) need not name it; a model
\* with hand-overs overrides it in its .cfg (MaxHandOvers = k).
MaxHandOvers == 0

\* At most this many fences in a behaviour: a definition as MaxHandOvers is, overridden by a
\* model with fences (MaxFences = k). With none, fenced stays FALSE everywhere.
MaxFences == 0

VARIABLES
    alive,          \* env: [Nodes -> BOOLEAN], the node is running
    role,           \* [Nodes -> {"Master", "Observer", "Worker"}]
    epoch,          \* [Nodes -> Nat], highest epoch seen (persisted)
    leader,         \* [Nodes -> Nodes \cup {NoNode}], the Master the node obeys
    suspects,       \* [Nodes -> SUBSET Nodes], nodes declared failed (volatile)
    lastCommand,    \* [Nodes -> Nat], epoch of the last command obeyed, 0 for none
    msgs,           \* env: set of [epoch, from] commands sent
    handOvers,      \* env: set of [epoch, from, to, boot] hand-overs sent
    boot,           \* [Nodes -> Nat], the node's boot, a new one at each restart
    restartEpoch,   \* env: [Nodes -> Nat], highest running epoch at the last restart
    crashes,        \* env: number of crashes so far
    restarts,       \* env: number of restarts so far
    handOverCount,  \* env: number of hand-overs so far
    falseSuspicions, \* env: number of running nodes declared failed so far
    fenced,         \* [Nodes -> BOOLEAN], the node knows its view excludes it (persisted)
    fenceCount      \* env: number of fences so far

vars == <<alive, role, epoch, leader, suspects, lastCommand, msgs, handOvers, boot,
          restartEpoch, crashes, restarts, handOverCount, falseSuspicions, fenced,
          fenceCount>>

\* The owner of epoch e >= 1, and the position of a node in the succession.
Owner(e) == Priority[((e - 1) % N) + 1]
Rank(n) == CHOOSE i \in 1..N : Priority[i] = n

\* The first epoch after epoch[n] that n owns.
NextEpoch(n) ==
    LET k == (Rank(n) - ((epoch[n] % N) + 1)) % N
    IN  epoch[n] + 1 + k

\* The owners of the epochs after epoch[n] and before NextEpoch(n): the nodes that
\* come before n in the succession from the Master of epoch[n].
Ahead(n) == {Owner(e) : e \in (epoch[n] + 1)..(NextEpoch(n) - 1)} \ {n}

\* Node n knows the Master of its epoch is gone: n declared it failed, or its
\* heartbeats (which carry the sender's role and epoch) say it is no longer Master of
\* that epoch (it rebooted, or moved on to a later one).
MasterGone(n) ==
    \/ epoch[n] = 0
    \/ LET m == Owner(epoch[n]) IN
          \/ m = n
          \/ m \in suspects[n]
          \/ role[m] # "Master"
          \/ epoch[m] # epoch[n]

\* The role a node takes when it adopts epoch e from a command: never Master (only
\* BecomeMaster makes a Master); Observer if it is among the Observers of e.
ObserversOf(e) == {Owner(e + i) : i \in 1..NumObservers}
RoleIn(n, e) == IF n \in ObserversOf(e) THEN "Observer" ELSE "Worker"

MaxEpochOf(S) == IF S = {} THEN 0 ELSE CHOOSE e \in S : \A x \in S : x <= e

Messages == [epoch : Nat, from : Nodes]
HandOverMessages == [epoch : Nat, from : Nodes, to : Nodes, boot : 0..MaxRestarts]

TypeOK ==
    /\ alive \in [Nodes -> BOOLEAN]
    /\ role \in [Nodes -> {"Master", "Observer", "Worker"}]
    /\ epoch \in [Nodes -> Nat]
    /\ leader \in [Nodes -> Nodes \cup {NoNode}]
    /\ suspects \in [Nodes -> SUBSET Nodes]
    /\ lastCommand \in [Nodes -> Nat]
    /\ msgs \subseteq Messages
    /\ handOvers \subseteq HandOverMessages
    /\ boot \in [Nodes -> 0..MaxRestarts]
    /\ restartEpoch \in [Nodes -> Nat]
    /\ crashes \in 0..MaxCrashes
    /\ restarts \in 0..MaxRestarts
    /\ falseSuspicions \in 0..MaxFalseSuspicions
    /\ handOverCount \in 0..MaxHandOvers
    /\ fenced \in [Nodes -> BOOLEAN]
    /\ fenceCount \in 0..MaxFences

\* Epoch 1: Priority[1] is the Master, everyone knows it.
Init ==
    /\ alive = [n \in Nodes |-> TRUE]
    /\ role = [n \in Nodes |-> IF n = Owner(1) THEN "Master" ELSE RoleIn(n, 1)]
    /\ epoch = [n \in Nodes |-> 1]
    /\ leader = [n \in Nodes |-> Owner(1)]
    /\ suspects = [n \in Nodes |-> {}]
    /\ lastCommand = [n \in Nodes |-> 1]
    /\ msgs = {[epoch |-> 1, from |-> Owner(1)]}
    /\ handOvers = {}
    /\ boot = [n \in Nodes |-> 0]
    /\ restartEpoch = [n \in Nodes |-> 0]
    /\ crashes = 0
    /\ restarts = 0
    /\ falseSuspicions = 0
    /\ handOverCount = 0
    /\ fenced = [n \in Nodes |-> FALSE]
    /\ fenceCount = 0

(***************************************************************************)
(* Protocol                                                                *)
(***************************************************************************)

\* Node n's failure detector declares m failed (see the header for when it may).
Suspect(n, m) ==
    /\ alive[n]
    /\ m # n
    /\ m \notin suspects[n]
    /\ alive[m] => falseSuspicions < MaxFalseSuspicions
    /\ suspects' = [suspects EXCEPT ![n] = @ \cup {m}]
    /\ falseSuspicions' = IF alive[m] THEN falseSuspicions + 1 ELSE falseSuspicions
    /\ UNCHANGED <<alive, role, epoch, leader, lastCommand, msgs, handOvers, boot,
                   restartEpoch, crashes, restarts, handOverCount, fenced, fenceCount>>

\* Node n hears m's heartbeat, which says m's view excludes it, and declares m failed: m's
\* own word, no false declaration (runtime: the monitor declares a node whose heartbeat
\* says `excluded`, as the election passes over a node its view excludes).
SuspectFenced(n, m) ==
    /\ alive[n]
    /\ m # n
    /\ m \notin suspects[n]
    /\ alive[m]
    /\ fenced[m]
    /\ suspects' = [suspects EXCEPT ![n] = @ \cup {m}]
    /\ UNCHANGED <<alive, role, epoch, leader, lastCommand, msgs, handOvers, boot,
                   restartEpoch, crashes, restarts, falseSuspicions, handOverCount, fenced,
                   fenceCount>>

\* A restarted node that has obeyed no command since (its heartbeats say it waits).
Waiting(n) == alive[n] /\ leader[n] = NoNode

\* A node that is idle claims no epoch: it waits, or it runs knowing it is fenced.
Idle(n) == Waiting(n) \/ (alive[n] /\ fenced[n])

\* Node n takes over: everyone ahead of it in the succession has been declared failed.
\* A node that waits, or is fenced, never does.
BecomeMaster(n) ==
    /\ alive[n]
    /\ role[n] # "Master"
    /\ ~Waiting(n)
    /\ ~fenced[n]
    /\ MasterGone(n)
    /\ Ahead(n) \subseteq suspects[n]
    /\ LET e == NextEpoch(n) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>

\* The first epoch after e that n owns.
NextEpochAbove(n, e) == e + 1 + ((Rank(n) - ((e % N) + 1)) % N)

\* A whole-cluster power cycle: every node is idle (waits, or runs fenced), so no node is
\* Master and none will claim. One node (any, a fenced one too: the runtime's, the first
\* of the succession, refines this) takes the first epoch it owns above every node's epoch
\* (each heard in its heartbeats) and commands, in a view that excludes no one.
WarmBootBy(IsIdle(_), n) ==
    /\ \A x \in Nodes : IsIdle(x)
    /\ LET e == NextEpochAbove(n, MaxEpochOf({epoch[x] : x \in Nodes})) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ fenced' = [fenced EXCEPT ![n] = FALSE]
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenceCount>>

WarmBoot(n) == WarmBootBy(Idle, n)

\* The Master sends a command stamped with its epoch.
BroadcastCommand(n) ==
    /\ alive[n]
    /\ role[n] = "Master"
    /\ [epoch |-> epoch[n], from |-> n] \notin msgs
    /\ msgs' = msgs \cup {[epoch |-> epoch[n], from |-> n]}
    /\ UNCHANGED <<alive, role, epoch, leader, suspects, lastCommand, handOvers, boot,
                   restartEpoch, crashes, restarts, falseSuspicions, handOverCount, fenced,
                   fenceCount>>

\* The one place where stale epochs are rejected.
Fresh(n, msg) == msg.epoch >= epoch[n]

\* Node n receives a command and obeys it: it is from the highest epoch n has seen.
\* A stale command is rejected, which changes nothing (a stuttering step, which a
\* trace may log as "RejectCommand"). A command of a newer epoch is a sign of life of
\* its sender, whom n no longer holds for failed. A fenced node stays fenced, a Worker (the
\* Master's view still excludes it); only Readmit, a warm boot or a hand-over readmit it.
ReceiveCommand(n, msg) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.from # n
    /\ Fresh(n, msg)
    /\ epoch' = [epoch EXCEPT ![n] = msg.epoch]
    /\ leader' = [leader EXCEPT ![n] = msg.from]
    /\ lastCommand' = [lastCommand EXCEPT ![n] = msg.epoch]
    /\ role' = IF msg.epoch > epoch[n]
                  THEN [role EXCEPT ![n] = IF fenced[n] THEN "Worker"
                                                        ELSE RoleIn(n, msg.epoch)]
                  ELSE role
    /\ suspects' = IF msg.epoch > epoch[n]
                      THEN [suspects EXCEPT ![n] = @ \ {msg.from}]
                      ELSE suspects
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>

\* Master m declares the running node n failed and excludes it from its view (one step: the
\* declaration is a false one, counted by MaxFences, not MaxFalseSuspicions), and n
\* receives that view: a command of m's epoch, fresh for n. n adopts the epoch as a Worker
\* obeying m, and knows itself fenced. A command of a newer epoch is a sign of life of m,
\* as in ReceiveCommand.
Fence(m, n) ==
    /\ alive[m]
    /\ role[m] = "Master"
    /\ n # m
    /\ alive[n]
    /\ ~fenced[n]
    /\ Fresh(n, [epoch |-> epoch[m], from |-> m])
    /\ fenceCount < MaxFences
    /\ fenced' = [fenced EXCEPT ![n] = TRUE]
    /\ epoch' = [epoch EXCEPT ![n] = epoch[m]]
    /\ role' = [role EXCEPT ![n] = "Worker"]
    /\ leader' = [leader EXCEPT ![n] = m]
    /\ lastCommand' = [lastCommand EXCEPT ![n] = epoch[m]]
    /\ suspects' = [suspects EXCEPT ![m] = @ \cup {n},
                                     ![n] = IF epoch[m] > epoch[n] THEN @ \ {m} ELSE @]
    /\ fenceCount' = fenceCount + 1
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount>>

\* The running Master m readmits the fenced node n: n obeys m's command, whose view
\* includes it (fresh for n), and is no longer fenced. No node holds n for failed any more:
\* each forgets its declaration of n when it adopts that view (runtime: the monitors'
\* Readmit, spec Rejoin), here in the same step.
Readmit(m, n) ==
    /\ alive[m]
    /\ role[m] = "Master"
    /\ n # m
    /\ alive[n]
    /\ fenced[n]
    /\ Fresh(n, [epoch |-> epoch[m], from |-> m])
    /\ fenced' = [fenced EXCEPT ![n] = FALSE]
    /\ epoch' = [epoch EXCEPT ![n] = epoch[m]]
    /\ role' = [role EXCEPT ![n] = RoleIn(n, epoch[m])]
    /\ leader' = [leader EXCEPT ![n] = m]
    /\ lastCommand' = [lastCommand EXCEPT ![n] = epoch[m]]
    /\ suspects' = [x \in Nodes |-> IF x = n THEN suspects[n] \ {m} ELSE suspects[x] \ {n}]
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenceCount>>

\* Master m hands its mastership over to r (see the header): a hand-over for the first
\* epoch above its own that r owns, naming r's boot as m hears it in r's heartbeats. m
\* adopts that epoch at once, as r's Observer or Worker, and obeys r. r is not fenced (the
\* runtime hands over only to a node it readmitted).
HandOver(m, r) ==
    /\ alive[m]
    /\ role[m] = "Master"
    /\ r # m
    /\ alive[r]
    /\ ~fenced[r]
    /\ epoch[r] <= epoch[m]
    /\ handOverCount < MaxHandOvers
    /\ LET e == NextEpochAbove(r, epoch[m]) IN
        /\ handOvers' = handOvers \cup {[epoch |-> e, from |-> m, to |-> r, boot |-> boot[r]]}
        /\ epoch' = [epoch EXCEPT ![m] = e]
        /\ role' = [role EXCEPT ![m] = RoleIn(m, e)]
        /\ leader' = [leader EXCEPT ![m] = r]
        /\ lastCommand' = [lastCommand EXCEPT ![m] = e]
    /\ handOverCount' = handOverCount + 1
    /\ UNCHANGED <<alive, suspects, msgs, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, fenced, fenceCount>>

\* The boot check: the hand-over names the receiver's current boot.
MeantForThisBoot(r, h) == h.boot = boot[r]

\* Node r takes a hand-over meant for it: fresh, and for this boot. It becomes Master of
\* the hand-over's epoch, and commands from then on (BroadcastCommand). A hand-over for a
\* boot of r that ended, or a stale one, is dropped, which changes nothing (a stuttering
\* step; the runtime counts it in hand_overs_stale). As a command, a hand-over of a newer
\* epoch is a sign of life of its sender. A hand-over's view never excludes its receiver:
\* one fenced since is readmitted by it.
TakeHandOver(r, h) ==
    /\ alive[r]
    /\ h \in handOvers
    /\ h.to = r
    /\ MeantForThisBoot(r, h)
    /\ Fresh(r, h)
    /\ epoch' = [epoch EXCEPT ![r] = h.epoch]
    /\ role' = [role EXCEPT ![r] = "Master"]
    /\ leader' = [leader EXCEPT ![r] = r]
    /\ lastCommand' = [lastCommand EXCEPT ![r] = h.epoch]
    /\ suspects' = IF h.epoch > epoch[r]
                      THEN [suspects EXCEPT ![r] = @ \ {h.from}]
                      ELSE suspects
    /\ fenced' = [fenced EXCEPT ![r] = FALSE]
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenceCount>>

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* The last node to go down takes every message in flight with it: no node is left to
\* retransmit, and none is delivered after the whole cluster restarted.
Crash(n) ==
    /\ alive[n]
    /\ crashes < MaxCrashes
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ crashes' = crashes + 1
    /\ msgs' = IF \A x \in Nodes \ {n} : ~alive[x] THEN {} ELSE msgs
    /\ handOvers' = IF \A x \in Nodes \ {n} : ~alive[x] THEN {} ELSE handOvers
    /\ UNCHANGED <<role, epoch, leader, suspects, lastCommand, boot,
                   restartEpoch, restarts, falseSuspicions, handOverCount, fenced,
                   fenceCount>>

\* The epoch a rebooted node rejoins with: its persisted one, or a higher one heard in
\* the heartbeats of the running nodes.
RejoinEpoch(n) == MaxEpochOf({epoch[n]} \cup {epoch[x] : x \in {y \in Nodes : alive[y]}})

\* The boot a node restarts in: a new one. Only hand-overs read boots, so a model without
\* them (MaxHandOvers = 0) keeps every boot 0 and its state space is the one without boots.
NewBoot(n) == IF MaxHandOvers = 0 THEN boot[n] ELSE boot[n] + 1

\* Node n boots again, in a new boot, as a Worker, once every running node has declared
\* it failed (a reboot takes longer than failure detection). Its view is persisted: a
\* fenced node stays fenced.
Restart(n) ==
    /\ ~alive[n]
    /\ restarts < MaxRestarts
    /\ \A x \in Nodes : alive[x] => n \in suspects[x]
    /\ alive' = [alive EXCEPT ![n] = TRUE]
    /\ role' = [role EXCEPT ![n] = "Worker"]
    /\ epoch' = [epoch EXCEPT ![n] = RejoinEpoch(n)]
    /\ leader' = [leader EXCEPT ![n] = NoNode]
    /\ suspects' = [suspects EXCEPT ![n] = {}]
    /\ boot' = [boot EXCEPT ![n] = NewBoot(n)]
    /\ restartEpoch' = [restartEpoch EXCEPT ![n] = RejoinEpoch(n)]
    /\ restarts' = restarts + 1
    /\ UNCHANGED <<lastCommand, msgs, handOvers, crashes, falseSuspicions, handOverCount,
                   fenced, fenceCount>>

ProtocolNext ==
    \/ \E n, m \in Nodes : Suspect(n, m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes : WarmBoot(n)
    \/ \E n \in Nodes : BroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ \E m, r \in Nodes : HandOver(m, r)
    \/ \E r \in Nodes, h \in handOvers : TakeHandOver(r, h)
    \/ \E m, n \in Nodes : Fence(m, n)
    \/ \E n, m \in Nodes : SuspectFenced(n, m)
    \/ \E m, n \in Nodes : Readmit(m, n)

EnvironmentNext ==
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : Restart(n)

Next == ProtocolNext \/ EnvironmentNext

\* Fairness: failure detection of crashed nodes is complete, so is the declaration of a
\* fenced node heard saying so, a node that may take over eventually does, and a message
\* (a command, a hand-over) that would change its receiver is eventually taken. A Master
\* need not hand over, fence, nor readmit.
Fairness ==
    /\ \A n, m \in Nodes : WF_vars(~alive[m] /\ Suspect(n, m))
    /\ \A n, m \in Nodes : WF_vars(SuspectFenced(n, m))
    /\ \A n \in Nodes : WF_vars(BecomeMaster(n))
    /\ WF_vars(\E n \in Nodes : WarmBoot(n))
    /\ \A n \in Nodes : WF_vars(BroadcastCommand(n))
    /\ \A n \in Nodes : WF_vars(\E msg \in msgs : ReceiveCommand(n, msg))
    /\ \A r \in Nodes : WF_vars(\E h \in handOvers : TakeHandOver(r, h))

Spec == Init /\ [][Next]_vars
FairSpec == Spec /\ Fairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

OneMasterPerEpochInv ==
    \A n, m \in Nodes :
        (role[n] = "Master" /\ role[m] = "Master" /\ epoch[n] = epoch[m]) => n = m

MasterOwnsEpochInv ==
    \A n \in Nodes : role[n] = "Master" => Owner(epoch[n]) = n

NoStaleMastershipInv ==
    \A n \in Nodes : role[n] = "Master" => epoch[n] > restartEpoch[n]

EpochMonotoneProp == [][\A n \in Nodes : epoch'[n] >= epoch[n]]_vars

StaleCommandRejectedProp ==
    [][\A n \in Nodes : lastCommand'[n] # lastCommand[n] => lastCommand'[n] >= epoch[n]]_vars

MasterLiveness ==
    (\E n \in Nodes : <>[]alive[n]) => <>[](\E m \in Nodes : alive[m] /\ role[m] = "Master")

RecoveryLiveness ==
    <>[](\A n \in Nodes : alive[n]) => <>[](\E m \in Nodes : alive[m] /\ role[m] = "Master")

=============================================================================
