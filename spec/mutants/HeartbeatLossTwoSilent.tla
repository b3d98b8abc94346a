---------------------- MODULE HeartbeatLossTwoSilent ------------------------
(***************************************************************************)
(* Not a broken protocol but a bound that does not reach: MissLimit 3 with *)
(* MaxLoss 2 (the manifest sets it; accuracy allows MissLimit - 1). Both   *)
(* links to a monitor may then lose two heartbeats in a row, so the        *)
(* monitor may hear no one for two periods in a row, and                   *)
(* DetectionBoundTicks = 2 * MissLimit + 1 = 7 assumes at most every other *)
(* period silent (TLC's shortest counterexample: the monitor's count of a  *)
(* crashed node reaches MissLimit at the eighth tick after the crash). TLC *)
(* must report CompletenessInv violated (exit 12).                         *)
(***************************************************************************)
EXTENDS MCHeartbeat
=============================================================================
