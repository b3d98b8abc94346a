-------------------------- MODULE ElectionNoOwnership --------------------------
(***************************************************************************)
(* Mutant of MasterElection: epochs not tied to the priority order. Any    *)
(* node that sees the Master gone claims epoch[n] + 1 at once, without     *)
(* waiting for the nodes ahead of it, so the higher- and the lower-        *)
(* priority Observer both become Master of the same epoch. TLC must       *)
(* report OneMasterPerEpochInv violated (exit 12).                         *)
(***************************************************************************)
EXTENDS MCMasterElection

GreedyBecomeMaster(n) ==
    /\ alive[n]
    /\ role[n] # "Master"
    /\ MasterGone(n)
    /\ LET e == epoch[n] + 1 IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>

MutantNext ==
    \/ \E n, m \in Nodes : Suspect(n, m)
    \/ \E n \in Nodes : GreedyBecomeMaster(n)
    \/ \E n \in Nodes : BroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ EnvironmentNext

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
