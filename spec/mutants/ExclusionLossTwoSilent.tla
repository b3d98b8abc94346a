---------------------- MODULE ExclusionLossTwoSilent ------------------------
(***************************************************************************)
(* Not a broken protocol but a bound that does not reach: MissLimit 3 with *)
(* MaxLoss 2 on healthy links (the manifest sets it; Exclusion allows any  *)
(* MaxLoss < MissLimit). A healthy monitor may then hear no one for two    *)
(* periods in a row, and ExcludeBound = 2 * MissLimit + 1 assumes at most  *)
(* every other period silent: a crashed node is still not excluded more    *)
(* than ExcludeBound periods after its crash. TLC must report              *)
(* CompletenessInv violated (exit 12).                                     *)
(***************************************************************************)
EXTENDS MCExclusionBig
=============================================================================
