------------------------ MODULE ExclusionNoLateCheck ------------------------
(***************************************************************************)
(* Mutant of Exclusion: a monitor counts a period in which its own loop    *)
(* ran late (it heard someone, so it does not suspect itself). A stalled   *)
(* Master, the last monitor, declares and excludes a node whose heartbeat  *)
(* it did not get to in time. TLC must report NoFalseExclusionInv violated *)
(* (exit 12).                                                              *)
(***************************************************************************)
EXTENDS MCExclusion

CountsEvenLate(m) == heard[m] # {}

MutantSpec == Init /\ [][NextBy(CountsEvenLate, Needed)]_vars
=============================================================================
