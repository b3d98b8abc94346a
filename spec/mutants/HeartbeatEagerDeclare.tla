------------------------- MODULE HeartbeatEagerDeclare -------------------------
(***************************************************************************)
(* Mutant of Heartbeat: a threshold that ignores loss. The monitor         *)
(* declares a node failed after a single missed period instead of          *)
(* MissLimit, so one lost heartbeat (which the channel may drop) takes     *)
(* down a running node. TLC must report AccuracyInv violated (exit 12).   *)
(***************************************************************************)
EXTENDS MCHeartbeat

EagerDeclareFailed(m, n) ==
    /\ alive[m]
    /\ n \in Watched(m)
    /\ n \notin failed[m]
    /\ missed[m][n] >= 1
    /\ failed' = [failed EXCEPT ![m] = @ \cup {n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, missed, downFor,
                   heardOnce, unbooted, clock>>

MutantNext ==
    \/ \E n \in Nodes : SendHeartbeat(n)
    \/ \E m \in Monitors, n \in Nodes : ReceiveHeartbeat(m, n)
    \/ Tick
    \/ \E m \in Monitors, n \in Nodes : EagerDeclareFailed(m, n)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m)
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : Boot(n)

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
