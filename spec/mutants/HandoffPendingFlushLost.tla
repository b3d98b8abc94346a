------------------------ MODULE HandoffPendingFlushLost ------------------------
(***************************************************************************)
(* Mutant of Handoff: a node that adopts a view which excludes the Storage *)
(* node drops the final flushes still pending there without making their   *)
(* hand-offs unstored (the Master's own switch in DeclareStorageFailed     *)
(* too). A node that deactivated a task with the Storage node in its view  *)
(* and then adopts its exclusion has nothing to flush when the Storage     *)
(* node is readmitted, and the task's next host starts it from the Storage *)
(* node, below that hand-off: TLC must report NoStateLossInv violated      *)
(* (exit 12).                                                              *)
(***************************************************************************)
EXTENDS MCHandoff

MutantNext ==
    \/ \E m \in Nodes : HBootSwitch(m)
    \/ \E m, f \in Nodes : HExclude(m, f)
    \/ \E m \in Nodes : DeclareStorageFailedBy(m, FALSE)
    \/ \E m \in Nodes : ReadmitStorage(m)
    \/ \E m \in Nodes : HBroadcastActivate(m)
    \/ \E m \in Nodes : HCompleteSwitch(m)
    \/ \E n \in Nodes : HBecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : HReceiveCommandBy(n, msg, TRUE, FALSE)
    \/ \E n \in Nodes, t \in Tasks : HDeactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : HFlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : HAck(n, k)
    \/ \E n \in Nodes, msg \in msgs : HReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : HActivate(n, t)
    \/ HPlannedNext
    \/ HEnvironmentNext

MutantSpec == HInit /\ [][MutantNext]_everything
=============================================================================
