------------------------- MODULE GroundReadmitPending -------------------------
(***************************************************************************)
(* Ground with the readmit taken while the node's resignation is under way *)
(* (the runtime: ground_readmit lifts the hold at once). The ground        *)
(* excludes PN3, which resigns, and lets it back before PN1 excluded it;   *)
(* it then excludes PN1 (A to C, PN3 no longer held); PN2 takes over into  *)
(* C and excludes PN3 on its word into S2, no node crashed: TLC must       *)
(* report SafeOnlyByFailureInv violated.                                   *)
(***************************************************************************)
EXTENDS MCGround

MutantGNext ==
    \/ GNext
    \/ \E x \in Nodes : GroundReadmitBy(x)

MutantSpec == GInit /\ [][MutantGNext]_allVars
=============================================================================
