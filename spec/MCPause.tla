------------------------------ MODULE MCPause -------------------------------
(***************************************************************************)
(* The model of Pause: PN1 (the Master) and PN2, ST1 the Storage node; the *)
(* checkpointed task t1, which the ground may pause, and the essential t2, *)
(* which it may not. Two phases place them crosswise, so a planned switch  *)
(* moves both:                                                             *)
(*                                                                         *)
(*   config  t1    t2                                                      *)
(*   P1      PN2   PN1     (initial)                                       *)
(*   P2      PN1   PN2                                                     *)
(*                                                                         *)
(* No crash (ConfigSwitch's models cover them; a crashed node holds        *)
(* nothing), two planned switches (P1 to P2 and back), a task runs one     *)
(* step, three ground commands, each reaching any set of running nodes.    *)
(***************************************************************************)
EXTENDS Pause

CONSTANTS PN1, PN2, t1, t2

MCPriority == <<PN1, PN2>>
MCConfigIds == {"P1", "P2"}
MCInitialConfig == "P1"
MCPlacement(c, t) == IF (c = "P1") = (t = t1) THEN PN2 ELSE PN1
MCOnFailure(c, f) == c
MCOnPhase(c) == {IF c = "P1" THEN "P2" ELSE "P1"}

\* Witness: a task activated at a node that held it paused (moved there, not started),
\* resumed there, and run there.
WitnessResumedAfterMoveInv == ~\E n \in Nodes, t \in Tasks : <<"ranResumed", n, t>> \in hist
=============================================================================
