------------------------- MODULE HeartbeatLossAtLimit -------------------------
(***************************************************************************)
(* Not a broken protocol but a broken assumption: the channel loses        *)
(* MissLimit heartbeats in a row (the manifest sets MaxLoss = MissLimit),  *)
(* one more than AccuracyInv allows. The correct protocol then declares a  *)
(* running node failed, which shows that the accuracy bound is tight. TLC  *)
(* must report AccuracyInv violated (exit 12).                             *)
(***************************************************************************)
EXTENDS MCHeartbeat
=============================================================================
