--------------------------- MODULE LeaseStepDownEager ---------------------------
(***************************************************************************)
(* Mutant of LeaseStepDown: a Master steps down as "cut off" without a     *)
(* silent period (any time). Its successor takes over on its word, and a  *)
(* healthy Master is out of the cluster: TLC must report                   *)
(* NoFalseExclusionInv violated (exit 12).                                 *)
(***************************************************************************)
EXTENDS MCLeaseStepDown

MutantSpec == SInit /\ [][SNextBy(0)]_stepDownVars
=============================================================================
