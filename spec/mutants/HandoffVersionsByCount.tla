------------------------ MODULE HandoffVersionsByCount ------------------------
(***************************************************************************)
(* Mutant of Handoff: the Storage node compares the states it is sent by   *)
(* their count of steps alone, not lineage first (the rule before          *)
(* lineages). After a start without the Storage node from an older state,  *)
(* the readmitted Storage node keeps the abandoned lineage's higher count, *)
(* and the task runs below it: TLC must report                             *)
(* HResumeLatestCheckpointInv violated (exit 12) in MCHandoffLineage.      *)
(***************************************************************************)
EXTENDS MCHandoff

StoresHigherCount(w, t) == w[3] > stored[t]

MutantNext ==
    \/ HSwitchNextBy(StoresHigherCount)
    \/ \E n \in Nodes, t \in Tasks : HActivate(n, t)
    \/ HPlannedNext
    \/ HEnvironmentNextBy(StoresHigherCount)

MutantSpec == HInit /\ [][MutantNext]_everything
=============================================================================
