----------------------- MODULE ExclusionNoLastMonitor -----------------------
(***************************************************************************)
(* Mutant of Exclusion: two declarations always, even when the Master is  *)
(* the last monitor left. A crashed Observer is then never excluded and    *)
(* what it hosted is never moved. TLC must report CompletenessInv          *)
(* violated (exit 12).                                                     *)
(***************************************************************************)
EXTENDS MCExclusion

TwoDeclarations(n) == 2

MutantSpec == Init /\ [][NextBy(Counts, TwoDeclarations)]_vars
=============================================================================
