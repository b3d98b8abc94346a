----------------------------- MODULE AskExclusion -----------------------------
(***************************************************************************)
(* A node that asks to be excluded: its own word, for itself, not the      *)
(* Master's (core/fsm/node_protocol.cpp NodeProtocol::resign, the branch   *)
(* of a node that is not the acting Master; enforce_lease; the Master's    *)
(* handling of an ErrorNotification).                                      *)
(*                                                                         *)
(* A Worker or Observer resigns (a task keeps failing on it, the ground    *)
(* holds it out, its disk failed): its AskExclusion line. It sends         *)
(* ErrorNotification{from: itself, epoch, failed: itself} to every node,   *)
(* again every period until a view that excludes it arrives, its           *)
(* heartbeats say `excluded` (so every monitor declares it at once), and   *)
(* it stops its tasks at once (enforce_lease holds them: the Master moves  *)
(* them as soon as it reads the request, maybe before its Command reaches  *)
(* the node). It never takes over or drives (resign_ is no longer none).  *)
(* The acting Master cannot exclude itself through its own manager: it     *)
(* resigns instead (Resign.tla). The Master takes a notification as the   *)
(* node's own word only when it names its sender (failed_node == from);   *)
(* any other is a report, evidence counted as Exclusion.tla's rule 2 says. *)
(*                                                                         *)
(* On Lease.tla: the node's word is Lease's `resigned` (no lease, no       *)
(* decision, no evidence needed for its exclusion), now for any node, not *)
(* only a Master whose lease lapsed. The notifications the Master holds    *)
(* are the asks, <<n, n>>, and the Observers' reports, <<m, x>> for each   *)
(* x that m declares (Exclusion's `failed`); the word that excludes n      *)
(* without evidence is one whose sender is n. The Master reads it at once *)
(* (Lease's abstraction: every node knows at once what the Master knows).  *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - NoExcludedRunsInv (Lease's): the node the Master excludes on its     *)
(*    word runs nothing by then: no second running copy of its tasks.      *)
(*  - OwnWordExclusionInv: every excluded node crashed, is omissive, or    *)
(*    asked itself (Exclusion's NoFalseExclusionInv, with the node's own   *)
(*    word): no node is excluded on a word about it that is not its own.   *)
(*    An Observer that asks leaves the cluster: it counts among the        *)
(*    MaxFaulty failures (a Worker does not: it is no voter).              *)
(*  - AskedTakesNoPartInv: a node that asked runs nothing and is never the *)
(*    acting Master.                                                       *)
(*  - AckBoundInv (Lease's).                                               *)
(* Mutants: mutants/AskKeepsRunning.tla (the node runs on until excluded) *)
(* and AskAnyNotification.tla (a report taken as the named node's word).   *)
(*                                                                         *)
(* Abstraction: Exclusion's decider is the first monitor in succession not *)
(* excluded; an Observer that asked decides nothing (Lease's DecidesBy),  *)
(* so should the Master die before it excludes that Observer, the spec's  *)
(* next decider waits for it, where the runtime's next Observer takes over *)
(* at once (every monitor declared the Observer on its word). A liveness   *)
(* question this spec does not check.                                      *)
(***************************************************************************)
EXTENDS Lease

VARIABLES
    asked   \* the nodes that asked to be excluded (history: their ErrorNotification
            \* about themselves stays with the Master)

askVars == <<allVars, asked>>

ATypeOK ==
    /\ TypeOK
    /\ ackLoss \in [Nodes -> [Monitors -> 0..MaxLoss]]
    /\ ackAge \in [Nodes -> [Monitors -> 0..MaxAge]]
    /\ resigned \subseteq Nodes
    /\ running \in [Nodes -> BOOLEAN]
    /\ asked \subseteq Nodes

AInit == LInit /\ asked = {}

\* The ErrorNotifications the Master holds: <<from, failed node>>.
Notes == {<<n, n>> : n \in asked} \cup UNION {{<<m, x>> : x \in failed[m]} : m \in Monitors}

\* n's own word: it resigned (Lease), or a notification about n that n sent (`checked`:
\* the Master compares the sender with the node named; FALSE in the mutant).
OwnWordBy(n, checked) == n \in resigned \/ \E w \in Notes : w[2] = n /\ (checked => w[1] = n)

\* Lease's LeaseNeededBy, with the own word as the Master reads it.
AskNeededBy(n, checked) ==
    IF ~DecidesBy(Decider(n), n, MissLimit, Quorum, TRUE) THEN Cardinality(Nodes) + 1
    ELSE IF OwnWordBy(n, checked) THEN 0
    ELSE Needed(n)

(***************************************************************************)
(* Protocol                                                                *)
(***************************************************************************)

\* Node n, not the acting Master, asks to be excluded (its AskExclusion line). `holds`:
\* it stops its tasks at once and takes no part (FALSE in the mutant that runs on until
\* the exclusion reaches it).
AskExclusionBy(n, holds) ==
    /\ alive[n]
    /\ n # Master
    /\ n \notin excluded
    /\ n \notin resigned
    /\ n \notin asked
    \* A monitor that leaves is one of the failures the cluster tolerates (MaxFaulty,
    \* with the crashed and omissive nodes): the monitors left must still tell a faulty
    \* one from a right one (with two left, one partly deaf Observer lapses the
    \* Master's lease: Lease's price of the last two monitors).
    /\ n \in Monitors =>
         Cardinality({x \in Nodes : ~alive[x]} \cup omissive \cup (asked \cap Monitors)) < MaxFaulty
    /\ asked' = asked \cup {n}
    /\ IF holds
       THEN /\ resigned' = resigned \cup {n}
            /\ running' = [running EXCEPT ![n] = FALSE]
       ELSE UNCHANGED <<resigned, running>>
    /\ UNCHANGED <<vars, ackLoss, ackAge>>

\* Lease's period end (LTickBy) and exclusion (LExcludeBy), with AskNeededBy.
ATickBy(checked) ==
    LET NeededNow(n) == AskNeededBy(n, checked)
    IN /\ TickBy(Counts, NeededNow)
       /\ \E lost \in SUBSET {p \in Nodes \X Monitors : Sends(p[2], p[1]) /\ MayLoseAck(p[2], p[1])} :
            /\ ackAge' = [x \in Nodes |-> [v \in Monitors |->
                            IF Sends(v, x) /\ <<x, v>> \notin lost
                            THEN Min(AckOf(v, x) + 1, MaxAge)
                            ELSE Min(ackAge[x][v] + 1, MaxAge)]]
            /\ ackLoss' = [x \in Nodes |-> [v \in Monitors |->
                            IF ~Sends(v, x) THEN ackLoss[x][v]
                            ELSE IF <<x, v>> \notin lost THEN 0
                            ELSE IF x \notin omissive /\ v \notin omissive /\ x \notin deaf /\ x \notin late
                                 THEN ackLoss[x][v] + 1
                                 ELSE ackLoss[x][v]]]
       /\ resigned' = resigned \cup
                        {m \in {Master} : alive[m] /\ ~(HoldsLeaseBy(m, MissLimit, Quorum, {}))'}
       /\ running' = [x \in Nodes |-> (Running(x))']
       /\ UNCHANGED asked

AExcludeBy(n, checked) ==
    LET NeededNow(m) == AskNeededBy(m, checked)
    IN /\ ExcludeBy(n, NeededNow)
       /\ UNCHANGED <<ackLoss, ackAge, resigned, asked>>
       /\ running' = [x \in Nodes |-> (Running(x))']

ANextBy(holds, checked) ==
    \/ \E n \in Nodes : SendHeartbeat(n) /\ UNCHANGED <<leaseVars, asked>>
    \/ \E m \in Monitors, n \in Nodes : ReceiveHeartbeat(m, n) /\ UNCHANGED <<leaseVars, asked>>
    \/ ATickBy(checked)
    \/ \E n \in Nodes : AExcludeBy(n, checked)
    \/ \E m \in Monitors, n \in Nodes : LoseHeartbeat(n, m) /\ UNCHANGED <<leaseVars, asked>>
    \/ \E n \in Nodes : Crash(n) /\ UNCHANGED <<leaseVars, asked>>
    \/ \E n \in Nodes : AskExclusionBy(n, holds)

ANext == ANextBy(TRUE, TRUE)

ASpec == AInit /\ [][ANext]_askVars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* No node is excluded on a word about it that is not its own.
OwnWordExclusionInv == \A n \in excluded : ~alive[n] \/ n \in omissive \/ n \in asked

\* A node that asked runs nothing and is never the acting Master (a take-over by it
\* would be a second Master beside the one it asked).
AskedTakesNoPartInv == \A n \in asked : ~running[n] /\ (alive[n] /\ n \notin excluded => n # Master)
=============================================================================
