------------------------- MODULE GroundExcludeOwnOnly -------------------------
(***************************************************************************)
(* Mutant of Ground: the exclude check walks the graph for the node alone, *)
(* not for the nodes held out already that the view has not excluded yet.  *)
(* The ground excludes PN3 (A to B), then, before PN1 excludes it, PN1     *)
(* (A to C); together they lead to S2: PN2 takes over into C and excludes *)
(* PN3 into SAFE, no node crashed: TLC must report SafeOnlyByFailureInv    *)
(* violated.                                                               *)
(***************************************************************************)
EXTENDS MCGround

Alone(n, x) == <<x>>

OwnOnly(x) == ViewAgreed /\ GroundExcludeBy(LAMBDA n, y : ExcludeAcceptedBy(Alone, n, y), x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, OwnOnly, Readmit, HandOver)]_allVars
=============================================================================
