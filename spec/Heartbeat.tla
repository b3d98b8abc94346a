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
(* Start-up grace. Real processes do not boot at the same instant. A node  *)
(* monitor m has never heard is declared only after StartupGrace missed    *)
(* periods (StartupGrace >= MissLimit; the mission's                       *)
(* heartbeat.startup_grace_ms in periods); once m has heard it, the        *)
(* MissLimit rule applies. `heardOnce[m]` holds the nodes m heard in a     *)
(* period that has ended (the C++ adds a node at the receipt; it counts    *)
(* only at the period's end, so the two agree on every declaration).       *)
(* Up to MaxLateBoots watched nodes boot late, at most MaxBootDelay ticks  *)
(* after the start; until then they are down. Monitors boot at the start:  *)
(* monitors share nothing, and a monitor that boots late sees the nodes    *)
(* that booted before it like nodes that boot with it, so its case is the  *)
(* same up to a shift of time.                                             *)
(*                                                                         *)
(* The environment is modelled apart from the protocol: nodes crash (at    *)
(* most MaxCrashes of them), and the channel loses heartbeats, at most     *)
(* MaxLoss in a row on each link, and delays them by less than one period  *)
(* (a heartbeat sent in a period is received or lost before that period   *)
(* ends, in any order with every other event of the period).               *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - CompletenessInv: a crashed node is declared failed by every running  *)
(*    monitor within DetectionBoundTicks = 2 * MissLimit + 1 ticks of its  *)
(*    crash (the crash may come just after its last heartbeat was sent)    *)
(*    if the monitor ever heard it, else within GraceBoundTicks + 1 ticks. *)
(*    The bounds count the periods a monitor does not count because it     *)
(*    heard no one (self-suspicion): with MaxLoss < MissLimit <= 2 at most *)
(*    every other period is silent for a running monitor.                  *)
(*  - AccuracyInv: when at most MissLimit - 1 consecutive heartbeats are   *)
(*    lost on a link (MaxLoss < MissLimit) and a late node boots early     *)
(*    enough that its boot delay and a loss streak stay below the grace    *)
(*    (MaxBootDelay + MaxLoss < StartupGrace), no node is ever declared    *)
(*    failed while it runs, nor before it boots.                           *)
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
    MaxCrashes,  \* environment: at most MaxCrashes nodes crash
    StartupGrace,  \* a node never heard is declared after this many missed periods
    MaxLateBoots,  \* environment: at most this many watched nodes boot late
    MaxBootDelay   \* environment: a late node boots within this many ticks of the start

ASSUME MonitorsAssumption == Monitors \subseteq Nodes /\ Monitors # {}
ASSUME MissLimitAssumption == MissLimit \in Nat /\ MissLimit >= 1
ASSUME MaxLossAssumption == MaxLoss \in Nat
ASSUME MaxCrashesAssumption == MaxCrashes \in Nat /\ MaxCrashes <= Cardinality(Nodes)
ASSUME GraceAssumption == StartupGrace \in Nat /\ StartupGrace >= MissLimit
ASSUME LateBootAssumption == {MaxLateBoots, MaxBootDelay} \subseteq Nat

VARIABLES
    alive,     \* env: [Nodes -> BOOLEAN], the node is running
    sent,      \* [Nodes -> BOOLEAN], the node sent its heartbeat this period
    inFlight,  \* env: set of <<n, m>>, n's heartbeat to monitor m in transit
    lossRun,   \* env: [Monitors -> [Nodes -> 0..MaxLoss]], losses in a row on n -> m
    heard,     \* [Monitors -> SUBSET Nodes], nodes m heard from this period
    missed,    \* [Monitors -> [Nodes -> 0..MissLimit]], missed periods in a row
    failed,    \* [Monitors -> SUBSET Nodes], nodes m declared failed
    downFor,   \* env: [Nodes -> 0..GraceBoundTicks + 1], ticks since the crash (history)
    heardOnce, \* [Monitors -> SUBSET Nodes], nodes m heard in a period that ended
    unbooted,  \* env: SUBSET Nodes, the late nodes that have not booted yet
    clock      \* env: 0..MaxBootDelay, ticks since the start (saturates)

vars == <<alive, sent, inFlight, lossRun, heard, missed, failed, downFor, heardOnce,
          unbooted, clock>>

\* A crashed node is declared failed by every running monitor within this many ticks.
DetectionBoundTicks == 2 * MissLimit + 1
\* The same for a node the monitor never heard (it counts it from the start).
GraceBoundTicks == 2 * StartupGrace + 1

\* The nodes monitor m watches: everyone but itself.
Watched(m) == Nodes \ {m}

Min(a, b) == IF a < b THEN a ELSE b

\* Missed periods after which monitor m declares n: the grace until m has heard n.
DeclareAt(m, n) == IF n \in heardOnce[m] THEN MissLimit ELSE StartupGrace

\* downFor counts up to the bound CompletenessInv needs: DetectionBoundTicks + 1 for a
\* node every monitor has heard, GraceBoundTicks + 1 for one some monitor never heard.
DownForCap(n) ==
    IF \A m \in Monitors : n \in heardOnce[m] \cup heard[m]
    THEN DetectionBoundTicks + 1
    ELSE GraceBoundTicks + 1

\* The nodes that may boot late: any but the monitors (see the header).
LateCandidates == Nodes \ Monitors

TypeOK ==
    /\ alive \in [Nodes -> BOOLEAN]
    /\ sent \in [Nodes -> BOOLEAN]
    /\ inFlight \subseteq (Nodes \X Monitors)
    /\ lossRun \in [Monitors -> [Nodes -> 0..MaxLoss]]
    /\ heard \in [Monitors -> SUBSET Nodes]
    /\ missed \in [Monitors -> [Nodes -> 0..StartupGrace]]
    /\ failed \in [Monitors -> SUBSET Nodes]
    /\ downFor \in [Nodes -> 0..(GraceBoundTicks + 1)]
    /\ heardOnce \in [Monitors -> SUBSET Nodes]
    /\ unbooted \subseteq LateCandidates
    /\ clock \in 0..MaxBootDelay

Init ==
    /\ unbooted \in {B \in SUBSET LateCandidates : Cardinality(B) <= MaxLateBoots}
    /\ alive = [n \in Nodes |-> n \notin unbooted]
    /\ sent = [n \in Nodes |-> FALSE]
    /\ inFlight = {}
    /\ lossRun = [m \in Monitors |-> [n \in Nodes |-> 0]]
    /\ heard = [m \in Monitors |-> {}]
    /\ missed = [m \in Monitors |-> [n \in Nodes |-> 0]]
    /\ failed = [m \in Monitors |-> {}]
    /\ downFor = [n \in Nodes |-> 0]
    /\ heardOnce = [m \in Monitors |-> {}]
    /\ clock = 0

(***************************************************************************)
(* Protocol                                                                *)
(***************************************************************************)

\* Node n sends its heartbeat of this period to every other monitor.
SendHeartbeat(n) ==
    /\ alive[n]
    /\ ~sent[n]
    /\ sent' = [sent EXCEPT ![n] = TRUE]
    /\ inFlight' = inFlight \cup {<<n, m>> : m \in Monitors \ {n}}
    /\ UNCHANGED <<alive, lossRun, heard, missed, failed, downFor, heardOnce,
                   unbooted, clock>>

\* Monitor m receives n's heartbeat.
ReceiveHeartbeat(m, n) ==
    /\ <<n, m>> \in inFlight
    /\ alive[m]
    /\ inFlight' = inFlight \ {<<n, m>>}
    /\ heard' = [heard EXCEPT ![m] = @ \cup {n}]
    /\ lossRun' = [lossRun EXCEPT ![m][n] = 0]
    /\ UNCHANGED <<alive, sent, missed, failed, downFor, heardOnce,
                   unbooted, clock>>

\* The monitor's counting rule at the end of a period, for one watched node.
MissedAfterTick(m, n) ==
    IF n \in heard[m] THEN 0 ELSE Min(missed[m][n] + 1, DeclareAt(m, n))

\* Self-suspicion (fault model 2; Exclusion.tla, rule 1): a monitor that heard no other
\* node's heartbeat in the period (declared ones included) counts no miss for it. (Nor does
\* a monitor whose loop ran late; lateness is Exclusion.tla's environment, and the trace
\* spec follows the node's logged decision.)
Counts(m) == heard[m] # {}

\* A declaration monitor m owes before the period may end.
Pending(m, n) == missed[m][n] >= DeclareAt(m, n) /\ n \notin failed[m]

\* The period ends. Every running node has sent, every heartbeat of the period has
\* been received or lost (delay below one period), every running monitor has made
\* the declarations its counters call for, and no late node is due to boot.
\* TickBy is parameterised by the counting rule, so that the trace spec can follow the
\* node's own logged decision (and a mutant could swap the rule alone).
TickBy(CountsOp(_)) ==
    /\ \A n \in Nodes : alive[n] => sent[n]
    /\ inFlight = {}
    /\ \A m \in Monitors : alive[m] => \A n \in Watched(m) : ~Pending(m, n)
    /\ unbooted # {} => clock < MaxBootDelay
    /\ missed' = [m \in Monitors |->
                    [n \in Nodes |->
                        IF alive[m] /\ n \in Watched(m) /\ n \notin failed[m]
                        THEN IF CountsOp(m) THEN MissedAfterTick(m, n)
                             ELSE IF n \in heard[m] THEN 0 ELSE missed[m][n]
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

Tick == TickBy(Counts)

\* Monitor m declares n failed.
DeclareFailed(m, n) ==
    /\ alive[m]
    /\ n \in Watched(m)
    /\ n \notin failed[m]
    /\ missed[m][n] >= DeclareAt(m, n)
    /\ failed' = [failed EXCEPT ![m] = @ \cup {n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, missed, downFor, heardOnce,
                   unbooted, clock>>

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
    /\ UNCHANGED <<alive, sent, heard, missed, failed, downFor, heardOnce,
                   unbooted, clock>>

\* Node n crashes, possibly after it sent this period's heartbeat.
Crash(n) ==
    /\ alive[n]
    /\ Cardinality({x \in Nodes : ~alive[x]} \ unbooted) < MaxCrashes
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ UNCHANGED <<sent, inFlight, lossRun, heard, missed, failed, downFor, heardOnce,
                   unbooted, clock>>

\* Late node n boots, at any point of a period up to MaxBootDelay ticks after the start
\* (Tick waits for it); it sends its first heartbeat in this period.
Boot(n) ==
    /\ n \in unbooted
    /\ unbooted' = unbooted \ {n}
    /\ alive' = [alive EXCEPT ![n] = TRUE]
    /\ downFor' = [downFor EXCEPT ![n] = 0]
    /\ UNCHANGED <<sent, inFlight, lossRun, heard, missed, failed, heardOnce, clock>>

Next ==
    \/ \E n \in Nodes : SendHeartbeat(n)
    \/ \E m \in Monitors, n \in Nodes : ReceiveHeartbeat(m, n)
    \/ Tick
    \/ \E m \in Monitors, n \in Nodes : DeclareFailed(m, n)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m)
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : Boot(n)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* Completeness: a crashed node that monitor m has heard is declared failed by m once it
\* has been down for more than DetectionBoundTicks ticks; one m never heard, once it has
\* been down for more than GraceBoundTicks (m counts it from the start, before the
\* crash).
CompletenessInv ==
    \A m \in Monitors, n \in Nodes :
        (/\ alive[m] /\ n \in Watched(m) /\ n \notin unbooted
         /\ downFor[n] > IF n \in heardOnce[m] \cup heard[m]
                         THEN DetectionBoundTicks
                         ELSE GraceBoundTicks)
            => n \in failed[m]

\* Accuracy: only crashed nodes are declared failed (a node declared before it boots
\* violates it when it boots). It holds when fewer than MissLimit heartbeats are lost in
\* a row (MaxLoss < MissLimit, as in every model) and MaxBootDelay + MaxLoss <
\* StartupGrace; with MaxLoss = MissLimit it fails (mutants/HeartbeatLossAtLimit.tla),
\* and so it does when the grace is ignored (mutants/HeartbeatNoStartupGrace.tla).
AccuracyInv ==
    \A m \in Monitors : \A n \in failed[m] : ~alive[n]

=============================================================================
