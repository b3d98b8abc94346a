----------------------- MODULE EpochBoundNoPeriodCap ------------------------
(***************************************************************************)
(* Mutant of EpochBound (c): no per-period growth cap. A node that knows   *)
(* its epoch adopts a Command of any epoch below the width: PN1, the first *)
(* Master, follows the liar PN3's epoch 9 at once, where the allowance is  *)
(* 7. TLC must report LapPerPeriodInv violated (exit 12).                  *)
(***************************************************************************)
EXTENDS MCEpochBound

AnyBelowWidth(n) == MaxAdoptable

MutantSpec ==
    Init /\ [][NextBy(Knows, FirstBound, AnyBelowWidth, CeilingAfter, OpenOk)]_vars
=============================================================================
