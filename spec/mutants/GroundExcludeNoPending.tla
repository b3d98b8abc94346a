------------------------ MODULE GroundExcludeNoPending ------------------------
(***************************************************************************)
(* Mutant of Ground: the Master's walk without its pending declared nodes  *)
(* (the nodes it holds out only). PN2 crashes; the ground excludes PN3 (A  *)
(* to B, safe alone), which PN1 holds out before it declares PN2; PN1      *)
(* walks PN3 alone and excludes it (B), then PN2 (S1), where PN2 alone     *)
(* leads to D: TLC must report SafeByFailuresInv violated.                 *)
(***************************************************************************)
EXTENDS MCGroundWalk

HeldOnly(m, x) ==
    /\ masterConfig[m] \notin SafeIds
    /\ GroundWalkOk(masterConfig[m], MasterHeld(m), x)

HeldOnlySwitch(m, x) == GroundExcludeSwitchBy(HeldOnly, Between, m, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, GroundExclude, HeldOnlySwitch, Readmit,
                                    HandOver)]_allVars
=============================================================================
