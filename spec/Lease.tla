-------------------------------- MODULE Lease --------------------------------
(***************************************************************************)
(* An isolated node stops before the cluster may replace it (fault model  *)
(* 2, rule 3).                                                             *)
(*                                                                         *)
(* Exclusion.tla decides when the cluster excludes a node: when enough     *)
(* monitors hold it failed. The node itself may well be alive: cut off     *)
(* from the monitors, mute (it receives but cannot send), deaf, paused. If *)
(* it keeps running, what the cluster moves elsewhere runs twice, and an  *)
(* excluded Master keeps commanding beside its successor (two running     *)
(* Masters across epochs). This spec adds the lease by which such a node  *)
(* stops first, on its own, without hearing from the cluster.              *)
(*                                                                         *)
(* Acknowledgements. A monitor's heartbeat tells every node how many       *)
(* periods the monitor has counted that node missed: MissLimit once it     *)
(* declared the node, or once the node is excluded (no monitor             *)
(* acknowledges an excluded node). A node keeps, per monitor, the latest   *)
(* count it received and ages it by one at each period boundary: a bound  *)
(* on what that monitor counts now (AckBoundInv).                          *)
(*                                                                         *)
(* Rule 3, the lease. A node runs (a Worker or Observer its tasks; the     *)
(* Master its commands, decisions and tasks) only while the voters whose  *)
(* bound reached MissLimit are fewer than the declarations an exclusion   *)
(* of it needs (Exclusion's Needed). Since an exclusion needs those        *)
(* declarations, the node stops in the period in which the cluster may     *)
(* first decide against it, before the decision. A node that is not the    *)
(* Master runs again when acknowledgements come back (it was not excluded: *)
(* an excluded node is never acknowledged again). A Master whose lease     *)
(* lapsed resigns for good: that is its own word, on which its successor   *)
(* excludes it without further evidence and takes over, so a Master that *)
(* cannot hear its acknowledgements (deaf, partly deaf) does not leave the *)
(* cluster without a Master. A decider that does not hold its own lease   *)
(* decides nothing; the node it decides on does not count against it (the *)
(* successor of a dead Master, the last two monitors, still takes over).   *)
(*                                                                         *)
(* Property: NoExcludedRunsInv, no excluded node that is alive runs. Two  *)
(* running Masters across epochs is its special case (a take-over is the  *)
(* old Master's exclusion); a task on two nodes the general one (an        *)
(* exclusion is what moves a node's tasks). Exclusion's NoFalseExclusionInv *)
(* and CompletenessInv still hold, and AckBoundInv is the lemma.           *)
(*                                                                         *)
(* Abstractions. Periods are global, as in Exclusion. In the runtime a     *)
(* node's boundaries are offset from a monitor's; it measures its lease    *)
(* from the send time of its own heartbeat that each monitor last         *)
(* acknowledged hearing, which bounds the monitor's count the same way,   *)
(* and stops a quarter period early (core/fsm/README.md). Every node knows *)
(* the cluster's exclusions at once (Voters reads `excluded`); in the      *)
(* runtime they reach it in the Master's Command, and the Master also      *)
(* fences a newly excluded node with a Command of its own.                 *)
(***************************************************************************)
EXTENDS Exclusion

VARIABLES
    ackLoss,   \* env: [Nodes -> [Monitors -> 0..MaxLoss]], acknowledgements lost in a row
    ackAge,    \* [Nodes -> [Monitors -> 0..MaxAge]], node x's bound on monitor v's count for x
    resigned,  \* SUBSET Monitors, Masters whose lease lapsed: stepped down for good
    running    \* [Nodes -> BOOLEAN], the node runs (holds its lease, by the rule in force)

leaseVars == <<ackLoss, ackAge, resigned, running>>
allVars == <<vars, leaseVars>>

MaxAge == MissLimit

\* What monitor v's heartbeat acknowledges of node x: its count of missed periods.
AckOf(v, x) == IF x \in failed[v] \/ x \in excluded THEN MissLimit ELSE missed[v][x]

\* The voters, but those in `without`, that may hold x failed by x's bounds (a lease of
\* `limit` periods).
StaleBy(x, limit, without) == {v \in Voters(x) \ without : ackAge[x][v] >= limit}

\* Exclusion's quorum for a set of voters: two, or one when only one is left.
Quorum(V) == IF Cardinality(V) >= 2 THEN 2 ELSE 1

\* Rule 3: fewer stale voters than the quorum that could exclude x. Parameterised (the
\* lease in periods, the quorum, the voters left out) so that a mutant can swap one part.
HoldsLeaseBy(x, limit, QuorumOp(_), without) ==
    Cardinality(StaleBy(x, limit, without)) < QuorumOp(Voters(x) \ without)

HoldsLease(x) == HoldsLeaseBy(x, MissLimit, Quorum, {})

RunningBy(x, limit, QuorumOp(_)) ==
    alive[x] /\ x \notin resigned /\ HoldsLeaseBy(x, limit, QuorumOp, {})

Running(x) == RunningBy(x, MissLimit, Quorum)

\* Whether decider d may decide on n: it runs, with its lease as it stands once n is out
\* (when decidedOut; n is the node the decision removes from d's voters, so n's silence
\* does not stop d: the successor of a dead Master, alone with it, still takes over).
DecidesBy(d, n, limit, QuorumOp(_), decidedOut) ==
    alive[d] /\ d \notin resigned /\ HoldsLeaseBy(d, limit, QuorumOp, IF decidedOut THEN {n} ELSE {})

\* The declarations an exclusion of n needs now: none on its own word (it resigned), and
\* no decision at all by a decider whose own lease lapsed.
LeaseNeededBy(n, limit, QuorumOp(_), decidedOut) ==
    IF ~DecidesBy(Decider(n), n, limit, QuorumOp, decidedOut) THEN Cardinality(Nodes) + 1
    ELSE IF n \in resigned THEN 0
    ELSE Needed(n)

LTypeOK ==
    /\ TypeOK
    /\ ackLoss \in [Nodes -> [Monitors -> 0..MaxLoss]]
    /\ ackAge \in [Nodes -> [Monitors -> 0..MaxAge]]
    /\ resigned \subseteq Monitors
    /\ running \in [Nodes -> BOOLEAN]

LInit ==
    /\ Init
    /\ ackLoss = [x \in Nodes |-> [v \in Monitors |-> 0]]
    /\ ackAge = [x \in Nodes |-> [v \in Monitors |-> 0]]
    /\ resigned = {}
    /\ running = [x \in Nodes |-> TRUE]

(***************************************************************************)
(* Protocol                                                                *)
(***************************************************************************)

\* The acknowledgements travel in the monitors' heartbeats of the period; they are
\* applied where the period ends, with the count the monitor holds then (before its own
\* tick), which is what it sent or lower (a declaration withdrawn since): a bound all the
\* same, and the node runs at least as long as in the runtime.
\* Which acknowledgements the channel may drop this period.
MayLoseAck(v, x) ==
    \/ x \in deaf \/ x \in late
    \/ (x \in omissive \/ v \in omissive) /\ ~DeafOnly
    \/ ackLoss[x][v] < MaxLoss

Sends(v, x) == v \in Monitors /\ Monitoring(v) /\ x # v /\ alive[x]

\* The period ends (Exclusion's Tick, with the lease's decider rule): each node takes the
\* acknowledgements that reached it (the environment picks the lost ones), every other
\* bound ages by one, and a Master whose lease lapsed resigns.
\* (`transit` is the period an acknowledgement spent on the way: 1.)
LTickBy(limit, QuorumOp(_), transit, decidedOut) ==
    LET NeededNow(n) == LeaseNeededBy(n, limit, QuorumOp, decidedOut)
    IN /\ TickBy(Counts, NeededNow)
       /\ \E lost \in SUBSET {p \in Nodes \X Monitors : Sends(p[2], p[1]) /\ MayLoseAck(p[2], p[1])} :
            /\ ackAge' = [x \in Nodes |-> [v \in Monitors |->
                            IF Sends(v, x) /\ <<x, v>> \notin lost
                            THEN Min(AckOf(v, x) + transit, MaxAge)
                            ELSE Min(ackAge[x][v] + 1, MaxAge)]]
            /\ ackLoss' = [x \in Nodes |-> [v \in Monitors |->
                            IF ~Sends(v, x) THEN ackLoss[x][v]
                            ELSE IF <<x, v>> \notin lost THEN 0
                            ELSE IF x \notin omissive /\ v \notin omissive /\ x \notin deaf /\ x \notin late
                                 THEN ackLoss[x][v] + 1
                                 ELSE ackLoss[x][v]]]
       /\ resigned' = resigned \cup
                        {m \in {Master} : alive[m] /\ ~(HoldsLeaseBy(m, limit, QuorumOp, {}))'}
       /\ running' = [x \in Nodes |-> (RunningBy(x, limit, QuorumOp))']

LExcludeBy(n, limit, QuorumOp(_), decidedOut) ==
    LET NeededNow(m) == LeaseNeededBy(m, limit, QuorumOp, decidedOut)
    IN /\ ExcludeBy(n, NeededNow)
       /\ UNCHANGED <<ackLoss, ackAge, resigned>>
       \* Every node learns the exclusion (see Abstractions): its voters may change.
       /\ running' = [x \in Nodes |-> (RunningBy(x, limit, QuorumOp))']

\* The next-state relation under rule 3 (mutants pass broken parts of it).
LNextBy(limit, QuorumOp(_), transit, decidedOut) ==
    \/ \E n \in Nodes : SendHeartbeat(n) /\ UNCHANGED leaseVars
    \/ \E m \in Monitors, n \in Nodes : ReceiveHeartbeat(m, n) /\ UNCHANGED leaseVars
    \/ LTickBy(limit, QuorumOp, transit, decidedOut)
    \/ \E n \in Nodes : LExcludeBy(n, limit, QuorumOp, decidedOut)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m) /\ UNCHANGED leaseVars
    \/ \E n \in Nodes : Crash(n) /\ UNCHANGED leaseVars

LNext == LNextBy(MissLimit, Quorum, 1, TRUE)

LSpec == LInit /\ [][LNext]_allVars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* No excluded node runs: not a Master beside its successor, not a task beside its new host.
NoExcludedRunsInv == \A n \in excluded : ~(alive[n] /\ running[n])

\* Exclusion's completeness, where the deciding monitors are the running ones: a Master
\* that resigned (its last voter went silent: it cannot tell a dead Observer from one cut
\* off, which would take over) decides nothing more. The price of the lease: the last two
\* monitors cannot lose one more.
LCompletenessInv ==
    \A n \in Nodes :
        (/\ ~alive[n]
         /\ downFor[n] > ExcludeBound
         /\ Cardinality({m \in Voters(n) : Healthy(m) /\ m \notin resigned}) >= Needed(n))
            => n \in excluded

\* The lemma: a node's bound on a monitor's count is never below the count.
AckBoundInv ==
    \A x \in Nodes, v \in Monitors :
        (Monitoring(v) /\ x # v /\ x \notin excluded) =>
            ackAge[x][v] >= (IF x \in failed[v] THEN MissLimit ELSE missed[v][x])
=============================================================================
