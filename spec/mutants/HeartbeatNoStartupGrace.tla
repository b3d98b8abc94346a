------------------------ MODULE HeartbeatNoStartupGrace ------------------------
(***************************************************************************)
(* Mutant of Heartbeat: a monitor without the start-up grace. A node it    *)
(* has never heard is declared after MissLimit missed periods like any     *)
(* other, so a node that boots a few periods after the monitor is declared *)
(* failed before it boots (or before its first heartbeat gets through).    *)
(* TLC must report AccuracyInv violated (exit 12).                         *)
(***************************************************************************)
EXTENDS MCHeartbeat

GracelessPending(m, n) == missed[m][n] >= MissLimit /\ n \notin failed[m]

GracelessTick ==
    /\ \A n \in Nodes : alive[n] => sent[n]
    /\ inFlight = {}
    /\ \A m \in Monitors : alive[m] => \A n \in Watched(m) : ~GracelessPending(m, n)
    /\ unbooted # {} => clock < MaxBootDelay
    /\ missed' = [m \in Monitors |->
                    [n \in Nodes |->
                        IF alive[m] /\ n \in Watched(m) /\ n \notin failed[m]
                        THEN IF n \in heard[m] THEN 0
                             ELSE Min(missed[m][n] + 1, MissLimit)
                        ELSE missed[m][n]]]
    /\ heardOnce' = [m \in Monitors |->
                       IF alive[m] THEN heardOnce[m] \cup heard[m] ELSE heardOnce[m]]
    /\ heard' = [m \in Monitors |-> {}]
    /\ sent' = [n \in Nodes |-> FALSE]
    /\ downFor' = [n \in Nodes |->
                     IF alive[n] \/ n \in unbooted THEN 0
                     ELSE Min(downFor[n] + 1, DownForCap(n))]
    /\ clock' = Min(clock + 1, MaxBootDelay)
    /\ UNCHANGED <<alive, inFlight, lossRun, failed, unbooted>>

GracelessDeclareFailed(m, n) ==
    /\ alive[m]
    /\ n \in Watched(m)
    /\ n \notin failed[m]
    /\ missed[m][n] >= MissLimit
    /\ failed' = [failed EXCEPT ![m] = @ \cup {n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, missed, downFor, heardOnce,
                   unbooted, clock>>

MutantNext ==
    \/ \E n \in Nodes : SendHeartbeat(n)
    \/ \E m \in Monitors, n \in Nodes : ReceiveHeartbeat(m, n)
    \/ GracelessTick
    \/ \E m \in Monitors, n \in Nodes : GracelessDeclareFailed(m, n)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m)
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : Boot(n)

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
