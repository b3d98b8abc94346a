-------------------------- MODULE AskAnyNotification --------------------------
(***************************************************************************)
(* Mutant of AskExclusion: the Master takes every ErrorNotification as the *)
(* word of the node it names, not only one that names its sender (the      *)
(* handler without failed_node == from). A partly deaf Observer's report   *)
(* of a healthy node excludes it without a second monitor's evidence: TLC  *)
(* must report OwnWordExclusionInv violated (exit 12).                     *)
(***************************************************************************)
EXTENDS MCAskExclusion

MutantSpec == AInit /\ [][ANextBy(TRUE, FALSE)]_askVars
=============================================================================
