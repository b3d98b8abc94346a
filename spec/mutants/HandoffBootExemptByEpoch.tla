----------------------- MODULE HandoffBootExemptByEpoch -----------------------
(***************************************************************************)
(* Mutant of Handoff: a start without state counts as unrecoverable only   *)
(* in an epoch after the first, as if the boot switch were told by the     *)
(* epoch alone (the runtime tells it by the view left: epoch 1, seq 0). A  *)
(* task that had run, started afresh after the Storage node and its host   *)
(* failed under the first Master, is then not reported: TLC must report    *)
(* UnrecoverableReportedInv violated (exit 12).                            *)
(***************************************************************************)
EXTENDS MCHandoff

\* The mutant's rule: whether a start without state is counted.
AfterFirstEpoch(n) == epoch[n] > 1

MutantNext ==
    \/ HSwitchNext
    \/ \E n \in Nodes, t \in Tasks : HActivateBy(n, t, TRUE, AfterFirstEpoch)
    \/ HPlannedNext
    \/ HEnvironmentNext

MutantSpec == HInit /\ [][MutantNext]_everything
=============================================================================
