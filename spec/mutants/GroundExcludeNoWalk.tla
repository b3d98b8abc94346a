------------------------- MODULE GroundExcludeNoWalk -------------------------
(***************************************************************************)
(* Mutant of Ground: the Master excludes a node it holds out without its   *)
(* walk (WalkOk TRUE). PN2 crashes; the ground excludes PN3 (A to B, safe  *)
(* alone), which PN1 holds out before it declares PN2; PN1 excludes PN2    *)
(* (A to D), then PN3, whose edge from D is S1, where PN2 alone leads to   *)
(* D: TLC must report SafeByFailuresInv violated.                          *)
(***************************************************************************)
EXTENDS MCGroundWalk

NoWalk(m, x) == TRUE

NoWalkSwitch(m, x) == GroundExcludeSwitchBy(NoWalk, Between, m, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, GroundExclude, NoWalkSwitch, Readmit,
                                    HandOver)]_allVars
=============================================================================
