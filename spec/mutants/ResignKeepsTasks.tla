-------------------------- MODULE ResignKeepsTasks --------------------------
(***************************************************************************)
(* Mutant of Resign: a Master that resigns stops driving but keeps its     *)
(* tasks running (ConfigSwitch::resign without deactivate). Its successor  *)
(* takes over once it is done and starts them elsewhere, a second running  *)
(* copy: TLC must report NoDoubleActivationInv violated (exit 12).         *)
(***************************************************************************)
EXTENDS MCResign

MutantSpec == RInit /\ [][RNextBy(FALSE, TRUE, Acting)]_allVars
=============================================================================
