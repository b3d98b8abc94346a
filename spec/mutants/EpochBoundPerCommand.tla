------------------------ MODULE EpochBoundPerCommand ------------------------
(***************************************************************************)
(* Mutant of EpochBound: the runtime's adoptable_epoch at 81049c4. The     *)
(* bound counts from the epoch last adopted, so adopting a Command of      *)
(* epoch e sets it to e + Lap whatever it was, and a run of the liar's     *)
(* Commands, each a lap above the last, moves a node any distance within   *)
(* one period. PN1 follows the liar PN3's 3, 6 and 9 in period 0, where    *)
(* the allowance is 7 (in the C++, 100 Commands move PN2 from 1 to 301 in  *)
(* under a millisecond): TLC must report LapPerPeriodInv violated (exit    *)
(* 12).                                                                    *)
(***************************************************************************)
EXTENDS MCEpochBound

ResetCeiling(n, s, e) ==
    IF e = epoch[n] THEN CeilingAfter(n, s, e) ELSE Capped(e + Lap)

MutantSpec == Init /\ [][NextBy(Knows, FirstBound, Ceiling, ResetCeiling, OpenOk)]_vars
=============================================================================
