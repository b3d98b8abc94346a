--------------------------- MODULE AskKeepsRunning ---------------------------
(***************************************************************************)
(* Mutant of AskExclusion: a node that asks to be excluded runs its tasks  *)
(* on until the exclusion reaches it (enforce_lease without the hold of a  *)
(* node that asked). The Master excludes it on its word at once and moves  *)
(* its tasks, a second running copy: TLC must report NoExcludedRunsInv     *)
(* violated (exit 12).                                                     *)
(***************************************************************************)
EXTENDS MCAskExclusion

MutantSpec == AInit /\ [][ANextBy(FALSE, TRUE)]_askVars
=============================================================================
