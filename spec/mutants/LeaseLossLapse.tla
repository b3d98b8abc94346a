-------------------------- MODULE LeaseLossLapse ----------------------------
(***************************************************************************)
(* Not a broken protocol but a property that loss takes away: with loss on *)
(* healthy links (MCLeaseLossy: MissLimit 3, MaxLoss 1, on heartbeats and  *)
(* on the acknowledgements they carry) the lease of a healthy Master may   *)
(* lapse, its heartbeat to a voter and then the voter's acknowledgement    *)
(* lost in consecutive periods, for as many voters as its lease counts     *)
(* (one, once another monitor is excluded: a crashed Observer, or a Master *)
(* with omission faults, as in TLC's counterexample); it resigns, and its  *)
(* successor excludes it on its own word. docs/fault-model.md names this   *)
(* lapse ("Lapses without a fault are possible under heavy loss"). TLC     *)
(* must report NoFalseExclusionInv violated (exit 12); the lease's own     *)
(* properties, NoExcludedRunsInv and AckBoundInv, are MCLeaseLossy's.      *)
(***************************************************************************)
EXTENDS MCLeaseBig
=============================================================================
