------------------------- MODULE GroundExcludeAnyView -------------------------
(***************************************************************************)
(* Ground with the rule before: the node the ground names resigns on its   *)
(* own check, whatever its view, Master or not. TLC must report            *)
(* SafeOnlyByFailureInv violated.                                          *)
(***************************************************************************)
EXTENDS MCGround

AnyNode(x) == TRUE

AnyView(x) == GroundExcludeBy(ExcludeAccepted, AnyNode, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, AnyView, GroundExcludeSwitch, Readmit,
                                    HandOver)]_allVars
=============================================================================
