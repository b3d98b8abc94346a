----------------------------- MODULE MCHandoff -----------------------------
(***************************************************************************)
(* Models of Handoff for CI: MCHandoff.cfg (a phase change, a crash, and   *)
(* the Storage node failing for good), MCHandoffReturn.cfg (the same, but  *)
(* the Storage node may run again, not readmitted: a take-over by a Master *)
(* whose view predates its exclusion includes it again),                   *)
(* MCHandoffPause.cfg (a phase change, the Storage node paused: it may be  *)
(* excluded meanwhile and runs again, not readmitted; no crash) and        *)
(* MCHandoffReadmit.cfg (the same, and the Master may readmit it once),    *)
(* MCHandoffLineage.cfg (MCHandoffReadmit with a crash: a task's host      *)
(* crashes, the Storage node paused holds its state, the task starts       *)
(* again from nothing, and the Storage node is readmitted).                *)
(*                                                                         *)
(* The paper's prototype: PN1 the Master, PN2 and PN3 the Observers, ST1   *)
(* the Storage node; one checkpointed task. A configuration id is a        *)
(* mission phase and the set of nodes its view excludes, the Storage node  *)
(* among them (the decision graph adds a failed node, a readmission        *)
(* removes it, a planned phase change swaps the phase). The task goes to   *)
(* the first node of its preference list that the view does not exclude:   *)
(* Priority rotated by one (PN2, PN3, PN1) in phase P1, by two (PN3, PN1,  *)
(* PN2) in P2, and, as in prototype3's graph (its SAFE configuration),     *)
(* Priority itself, the Master first, when the view excludes ST1. So the   *)
(* phase change moves the task between live nodes with the Storage node in *)
(* the view (the final flush; a hand-off the Storage node holds too), the  *)
(* Storage node's exclusion moves it while its old host is alive (a        *)
(* hand-off held nowhere else), and a crash moves it from a host that took *)
(* its state along (the out-of-reach case).                                *)
(***************************************************************************)
EXTENDS Handoff

CONSTANTS PN1, PN2, PN3, ST1, t1

MCPriority == <<PN1, PN2, PN3>>

\* The mission phases.
MCPhases == {"P1", "P2"}

\* Priority rotated left by k places.
Rotate(s, k) == [i \in 1..Len(s) |-> s[((i - 1 + k) % Len(s)) + 1]]

\* Where the task prefers to run: by phase, or on the Master first when the view excludes
\* the Storage node (prototype3's SAFE).
MCPreference(c) ==
    IF Storage \in c.failed THEN Priority
    ELSE IF c.phase = "P1" THEN Rotate(Priority, 1) ELSE Rotate(Priority, 2)

\* Views with at most MaxCrashes + MaxLateBoots processing nodes excluded, with or without
\* the Storage node.
MCConfigIds ==
    [phase : MCPhases,
     failed : {F \in SUBSET (ProcessingNodes \cup {Storage}) :
                 Cardinality(F \ {Storage}) <= MaxCrashes + MaxLateBoots}]
MCInitialConfig == [phase |-> "P1", failed |-> {}]

ASSUME MCBudgetAssumption == MaxCrashes + MaxLateBoots < Len(Priority)

MCPlacement(c, t) ==
    LET pref == MCPreference(c)
        i == CHOOSE i \in 1..Len(pref) :
                /\ pref[i] \notin c.failed
                /\ \A j \in 1..(i - 1) : pref[j] \in c.failed
    IN  pref[i]

MCOnFailure(c, f) == [c EXCEPT !.failed = @ \cup {f}]
MCOnReadmit(c, x) == [c EXCEPT !.failed = @ \ {x}]
MCOnPhase(c) == {[c EXCEPT !.phase = IF @ = "P1" THEN "P2" ELSE "P1"]}
MCViewFailed(c) == c.failed

(***************************************************************************)
(* Reduction: MCHView, as MCConfigSwitch's MCView (see there for why each  *)
(* part is dead for good), with the new variables: a crashed node's        *)
(* hand-offs, placedBefore and hostLost are hidden with the rest of its    *)
(* variables (no step reads a crashed node's hand-off: gathering and Reach *)
(* read alive nodes only); a node's version of a task is kept while it     *)
(* runs it, has it to flush or holds it as a hand-off (Activate overwrites *)
(* every other version before anything reads it). `unrecoverable` is kept: *)
(* it is the runtime's counter. Everything the properties and witnesses    *)
(* read is in the view.                                                    *)
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
           [t \in active[n] \cup unflushed[n] \cup handoff[n] |-> StateOf(n, t)],
           masterStage[n], masterConfig[n], masterSeq[n], failed[n], handoff[n],
           unstored[n], placedBefore[n], hostLost[n]>>
MCHView ==
    <<alive, unbooted, [n \in Nodes |-> MCNodeView(n)], stored, storedLineage,
      {msg \in msgs : MCLiveMsg(msg)}, {a \in acks : MCLiveAck(a)},
      crashes, phaseChanges, storageUp, storageFaults, readmissions, unrecoverable,
      start, saved>>

(***************************************************************************)
(* Witnesses: each is an invariant TLC must find violated (manifest        *)
(* "witnesses"): the states the properties are about are reachable.        *)
(***************************************************************************)
\* A task started from another node's hand-off, at a version above 0, the Storage node
\* being excluded in the starting node's view (item 4's case).
WitnessHolderRestoreInv ==
    \A t \in Tasks : ~(start[t].how = "Holder" /\ start[t].version[3] > 0)
\* An unrecoverable start of a task that had a saved state above version 0: the Storage
\* node and the task's host both failed, and the state was out of reach.
WitnessUnrecoverableStartInv ==
    \A t \in Tasks : ~(start[t].how = "Lost" /\ Gt(start[t].saved, Zero))
\* The Storage node holds a state of the lineage an unrecoverable start opened, with fewer
\* steps than the abandoned state that was saved before it (MCHandoffLineage: the new
\* lineage replaces the abandoned one however many steps that one had).
WitnessLineageReplacesInv ==
    \A t \in Tasks :
        ~(/\ start[t].how = "Lost"
          /\ start[t].saved[3] > stored[t]
          /\ storedLineage[t] = start[t].opened)
\* A task runs above version 0 on a node whose view excludes the Storage node: its
\* progress is saved nowhere else.
WitnessAdvanceWithoutStorageInv ==
    \A n \in Nodes, t \in Tasks :
        ~(alive[n] /\ t \in active[n] /\ ~StorageAvailable(n) /\ version[n][t] > 0)
=============================================================================
