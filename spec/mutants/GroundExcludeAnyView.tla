------------------------- MODULE GroundExcludeAnyView -------------------------
(***************************************************************************)
(* Ground with the exclude taken whatever the views (the runtime: no node  *)
(* waits for the cluster to agree on its view). The ground excludes PN1,   *)
(* which resigns, and lets it back; PN2 takes over into C; PN3, still in A,*)
(* accepts the exclusion of PN3 (A to B) and resigns, where PN2 refused it *)
(* (C to S2); PN2 excludes PN3 on its word into SAFE, no node crashed: TLC *)
(* must report SafeOnlyByFailureInv violated.                              *)
(***************************************************************************)
EXTENDS MCGround

AnyView(x) == GroundExcludeBy(ExcludeAccepted, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, AnyView, Readmit, HandOver)]_allVars
=============================================================================
