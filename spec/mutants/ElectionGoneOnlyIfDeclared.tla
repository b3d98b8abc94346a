----------------------- MODULE ElectionGoneOnlyIfDeclared -----------------------
(***************************************************************************)
(* Mutant of MasterElection: a node considers the Master of its epoch gone *)
(* only once it has declared it failed, and ignores what the Master's own  *)
(* heartbeats say. When that Master reboots quickly it is alive again, as  *)
(* a Worker, so nobody declares it failed and nobody takes over: the       *)
(* cluster stays without a Master. TLC must report MasterLiveness          *)
(* violated (exit 13).                                                     *)
(***************************************************************************)
EXTENDS MCMasterElection

DeclaredGone(n) ==
    \/ epoch[n] = 0
    \/ Owner(epoch[n]) = n
    \/ Owner(epoch[n]) \in suspects[n]

DeafBecomeMaster(n) ==
    /\ alive[n]
    /\ role[n] # "Master"
    /\ DeclaredGone(n)
    /\ Ahead(n) \subseteq suspects[n]
    /\ LET e == NextEpoch(n) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>

MutantNext ==
    \/ \E n, m \in Nodes : Suspect(n, m)
    \/ \E n \in Nodes : DeafBecomeMaster(n)
    \/ \E n \in Nodes : BroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ EnvironmentNext

MutantFairness ==
    /\ \A n, m \in Nodes : WF_vars(~alive[m] /\ Suspect(n, m))
    /\ \A n \in Nodes : WF_vars(DeafBecomeMaster(n))
    /\ \A n \in Nodes : WF_vars(BroadcastCommand(n))
    /\ \A n \in Nodes : WF_vars(\E msg \in msgs : ReceiveCommand(n, msg))

MutantSpec == Init /\ [][MutantNext]_vars /\ MutantFairness
=============================================================================
