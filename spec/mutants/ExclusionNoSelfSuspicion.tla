---------------------- MODULE ExclusionNoSelfSuspicion ----------------------
(***************************************************************************)
(* Mutant of Exclusion: a monitor counts a period in which it heard no one *)
(* (no self-suspicion). A deaf Master, the last monitor once the Observer  *)
(* crashed, declares and excludes every healthy node. TLC must report      *)
(* NoFalseExclusionInv violated (exit 12).                                 *)
(***************************************************************************)
EXTENDS MCExclusion

CountsEvenSilent(m) == m \notin late

MutantSpec == Init /\ [][NextBy(CountsEvenSilent, Needed)]_vars
=============================================================================
