-------------------------- MODULE ElectionNoEpochCheck --------------------------
(***************************************************************************)
(* Mutant of MasterElection: election without the epoch check. A node     *)
(* obeys every command it receives, whatever its epoch, so a deposed       *)
(* Master's late command drags a node back to a stale epoch. TLC must     *)
(* report StaleCommandRejectedProp violated (exit 12).                    *)
(***************************************************************************)
EXTENDS MCMasterElection

UncheckedReceiveCommand(n, msg) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.from # n
    /\ msg.epoch # epoch[n] \/ leader[n] # msg.from
    /\ epoch' = [epoch EXCEPT ![n] = msg.epoch]
    /\ leader' = [leader EXCEPT ![n] = msg.from]
    /\ lastCommand' = [lastCommand EXCEPT ![n] = msg.epoch]
    /\ role' = IF msg.epoch # epoch[n]
                  THEN [role EXCEPT ![n] = RoleIn(n, msg.epoch)]
                  ELSE role
    /\ suspects' = [suspects EXCEPT ![n] = @ \ {msg.from}]
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>

MutantNext ==
    \/ \E n, m \in Nodes : Suspect(n, m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes : BroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : UncheckedReceiveCommand(n, msg)
    \/ EnvironmentNext

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
