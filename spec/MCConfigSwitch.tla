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

\* Configurations reachable with at most MaxCrashes failures.
MCConfigIds ==
    [phase : MCPhases,
     failed : {F \in SUBSET ProcessingNodes : Cardinality(F) <= MaxCrashes}]
MCInitialConfig == [phase |-> "P1", failed |-> {}]

MCPlacement(c, t) ==
    LET pref == MCPreference(c.phase, t)
        i == CHOOSE i \in 1..Len(pref) :
                /\ pref[i] \notin c.failed
                /\ \A j \in 1..(i - 1) : pref[j] \in c.failed
    IN  pref[i]

MCOnFailure(c, f) == [c EXCEPT !.failed = @ \cup {f}]

MCOnPhase(c) == {[c EXCEPT !.phase = IF @ = "P1" THEN "P2" ELSE "P1"]}
=============================================================================
