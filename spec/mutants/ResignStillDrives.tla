-------------------------- MODULE ResignStillDrives --------------------------
(***************************************************************************)
(* Mutant of Resign: a Master that resigned still drives switches while it *)
(* flushes (NodeProtocol::resign without manager_.step_down): it starts a  *)
(* planned switch, or the switch of a failure, after its Resign: TLC must  *)
(* report ResignedRunsNothingInv violated (exit 12).                       *)
(***************************************************************************)
EXTENDS MCResign

AnyDriver(m) == TRUE

MutantSpec == RInit /\ [][RNextBy(TRUE, TRUE, AnyDriver)]_allVars
=============================================================================
