---------------------------- MODULE MCConfigSwitch ----------------------------
(***************************************************************************)
(* Models of ConfigSwitch: MCConfigSwitch.cfg (a failure or a planned      *)
(* phase change during any switch) and MCConfigSwitchFailover.cfg (the     *)
(* composed scenario: a further failure and a Master crash in the middle   *)
(* of a switch, then the next node in Priority takes over).                *)
(*                                                                         *)
(* The paper's prototype: PN1 the Master, PN2 and PN3 the Observers, ST1   *)
(* the Storage node; two checkpointed tasks. A configuration id is a       *)
(* mission phase and the set of failed nodes (the decision graph adds the  *)
(* failed node to the set); each task goes to the first node of its        *)
(* phase's preference list that has not failed. Preferences are rotations *)
(* of Priority, and the two phases swap them between the tasks, so a       *)
(* planned switch migrates both tasks at once, crosswise: the case where   *)
(* activating before deactivation would run a task twice. A task executes *)
(* at most one step, so a stale checkpoint is one version behind.          *)
(***************************************************************************)
EXTENDS ConfigSwitch

CONSTANTS PN1, PN2, PN3, t1, t2

MCPriority == <<PN1, PN2, PN3>>
MCTaskList == <<t1, t2>>

\* The mission phases.
MCPhases == {"P1", "P2"}

\* Priority rotated left by k places.
Rotate(s, k) == [i \in 1..Len(s) |-> s[((i - 1 + k) % Len(s)) + 1]]

\* Task number i prefers Priority rotated by i in phase P1, by (#tasks + 1 - i) in P2.
TaskIndex(t) == CHOOSE i \in 1..Len(MCTaskList) : MCTaskList[i] = t
MCPreference(p, t) ==
    IF p = "P1" THEN Rotate(Priority, TaskIndex(t))
    ELSE Rotate(Priority, Len(MCTaskList) + 1 - TaskIndex(t))

\* Configurations reachable with at most MaxCrashes failures and MaxLateBoots nodes
\* declared before they booted.
MCConfigIds ==
    [phase : MCPhases,
     failed : {F \in SUBSET ProcessingNodes :
                 Cardinality(F) <= MaxCrashes + MaxLateBoots}]
MCInitialConfig == [phase |-> "P1", failed |-> {}]

\* A configuration's failed set holds crashed nodes and nodes declared before they booted;
\* at least one processing node is left to place the tasks on.
ASSUME MCBudgetAssumption == MaxCrashes + MaxLateBoots < Len(Priority)

MCPlacement(c, t) ==
    LET pref == MCPreference(c.phase, t)
        i == CHOOSE i \in 1..Len(pref) :
                /\ pref[i] \notin c.failed
                /\ \A j \in 1..(i - 1) : pref[j] \in c.failed
    IN  pref[i]

MCOnFailure(c, f) == [c EXCEPT !.failed = @ \cup {f}]

MCOnPhase(c) == {[c EXCEPT !.phase = IF @ = "P1" THEN "P2" ELSE "P1"]}

(***************************************************************************)
(* Reduction: MCView, the VIEW of every model of ConfigSwitch. TLC tells   *)
(* states apart by MCView instead of all variables, so states that differ  *)
(* only in what no step and no property will ever read again are one       *)
(* state. That is sound when (1) the properties read nothing the view      *)
(* hides, and (2) two states with the same view have the same enabled      *)
(* steps with successors of the same view (a bisimulation), so no          *)
(* behaviour, safety or liveness, is lost. What is hidden, and why no step *)
(* reads it again:                                                         *)
(*  - dead messages. A command is read only by a node with an older switch *)
(*    id (ReceiveCommand needs Newer); an Activate only by a node in its   *)
(*    switch, Deactivating or Prepared (or older, which may still get its  *)
(*    command). Ids of running nodes only grow, a switch's stage only      *)
(*    advances, crashed nodes never return, and an unbooted node counts as *)
(*    a receiver with its initial id: a message dead once stays dead.      *)
(*  - dead acks. AllAcked reads only the acks of the running Master's      *)
(*    current switch, "Prepared" ones while it prepares; a new switch or   *)
(*    Master has a newer id than every ack sent, so other acks stay dead.  *)
(*  - a crashed node's variables but `epoch` (BecomeMaster takes the       *)
(*    largest epoch of all nodes): no step of a crashed node is enabled,   *)
(*    the others read only its alive, role (to see it is not a running     *)
(*    Master) and epoch, and every property reads only running nodes or    *)
(*    `active` (emptied at the crash).                                     *)
(*  - the version of a task a node neither runs nor has to flush: Activate *)
(*    overwrites it from `stored` before Execute or FlushCheckpoint reads  *)
(*    it again.                                                            *)
(* The spec keeps all of it: the trace validator compares logged values.  *)
(***************************************************************************)
MCId(n) == <<epoch[n], seq[n]>>
MCReceiver(n) == alive[n] \/ n \in unbooted
MCLiveMsg(msg) ==
    \E n \in Nodes :
        /\ MCReceiver(n)
        /\ \/ Newer(msg.epoch, msg.seq, epoch[n], seq[n])
           \/ /\ msg.kind = "Activate"
              /\ MCId(n) = <<msg.epoch, msg.seq>>
              /\ stage[n] \in {"Deactivating", "Prepared"}
MCLiveAck(a) ==
    \E m \in Nodes :
        /\ IsMaster(m)
        /\ <<a.epoch, a.seq>> = <<epoch[m], masterSeq[m]>>
        /\ \/ masterStage[m] = "Preparing"
           \/ masterStage[m] = "Activating" /\ a.kind = "Activated"
MCNodeView(n) ==
    IF ~alive[n] /\ n \notin unbooted
    THEN <<"crashed", epoch[n]>>
    ELSE <<role[n], epoch[n], seq[n], config[n], stage[n], active[n], unflushed[n],
           [t \in active[n] \cup unflushed[n] |-> version[n][t]],
           masterStage[n], masterConfig[n], masterSeq[n], failed[n]>>
MCView ==
    <<alive, unbooted, [n \in Nodes |-> MCNodeView(n)], stored,
      {msg \in msgs : MCLiveMsg(msg)}, {a \in acks : MCLiveAck(a)},
      crashes, phaseChanges>>
=============================================================================
