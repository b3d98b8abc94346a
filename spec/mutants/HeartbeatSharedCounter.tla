------------------------ MODULE HeartbeatSharedCounter ------------------------
(***************************************************************************)
(* Mutant of Heartbeat: one "last heartbeat" per monitor instead of one    *)
(* per watched node. Any heartbeat that arrives counts as a sign of life   *)
(* of every node, so while other nodes keep sending, a crashed node is     *)
(* never missed. TLC must report CompletenessInv violated (exit 12).      *)
(***************************************************************************)
EXTENDS MCHeartbeat

SharedReceiveHeartbeat(m, n) ==
    /\ <<n, m>> \in inFlight
    /\ alive[m]
    /\ inFlight' = inFlight \ {<<n, m>>}
    /\ heard' = [heard EXCEPT ![m] = Nodes]
    /\ lossRun' = [lossRun EXCEPT ![m][n] = 0]
    /\ UNCHANGED <<alive, sent, missed, failed, downFor,
                   heardOnce, unbooted, clock>>

MutantNext ==
    \/ \E n \in Nodes : SendHeartbeat(n)
    \/ \E m \in Monitors, n \in Nodes : SharedReceiveHeartbeat(m, n)
    \/ Tick
    \/ \E m \in Monitors, n \in Nodes : DeclareFailed(m, n)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m)
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : Boot(n)

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
