------------------------ MODULE LeaseTwoFaultsLapse -------------------------
(***************************************************************************)
(* Not a broken protocol but a property that two faults take away under    *)
(* Lease's count: with four monitors, a crashed Observer and another cut   *)
(* off (MCLeaseCrashCut), a healthy Master has two voters that may hold it *)
(* failed, which is Lease's quorum (two, or one when one voter is left,    *)
(* whatever the number of monitors), so its lease lapses, it resigns, and  *)
(* its successor excludes it on its own word before the crashed node is    *)
(* excluded. The runtime counts a majority of the view's members instead   *)
(* (Quorum.tla's Needed: three of four), which Lease.tla does not model.   *)
(* TLC must report NoFalseExclusionInv violated (exit 12);                 *)
(* NoExcludedRunsInv and AckBoundInv are MCLeaseCrashCut's.                *)
(***************************************************************************)
EXTENDS MCLeaseBig
=============================================================================
