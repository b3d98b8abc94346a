------------------------ MODULE HandoffNoHolderRestore ------------------------
(***************************************************************************)
(* Mutant of Handoff: without the Storage node a checkpointed task starts  *)
(* from version 0 on its new host, which asks no member of its view for    *)
(* the state its old host handed off (the rule before fault model 2, item  *)
(* 4; keel-sim's mutant no-holder-restore). When the Storage node's        *)
(* exclusion moves a task from a live host, its state is thrown away: TLC  *)
(* must report NoStateLossInv violated (exit 12).                          *)
(***************************************************************************)
EXTENDS MCHandoff

MutantNext ==
    \/ HSwitchNext
    \/ \E n \in Nodes, t \in Tasks : HActivateBy(n, t, FALSE, PlacedBefore)
    \/ HPlannedNext
    \/ HEnvironmentNext

MutantSpec == HInit /\ [][MutantNext]_everything
=============================================================================
