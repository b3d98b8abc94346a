------------------------- MODULE GroundExcludeUnchecked -------------------------
(***************************************************************************)
(* Mutant of Ground: an exclude every node accepts, without the walk of    *)
(* the graph. The ground excludes PN2, whose edge from A leads to SAFE; PN2 *)
(* resigns and PN1 excludes it into S1, no node crashed: TLC must report   *)
(* SafeOnlyByFailureInv violated.                                          *)
(***************************************************************************)
EXTENDS MCGround

Always(n, x) == TRUE

Unchecked(x) == ViewAgreed /\ GroundExcludeBy(Always, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, Unchecked, Readmit, HandOver)]_allVars
=============================================================================
