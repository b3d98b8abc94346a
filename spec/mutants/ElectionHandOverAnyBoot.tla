----------------------- MODULE ElectionHandOverAnyBoot -----------------------
(***************************************************************************)
(* Mutant of MasterElection: a hand-over's receiver ignores the boot it    *)
(* names. A node that restarts within the repeats of a hand-over meant for *)
(* its previous boot takes it in its new boot and is Master of the handed  *)
(* epoch, which its former Master adopted when it handed over: an epoch a  *)
(* running node held when the node restarted (keel-sim: PN1 Master of      *)
(* epoch 7 beside PN2's epoch 8). TLC must report NoStaleMastershipInv     *)
(* violated in MCMasterElectionHandOver (exit 12).                         *)
(***************************************************************************)
EXTENDS MCMasterElection

AnyBootTakeHandOver(r, h) ==
    /\ alive[r]
    /\ h \in handOvers
    /\ h.to = r
    /\ Fresh(r, h)
    /\ epoch' = [epoch EXCEPT ![r] = h.epoch]
    /\ role' = [role EXCEPT ![r] = "Master"]
    /\ leader' = [leader EXCEPT ![r] = r]
    /\ lastCommand' = [lastCommand EXCEPT ![r] = h.epoch]
    /\ suspects' = IF h.epoch > epoch[r]
                      THEN [suspects EXCEPT ![r] = @ \ {h.from}]
                      ELSE suspects
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>

MutantNext ==
    \/ \E n, m \in Nodes : Suspect(n, m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes : WarmBoot(n)
    \/ \E n \in Nodes : BroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ \E m, r \in Nodes : HandOver(m, r)
    \/ \E r \in Nodes, h \in handOvers : AnyBootTakeHandOver(r, h)
    \/ EnvironmentNext

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
