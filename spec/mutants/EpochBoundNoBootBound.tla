----------------------- MODULE EpochBoundNoBootBound ------------------------
(***************************************************************************)
(* Mutant of EpochBound (a): a node that knows no epoch follows its first  *)
(* Command whatever its epoch, below the width (no corroboration: the      *)
(* runtime before keel-sim liar seed 12942). PN2, booting, follows the     *)
(* liar PN3's first Command of epoch 9 at once, while PN1 is at 1 and the  *)
(* allowance is 7: TLC must report LapPerPeriodInv violated (exit 12).     *)
(***************************************************************************)
EXTENDS MCEpochBound

AnyFirst(n, s, e) == TRUE

MutantSpec == Init /\ [][NextBy(Knows, AnyFirst, Ceiling, CeilingAfter, OpenOk)]_vars
=============================================================================
