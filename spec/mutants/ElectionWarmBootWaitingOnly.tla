--------------------- MODULE ElectionWarmBootWaitingOnly ---------------------
(***************************************************************************)
(* Mutant of MasterElection: the warm boot counts only the nodes that      *)
(* wait (restarted, not commanded since), not the fenced ones (keel-sim's  *)
(* --mutant warm-boot-waiting-only). A Master that fenced both other nodes *)
(* crashes and restarts: it waits, the fenced nodes wait to be readmitted  *)
(* and never claim an epoch, and nobody warm-boots, so the cluster never   *)
(* has a Master again. TLC must report RecoveryLiveness violated in        *)
(* MCMasterElectionFenced (exit 13).                                       *)
(***************************************************************************)
EXTENDS MCMasterElection

WaitingOnlyWarmBoot(n) == WarmBootBy(Waiting, n)

MutantProtocolNext ==
    \/ \E n, m \in Nodes : Suspect(n, m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes : WaitingOnlyWarmBoot(n)
    \/ \E n \in Nodes : BroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ \E m, n \in Nodes : Fence(m, n)
    \/ \E n, m \in Nodes : SuspectFenced(n, m)
    \/ \E m, n \in Nodes : Readmit(m, n)

MutantNext == MutantProtocolNext \/ EnvironmentNext

MutantFairness ==
    /\ \A n, m \in Nodes : WF_vars(~alive[m] /\ Suspect(n, m))
    /\ \A n, m \in Nodes : WF_vars(SuspectFenced(n, m))
    /\ \A n \in Nodes : WF_vars(BecomeMaster(n))
    /\ WF_vars(\E n \in Nodes : WaitingOnlyWarmBoot(n))
    /\ \A n \in Nodes : WF_vars(BroadcastCommand(n))
    /\ \A n \in Nodes : WF_vars(\E msg \in msgs : ReceiveCommand(n, msg))

MutantSpec == Init /\ [][MutantNext]_vars /\ MutantFairness
=============================================================================
