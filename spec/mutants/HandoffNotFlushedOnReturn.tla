----------------------- MODULE HandoffNotFlushedOnReturn -----------------------
(***************************************************************************)
(* Mutant of Handoff: a node that adopts a view which includes the Storage *)
(* node again does not flush to it the hand-offs it made while its view    *)
(* excluded the Storage node, and acks "Prepared" without them (keel-sim's *)
(* mutant handoff-not-flushed). When a Master whose view predates the      *)
(* Storage node's exclusion takes over and places a task back on the node  *)
(* that holds its newest state as such a hand-off, that node starts it     *)
(* from the Storage node, below its own hand-off: TLC must report          *)
(* NoStateLossInv violated (exit 12).                                      *)
(***************************************************************************)
EXTENDS MCHandoff

MutantNext ==
    \/ \E m \in Nodes : HBootSwitch(m)
    \/ \E m, f \in Nodes : HExclude(m, f)
    \/ \E m \in Nodes : DeclareStorageFailed(m)
    \/ \E m \in Nodes : ReadmitStorageBy(m, FALSE)
    \/ \E m \in Nodes : HBroadcastActivate(m)
    \/ \E m \in Nodes : HCompleteSwitch(m)
    \/ \E n \in Nodes : HBecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : HReceiveCommandBy(n, msg, FALSE, TRUE)
    \/ \E n \in Nodes, t \in Tasks : HDeactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : HFlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : HAck(n, k)
    \/ \E n \in Nodes, msg \in msgs : HReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : HActivate(n, t)
    \/ HPlannedNext
    \/ HEnvironmentNext

MutantSpec == HInit /\ [][MutantNext]_everything
=============================================================================
