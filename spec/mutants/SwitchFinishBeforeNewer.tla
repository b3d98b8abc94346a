------------------------- MODULE SwitchFinishBeforeNewer -------------------------
(***************************************************************************)
(* Mutant of ConfigSwitch: a node in the middle of a switch ignores newer  *)
(* commands until it has finished the current switch. When the Master      *)
(* crashes before sending Activate, the nodes that acked "Prepared" wait   *)
(* for an Activate that never comes and never take the new Master's        *)
(* command: the interrupted switch does not converge. TLC must report      *)
(* SwitchConverges violated (exit 13).                                     *)
(***************************************************************************)
EXTENDS MCConfigSwitch

StubbornReceiveCommand(n, msg) ==
    /\ stage[n] = "Stable"
    /\ ReceiveCommand(n, msg)

MutantProtocolNext ==
    \/ \E m \in Nodes : BootSwitch(m)
    \/ \E m, f \in Nodes : Exclude(m, f)
    \/ \E m \in Nodes : BroadcastActivate(m)
    \/ \E m \in Nodes : CompleteSwitch(m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : StubbornReceiveCommand(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Deactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : FlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : Ack(n, k)
    \/ \E n \in Nodes, msg \in msgs : ReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Activate(n, t)

MutantSpec ==
    Init /\ [][MutantProtocolNext \/ PlannedNext \/ EnvironmentNext]_vars
         /\ WF_vars(MutantProtocolNext) /\ \A n \in Nodes : WF_vars(Boot(n))
=============================================================================
