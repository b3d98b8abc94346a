------------------------- MODULE GroundExcludeUnchecked -------------------------
(***************************************************************************)
(* Mutant of Ground: an exclude every node accepts, without the walk of    *)
(* the graph. The ground excludes PN3, which PN1 excludes (A to B); then   *)
(* PN1, the Master, whose edge from B leads to SAFE: PN1 steps down and    *)
(* PN2 takes over from B into S2, no node crashed: TLC must report         *)
(* SafeOnlyByFailureInv violated.                                          *)
(***************************************************************************)
EXTENDS MCGround

Always(n, x) == TRUE

Unchecked(x) == GroundExcludeBy(Always, ActingMaster, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, Unchecked, GroundExcludeSwitch, Readmit,
                                    HandOver)]_allVars
=============================================================================
