------------------------ MODULE ElectionRestartKeepsRole ------------------------
(***************************************************************************)
(* Mutant of MasterElection: the role is persisted with the epoch. A       *)
(* Master that crashes and reboots comes back as Master of its old epoch,  *)
(* after the others have moved on: a resurrected stale mastership. TLC     *)
(* must report NoStaleMastershipInv violated (exit 12).                    *)
(***************************************************************************)
EXTENDS MCMasterElection

PersistentRestart(n) ==
    /\ ~alive[n]
    /\ restarts < MaxRestarts
    /\ \A x \in Nodes : alive[x] => n \in suspects[x]
    /\ alive' = [alive EXCEPT ![n] = TRUE]
    /\ epoch' = [epoch EXCEPT ![n] = RejoinEpoch(n)]
    /\ suspects' = [suspects EXCEPT ![n] = {}]
    /\ boot' = [boot EXCEPT ![n] = NewBoot(n)]
    /\ restartEpoch' = [restartEpoch EXCEPT ![n] = RejoinEpoch(n)]
    /\ restarts' = restarts + 1
    /\ UNCHANGED <<role, leader, lastCommand, msgs, handOvers, crashes, falseSuspicions,
                   handOverCount, fenced, fenceCount>>

MutantNext ==
    \/ ProtocolNext
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : PersistentRestart(n)

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
