------------------------------ MODULE Exclusion ------------------------------
(***************************************************************************)
(* Evidence before exclusion (fault model 2).                              *)
(*                                                                         *)
(* Heartbeat.tla decides when one monitor *declares* a node failed. This   *)
(* spec decides when the Master *excludes* it, i.e. when a declaration     *)
(* becomes the cluster's decision, under the faults a single monitor can   *)
(* suffer without crashing: it cannot receive (deaf), it receives only     *)
(* part of what is sent to it (starved, a receive queue that overflows),   *)
(* or its own loop runs late (CPU starvation) and counts periods it did    *)
(* not see.                                                                *)
(*                                                                         *)
(* Two rules, one per fault:                                               *)
(*  1. Self-suspicion. A monitor counts a period against the nodes it did  *)
(*     not hear only if it heard someone in that period and its own loop   *)
(*     ran on time. A monitor that hears no one, or ran late, suspects     *)
(*     itself first: no miss counts for that period (what it did hear      *)
(*     still resets that node's count).                                    *)
(*  2. Evidence quorum. The Master excludes node n only when two distinct  *)
(*     monitors of the cluster (the Master's own declaration counts as     *)
(*     one; an Observer's ErrorNotification as another) currently hold n  *)
(*     failed. Only when a single monitor is left in the cluster (besides *)
(*     n) does one declaration suffice: there is no one else to ask.       *)
(* A monitor that hears a node it declared withdraws the declaration (the  *)
(* C++ Observers already did; the Master now does too while the node is    *)
(* not excluded), so a report is evidence only while it is current.        *)
(*                                                                         *)
(* The same rule decides a take-over: the Master is excluded by the next  *)
(* monitor in succession, on the declarations of two monitors (its own     *)
(* and another Observer's report), so that a single Observer that cannot   *)
(* hear the Master does not depose it. (Epochs, fencing and the switch     *)
(* that follows are MasterElection's and ConfigSwitch's business.)          *)
(* Time is counted in heartbeat periods, as in Heartbeat.tla.              *)
(*                                                                         *)
(* Environment: up to MaxCrashes other nodes crash; healthy links lose at  *)
(* most MaxLoss heartbeats in a row (MaxLoss < MissLimit); up to           *)
(* MaxOmissive nodes have omission faults; at most MaxFaulty nodes are     *)
(* crashed or omissive together. A heartbeat to an omissive node may be    *)
(* lost without bound; with MuteToo one from it as well (it cannot send,   *)
(* or is cut off from some nodes: a partition of one). With DeafOnly, its  *)
(* faults come a whole period at a time, and only as a receiver: in a     *)
(* period it is deaf (receives nothing) or stalled (its loop runs late: it *)
(* may lose any part of the period's heartbeats, and it knows it ran       *)
(* late), or it receives normally.                                         *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - NoFalseExclusionInv: every excluded node crashed or is omissive      *)
(*    itself: no single faulty monitor (Master included) gets a healthy    *)
(*    node excluded. With MaxFaulty = 1 this holds for any omission; with  *)
(*    a crash besides, only for whole deaf or stalled periods (DeafOnly):  *)
(*    once a crash leaves the Master the last monitor, a Master that       *)
(*    loses only some heartbeats cannot be told from a right one (TLC      *)
(*    shows it: MCExclusion with MaxFaulty = 2). Without rule 2 a partly  *)
(*    deaf Observer does (mutants/ExclusionSingleReport.tla); with         *)
(*    (mutants/ExclusionSingleReport.tla); with DeafOnly and the Master    *)
(*    the last monitor, without rule 1 a deaf or stalled Master does       *)
(*    (mutants/ExclusionNoSelfSuspicion.tla, ExclusionNoLateCheck.tla).    *)
(*  - CompletenessInv: a crashed node is excluded within ExcludeBound      *)
(*    periods of its crash whenever enough monitors stay healthy.          *)
(* Witnesses (MCExclusion.tla) show that exclusions, withdrawn             *)
(* declarations, deaf and stalled periods are all reached.                 *)
(***************************************************************************)
EXTENDS Naturals, FiniteSets, Sequences

CONSTANTS
    Nodes,        \* every node of the cluster
    Monitors,     \* the Master and the Observers
    Succession,   \* the monitors in succession order: the Master, then the Observers
    MissLimit,    \* a monitor declares a node after MissLimit counted missed periods
    MaxLoss,      \* environment: heartbeats lost in a row on a healthy link
    MaxCrashes,   \* environment: at most this many nodes crash
    MaxOmissive,  \* environment: at most this many nodes have omission faults
    MaxFaulty,    \* environment: at most this many nodes crash or are omissive, together
    DeafOnly,     \* environment: omission comes as whole deaf or stalled periods
    MuteToo       \* environment: an omissive node may also lose what it sends

ASSUME Monitors \subseteq Nodes
ASSUME Succession \in Seq(Monitors) /\ Len(Succession) = Cardinality(Monitors)
ASSUME \A i, j \in 1..Len(Succession) : i # j => Succession[i] # Succession[j]
ASSUME MissLimit \in Nat /\ MissLimit >= 1
ASSUME MaxLoss \in Nat /\ MaxLoss < MissLimit
ASSUME {MaxCrashes, MaxOmissive, MaxFaulty} \subseteq Nat
ASSUME DeafOnly \in BOOLEAN /\ MuteToo \in BOOLEAN

VARIABLES
    alive,     \* env: [Nodes -> BOOLEAN]
    omissive,  \* env: SUBSET Nodes, the nodes with omission faults (chosen at the start)
    deaf,      \* env: SUBSET omissive, deaf for the period under way (DeafOnly)
    late,      \* env: SUBSET omissive, whose loop runs late in the period under way
    sent,      \* [Nodes -> BOOLEAN], the node sent its heartbeat this period
    inFlight,  \* env: set of <<n, m>>, n's heartbeat to monitor m in transit
    lossRun,   \* env: [Monitors -> [Nodes -> 0..MaxLoss]], losses in a row on a healthy link
    heard,     \* [Monitors -> SUBSET Nodes], nodes m heard from this period
    missed,    \* [Monitors -> [Nodes -> 0..MissLimit]], counted missed periods in a row
    failed,    \* [Monitors -> SUBSET Nodes], m's current declarations (its reports)
    excluded,  \* SUBSET Nodes, the cluster's decisions (the Master's, or a successor's)
    downFor    \* env: [Nodes -> 0..ExcludeBound + 1], periods since the crash (history)

vars == <<alive, omissive, deaf, late, sent, inFlight, lossRun, heard, missed, failed,
          excluded, downFor>>

\* A crashed node is excluded within this many ticks: MissLimit counted periods, and a
\* healthy monitor may have a silent period (all its links lose at once) between any two.
ExcludeBound == 2 * MissLimit + 1

Min(a, b) == IF a < b THEN a ELSE b

\* The monitors still in the cluster that may vote on n.
Voters(n) == (Monitors \ excluded) \ {n}

\* Declarations the Master needs (rule 2).
Needed(n) == IF Cardinality(Voters(n)) >= 2 THEN 2 ELSE 1

Evidence(n) == {m \in Voters(n) : n \in failed[m]}

\* Who decides: the acting Master is the first monitor in succession not excluded. Its
\* own exclusion is decided by the next one not excluded, which thereby takes over.
Pos(m) == CHOOSE i \in 1..Len(Succession) : Succession[i] = m
InCluster == {i \in 1..Len(Succession) : Succession[i] \notin excluded}
First(S) == CHOOSE i \in S : \A j \in S : i <= j
Master == LET in == InCluster
          IN IF in = {} THEN Succession[1] ELSE Succession[First(in)]
Successor == LET master == Master
                 after == {i \in InCluster : Succession[i] # master /\ i > Pos(master)}
             IN IF after = {} THEN master ELSE Succession[First(after)]
Decider(n) == LET master == Master IN IF n = master THEN Successor ELSE master

\* A monitor that is part of the cluster and running.
Monitoring(m) == alive[m] /\ m \notin excluded

Healthy(n) == alive[n] /\ n \notin omissive

TypeOK ==
    /\ alive \in [Nodes -> BOOLEAN]
    /\ omissive \subseteq Nodes /\ deaf \subseteq omissive /\ late \subseteq omissive
    /\ sent \in [Nodes -> BOOLEAN]
    /\ inFlight \subseteq (Nodes \X Monitors)
    /\ lossRun \in [Monitors -> [Nodes -> 0..MaxLoss]]
    /\ heard \in [Monitors -> SUBSET Nodes]
    /\ missed \in [Monitors -> [Nodes -> 0..MissLimit]]
    /\ failed \in [Monitors -> SUBSET Nodes]
    /\ excluded \subseteq Nodes
    /\ downFor \in [Nodes -> 0..(ExcludeBound + 1)]

Init ==
    /\ omissive \in {O \in SUBSET Nodes : Cardinality(O) <= MaxOmissive}
    /\ deaf = {}
    /\ late = {}
    /\ alive = [n \in Nodes |-> TRUE]
    /\ sent = [n \in Nodes |-> FALSE]
    /\ inFlight = {}
    /\ lossRun = [m \in Monitors |-> [n \in Nodes |-> 0]]
    /\ heard = [m \in Monitors |-> {}]
    /\ missed = [m \in Monitors |-> [n \in Nodes |-> 0]]
    /\ failed = [m \in Monitors |-> {}]
    /\ excluded = {}
    /\ downFor = [n \in Nodes |-> 0]

(***************************************************************************)
(* Protocol                                                                *)
(***************************************************************************)

SendHeartbeat(n) ==
    /\ alive[n]
    /\ ~sent[n]
    /\ sent' = [sent EXCEPT ![n] = TRUE]
    /\ inFlight' = inFlight \cup {<<n, m>> : m \in Monitors \ {n}}
    /\ UNCHANGED <<alive, omissive, deaf, late, lossRun, heard, missed, failed, excluded,
                   downFor>>

\* Monitor m receives n's heartbeat; a declaration of n not yet acted on is withdrawn.
ReceiveHeartbeat(m, n) ==
    /\ <<n, m>> \in inFlight
    /\ alive[m]
    /\ m \notin deaf
    /\ inFlight' = inFlight \ {<<n, m>>}
    /\ heard' = [heard EXCEPT ![m] = @ \cup {n}]
    /\ lossRun' = [lossRun EXCEPT ![m][n] = 0]
    /\ failed' = IF n \in failed[m] /\ n \notin excluded
                 THEN [failed EXCEPT ![m] = @ \ {n}] ELSE failed
    /\ missed' = IF n \in failed[m] /\ n \notin excluded
                 THEN [missed EXCEPT ![m][n] = 0] ELSE missed
    /\ UNCHANGED <<alive, omissive, deaf, late, sent, excluded, downFor>>

\* Rule 1: whether monitor m counts the period that ends.
Counts(m) == heard[m] # {} /\ m \notin late

MissedAfterTick(m, n) ==
    IF n \in heard[m] THEN 0 ELSE Min(missed[m][n] + 1, MissLimit)

\* The Master acts on the evidence before the period ends (it is an event of the period).
\* Parameterised by the quorum rule, so that a mutant can swap the rule alone.
ExcludableBy(n, NeededOp(_)) ==
    /\ n \notin excluded
    /\ Decider(n) # n
    /\ alive[Decider(n)]
    /\ Cardinality(Evidence(n)) >= NeededOp(n)

Excludable(n) == ExcludableBy(n, Needed)

\* The period ends: every running node sent, every heartbeat was received or lost, the
\* Master acted on the evidence. Each running monitor counts (rule 1) and declares in the
\* same step (the sans-IO monitor returns its declarations from the tick). The
\* environment picks the deaf and stalled nodes of the next period.
\* TickBy is parameterised by rules 1 and 2, so that a mutant can swap one rule alone.
TickBy(CountsOp(_), NeededOp(_)) ==
    /\ \A n \in Nodes : alive[n] => sent[n]
    /\ inFlight = {}
    /\ \A n \in Nodes : ~ExcludableBy(n, NeededOp)
    /\ LET newMissed ==
               [m \in Monitors |->
                   [n \in Nodes |->
                       IF Monitoring(m) /\ n # m /\ n \notin excluded /\ n \notin failed[m]
                       THEN IF CountsOp(m) THEN MissedAfterTick(m, n)
                            ELSE IF n \in heard[m] THEN 0 ELSE missed[m][n]
                       ELSE missed[m][n]]]
       IN /\ missed' = newMissed
          /\ failed' = [m \in Monitors |->
                          IF Monitoring(m)
                          THEN failed[m] \cup {n \in Nodes \ ({m} \cup excluded) :
                                                 newMissed[m][n] >= MissLimit}
                          ELSE failed[m]]
    /\ heard' = [m \in Monitors |-> {}]
    /\ sent' = [n \in Nodes |-> FALSE]
    /\ downFor' = [n \in Nodes |-> IF alive[n] THEN 0
                                   ELSE Min(downFor[n] + 1, ExcludeBound + 1)]
    /\ \E D \in SUBSET omissive, L \in SUBSET omissive :
          /\ deaf' = IF DeafOnly THEN D ELSE {}
          /\ late' = L
          /\ DeafOnly => D \cap L = {}
    /\ UNCHANGED <<alive, omissive, inFlight, lossRun, excluded>>

Tick == TickBy(Counts, Needed)

\* Rule 2: the Master excludes n on enough independent evidence; the Master itself is
\* excluded, on the same rule, by its successor, which takes over.
ExcludeBy(n, NeededOp(_)) ==
    /\ ExcludableBy(n, NeededOp)
    /\ excluded' = excluded \cup {n}
    /\ UNCHANGED <<alive, omissive, deaf, late, sent, inFlight, lossRun, heard, missed,
                   failed, downFor>>

Exclude(n) == ExcludeBy(n, Needed)

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* Which heartbeats to m the channel may drop.
MayLose(n, m) ==
    \/ ~alive[m]
    \/ m \in deaf \/ m \in late
    \/ (m \in omissive \/ (MuteToo /\ n \in omissive)) /\ ~DeafOnly
    \/ lossRun[m][n] < MaxLoss

LoseHeartbeat(n, m) ==
    /\ <<n, m>> \in inFlight
    /\ MayLose(n, m)
    /\ inFlight' = inFlight \ {<<n, m>>}
    /\ lossRun' = IF alive[m] /\ m \notin omissive /\ n \notin omissive
                  THEN [lossRun EXCEPT ![m][n] = @ + 1] ELSE lossRun
    /\ UNCHANGED <<alive, omissive, deaf, late, sent, heard, missed, failed, excluded,
                   downFor>>

Crash(n) ==
    /\ alive[n]
    /\ Cardinality({x \in Nodes : ~alive[x]}) < MaxCrashes
    /\ Cardinality({x \in Nodes : ~alive[x]} \cup omissive) < MaxFaulty
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ UNCHANGED <<omissive, deaf, late, sent, inFlight, lossRun, heard, missed, failed,
                   excluded, downFor>>

\* The next-state relation under rules 1 and 2 (mutants pass broken ones).
NextBy(CountsOp(_), NeededOp(_)) ==
    \/ \E n \in Nodes : SendHeartbeat(n)
    \/ \E m \in Monitors, n \in Nodes : ReceiveHeartbeat(m, n)
    \/ TickBy(CountsOp, NeededOp)
    \/ \E n \in Nodes : ExcludeBy(n, NeededOp)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m)
    \/ \E n \in Nodes : Crash(n)

Next == NextBy(Counts, Needed)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* No single faulty monitor gets a healthy node excluded.
NoFalseExclusionInv == \A n \in excluded : ~alive[n] \/ n \in omissive

\* A crashed node is excluded within ExcludeBound periods, as long as every monitor but at
\* most one still in the cluster is healthy and can count it (so that enough evidence
\* can exist: two declarations, or one where one monitor is left).
CompletenessInv ==
    \A n \in Nodes :
        (/\ ~alive[n]
         /\ downFor[n] > ExcludeBound
         /\ Cardinality({m \in Voters(n) : Healthy(m)}) >= Needed(n))
            => n \in excluded

=============================================================================
