------------------------ MODULE GroundResignNoPending ------------------------
(***************************************************************************)
(* Mutant of Ground: every node's check of an exclude without its pending  *)
(* declared nodes (the nodes it holds out and the node named). PN2 crashes *)
(* and PN1, the Master, declares it; the ground excludes PN1, which walks  *)
(* itself alone (A to C) and steps down; PN3 takes over for PN1 and PN2    *)
(* (A to C to S3), where PN2 alone leads to D: TLC must report             *)
(* SafeByFailuresInv violated.                                             *)
(***************************************************************************)
EXTENDS MCGroundWalk

HeldAnd(n, x) == (heldOut[n] \ ViewFailed(n)) \cup {x}

NoPendingCheck(x) ==
    GroundExcludeBy(LAMBDA n, y : ExcludeAcceptedBy(HeldAnd, n, y), ActingMaster, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, NoPendingCheck, GroundExcludeSwitch,
                                    Readmit, HandOver)]_allVars
=============================================================================
