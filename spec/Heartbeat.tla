------------------------------ MODULE Heartbeat ------------------------------
(***************************************************************************)
(* Heartbeat failure detection of the OBC-NG middleware.                   *)
(*                                                                         *)
(* The Master and the Observers (the Monitors) watch every node. Time is   *)
(* counted in heartbeat periods: once per period every running node sends  *)
(* one heartbeat to every monitor, and at the end of the period (Tick)     *)
(* each monitor looks, for every node, whether a heartbeat from it arrived *)
(* during the period. `missed[m][n]` counts the consecutive periods in     *)
(* which monitor m heard nothing from n; when it reaches MissLimit, m      *)
(* declares n failed, before the next period begins (the sans-IO monitor   *)
(* returns its DeclareFailed actions from the same tick).                  *)
(*                                                                         *)
(* The environment is modelled apart from the protocol: nodes crash (at    *)
(* most MaxCrashes of them), and the channel loses heartbeats, at most     *)
(* MaxLoss in a row on each link, and delays them by less than one period  *)
(* (a heartbeat sent in a period is received or lost before that period   *)
(* ends, in any order with every other event of the period).               *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - CompletenessInv: a crashed node is declared failed by every running  *)
(*    monitor within DetectionBoundTicks = MissLimit + 1 ticks of its      *)
(*    crash (the crash may come just after its last heartbeat was sent).   *)
(*  - AccuracyInv: when at most MissLimit - 1 consecutive heartbeats are   *)
(*    lost on a link (MaxLoss < MissLimit), no running node is ever        *)
(*    declared failed.                                                     *)
(*                                                                         *)
(* Restarts are not modelled here: a restarted node rejoins through the    *)
(* election (MasterElection) and a new configuration (ConfigSwitch).      *)
(***************************************************************************)
EXTENDS Naturals, FiniteSets

CONSTANTS
    Nodes,       \* every node of the cluster (processing, storage, interface)
    Monitors,    \* the Master and the Observers: the nodes that monitor
    MissLimit,   \* a node is declared failed after MissLimit missed periods
    MaxLoss,     \* environment: at most MaxLoss heartbeats lost in a row per link
    MaxCrashes   \* environment: at most MaxCrashes nodes crash

ASSUME MonitorsAssumption == Monitors \subseteq Nodes /\ Monitors # {}
ASSUME MissLimitAssumption == MissLimit \in Nat /\ MissLimit >= 1
ASSUME MaxLossAssumption == MaxLoss \in Nat
ASSUME MaxCrashesAssumption == MaxCrashes \in Nat /\ MaxCrashes <= Cardinality(Nodes)

VARIABLES
    alive,     \* env: [Nodes -> BOOLEAN], the node is running
    sent,      \* [Nodes -> BOOLEAN], the node sent its heartbeat this period
    inFlight,  \* env: set of <<n, m>>, n's heartbeat to monitor m in transit
    lossRun,   \* env: [Monitors -> [Nodes -> 0..MaxLoss]], losses in a row on n -> m
    heard,     \* [Monitors -> SUBSET Nodes], nodes m heard from this period
    missed,    \* [Monitors -> [Nodes -> 0..MissLimit]], missed periods in a row
    failed,    \* [Monitors -> SUBSET Nodes], nodes m declared failed
    downFor    \* env: [Nodes -> 0..MissLimit + 2], ticks since the crash (history)

vars == <<alive, sent, inFlight, lossRun, heard, missed, failed, downFor>>

\* A crashed node is declared failed by every running monitor within this many ticks.
DetectionBoundTicks == MissLimit + 1

\* The nodes monitor m watches: everyone but itself.
Watched(m) == Nodes \ {m}

Min(a, b) == IF a < b THEN a ELSE b

TypeOK ==
    /\ alive \in [Nodes -> BOOLEAN]
    /\ sent \in [Nodes -> BOOLEAN]
    /\ inFlight \subseteq (Nodes \X Monitors)
    /\ lossRun \in [Monitors -> [Nodes -> 0..MaxLoss]]
    /\ heard \in [Monitors -> SUBSET Nodes]
    /\ missed \in [Monitors -> [Nodes -> 0..MissLimit]]
    /\ failed \in [Monitors -> SUBSET Nodes]
    /\ downFor \in [Nodes -> 0..(MissLimit + 2)]

Init ==
    /\ alive = [n \in Nodes |-> TRUE]
    /\ sent = [n \in Nodes |-> FALSE]
    /\ inFlight = {}
    /\ lossRun = [m \in Monitors |-> [n \in Nodes |-> 0]]
    /\ heard = [m \in Monitors |-> {}]
    /\ missed = [m \in Monitors |-> [n \in Nodes |-> 0]]
    /\ failed = [m \in Monitors |-> {}]
    /\ downFor = [n \in Nodes |-> 0]

(***************************************************************************)
(* Protocol                                                                *)
(***************************************************************************)

\* Node n sends its heartbeat of this period to every other monitor.
SendHeartbeat(n) ==
    /\ alive[n]
    /\ ~sent[n]
    /\ sent' = [sent EXCEPT ![n] = TRUE]
    /\ inFlight' = inFlight \cup {<<n, m>> : m \in Monitors \ {n}}
    /\ UNCHANGED <<alive, lossRun, heard, missed, failed, downFor>>

\* Monitor m receives n's heartbeat.
ReceiveHeartbeat(m, n) ==
    /\ <<n, m>> \in inFlight
    /\ alive[m]
    /\ inFlight' = inFlight \ {<<n, m>>}
    /\ heard' = [heard EXCEPT ![m] = @ \cup {n}]
    /\ lossRun' = [lossRun EXCEPT ![m][n] = 0]
    /\ UNCHANGED <<alive, sent, missed, failed, downFor>>

\* The monitor's counting rule at the end of a period, for one watched node.
MissedAfterTick(m, n) ==
    IF n \in heard[m] THEN 0 ELSE Min(missed[m][n] + 1, MissLimit)

\* A declaration monitor m owes before the period may end.
Pending(m, n) == missed[m][n] >= MissLimit /\ n \notin failed[m]

\* The period ends. Every running node has sent, every heartbeat of the period has
\* been received or lost (delay below one period), and every running monitor has made
\* the declarations its counters call for.
Tick ==
    /\ \A n \in Nodes : alive[n] => sent[n]
    /\ inFlight = {}
    /\ \A m \in Monitors : alive[m] => \A n \in Watched(m) : ~Pending(m, n)
    /\ missed' = [m \in Monitors |->
                    [n \in Nodes |->
                        IF alive[m] /\ n \in Watched(m) /\ n \notin failed[m]
                        THEN MissedAfterTick(m, n)
                        ELSE missed[m][n]]]
    /\ heard' = [m \in Monitors |-> {}]
    /\ sent' = [n \in Nodes |-> FALSE]
    /\ downFor' = [n \in Nodes |->
                     IF alive[n] THEN 0 ELSE Min(downFor[n] + 1, MissLimit + 2)]
    /\ UNCHANGED <<alive, inFlight, lossRun, failed>>

\* Monitor m declares n failed.
DeclareFailed(m, n) ==
    /\ alive[m]
    /\ n \in Watched(m)
    /\ n \notin failed[m]
    /\ missed[m][n] >= MissLimit
    /\ failed' = [failed EXCEPT ![m] = @ \cup {n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, missed, downFor>>

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* The channel drops n's heartbeat to m: within the loss budget of the link, or
\* because m is down (a crashed monitor receives nothing and counts nothing).
LoseHeartbeat(n, m) ==
    /\ <<n, m>> \in inFlight
    /\ alive[m] => lossRun[m][n] < MaxLoss
    /\ inFlight' = inFlight \ {<<n, m>>}
    /\ lossRun' = IF alive[m] THEN [lossRun EXCEPT ![m][n] = @ + 1] ELSE lossRun
    /\ UNCHANGED <<alive, sent, heard, missed, failed, downFor>>

\* Node n crashes, possibly after it sent this period's heartbeat.
Crash(n) ==
    /\ alive[n]
    /\ Cardinality({x \in Nodes : ~alive[x]}) < MaxCrashes
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ UNCHANGED <<sent, inFlight, lossRun, heard, missed, failed, downFor>>

Next ==
    \/ \E n \in Nodes : SendHeartbeat(n)
    \/ \E m \in Monitors, n \in Nodes : ReceiveHeartbeat(m, n)
    \/ Tick
    \/ \E m \in Monitors, n \in Nodes : DeclareFailed(m, n)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m)
    \/ \E n \in Nodes : Crash(n)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* Completeness: a node down for more than DetectionBoundTicks ticks has been declared
\* failed by every running monitor.
CompletenessInv ==
    \A m \in Monitors, n \in Nodes :
        (alive[m] /\ n \in Watched(m) /\ downFor[n] > DetectionBoundTicks)
            => n \in failed[m]

\* Accuracy: only crashed nodes are declared failed. It holds when fewer than MissLimit
\* heartbeats are lost in a row (MaxLoss < MissLimit, as in every model); with
\* MaxLoss = MissLimit it fails (mutants/HeartbeatLossAtLimit.tla shows it).
AccuracyInv ==
    \A m \in Monitors : \A n \in failed[m] : ~alive[n]

=============================================================================
