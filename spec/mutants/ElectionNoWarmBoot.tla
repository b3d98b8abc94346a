--------------------------- MODULE ElectionNoWarmBoot ---------------------------
(***************************************************************************)
(* Mutant of MasterElection: no warm boot. After a whole-cluster power     *)
(* cycle every node waits to be commanded and none claims an epoch, so the *)
(* cluster never has a Master again (the runtime before WarmBoot: every    *)
(* node had to be restarted with --cold-start). TLC must report            *)
(* RecoveryLiveness violated in MCMasterElectionPowerCycle (exit 13).      *)
(***************************************************************************)
EXTENDS MCMasterElection

MutantProtocolNext ==
    \/ \E n, m \in Nodes : Suspect(n, m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes : BroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)

MutantNext == MutantProtocolNext \/ EnvironmentNext

MutantFairness ==
    /\ \A n, m \in Nodes : WF_vars(~alive[m] /\ Suspect(n, m))
    /\ \A n \in Nodes : WF_vars(BecomeMaster(n))
    /\ \A n \in Nodes : WF_vars(BroadcastCommand(n))
    /\ \A n \in Nodes : WF_vars(\E msg \in msgs : ReceiveCommand(n, msg))

MutantSpec == Init /\ [][MutantNext]_vars /\ MutantFairness
=============================================================================
