------------------------------ MODULE Designate ------------------------------
(***************************************************************************)
(* A Master designated by the ground: a tie the cluster cannot break,      *)
(* broken by the ground's vote (fault model 2).                            *)
(*                                                                         *)
(* With four monitors a 2|2 partition that never heals leaves both sides   *)
(* without the majority an exclusion needs (Quorum.tla's Needed: three of  *)
(* four), and with two monitors left neither can tell a dead peer from a   *)
(* cut-off one: the cluster is headless or split for good. The ground      *)
(* (one operator, its commands signed and totally ordered by SEQ, reaching *)
(* each node over its own uplink, possibly not every node, possibly late)  *)
(* sends `designate D`: D is to take over. The ground cannot see which     *)
(* nodes that command reached.                                             *)
(*                                                                         *)
(* The natural design, the ground's vote counted only by the nodes that    *)
(* admitted it (a node counts it against itself, D counts it for itself    *)
(* and for the take-over's quorum), is not safe: a node the command never  *)
(* reached, the old Master say, holds its lease in the tie for ever (two   *)
(* of its three voters are stale, an exclusion needs three) and runs on    *)
(* beside D (mutants/DesignateAdmittedOnly.tla). A take-over on the        *)
(* ground's vote is safe only once no node of the other side can still     *)
(* run, and only a rule every node follows without hearing the ground can  *)
(* bound that: the ground must be a voter of the lease itself, before any  *)
(* designation. The rules:                                                 *)
(*  1. The ground is a member of every view with an even number of         *)
(*     members (a tie-breaking fifth of four, third of two): an exclusion  *)
(*     or a take-over in such a view needs NeededG declarations, the       *)
(*     ground's vote one of them (of four: three, as before; of two: two,  *)
(*     so the last monitor no longer takes over alone). Views with an odd  *)
(*     number of members are Quorum.tla's, unchanged.                      *)
(*  2. The ground's standing acknowledgement: in such a view a node counts *)
(*     the ground with it for TieGrace periods of a tie (its stale voters  *)
(*     are one short of NeededG, by its own count), then against it,       *)
(*     unless the ground's vote is for it (rule 3). In a 2|2 every node    *)
(*     runs TieGrace periods as before, then stops; a Master whose lease   *)
(*     lapses resigns (Lease.tla), its own word: only a designation makes  *)
(*     it a Master again, by a take-over.                                  *)
(*  3. The ground's vote. `designate D` (SEQ s) carries `wait` and         *)
(*     `span`: it is the ground's vote for D, and against every other      *)
(*     node, from `wait` periods after D admits it to `span` periods after *)
(*     the ground sent it (the runtime counts the span from D's own        *)
(*     heartbeat that the command echoes, sent before it: a late command   *)
(*     only shortens it). The ground sets `wait` to the periods left of    *)
(*     the latest span it gave another node, `span` to `wait` + VoteSpan.  *)
(*     A node counts the vote for it only while it holds the latest        *)
(*     designation it admitted and that one names it: admitting a          *)
(*     designation of another node ends its own (a designee steps down).   *)
(*  4. The take-over. D, holding the vote and its lease, takes over (an    *)
(*     epoch of its own) from its view's Master once every declaration of  *)
(*     the nodes it cannot hear (its own and its side's, whose lease holds *)
(*     by the cluster alone) has stood TieGrace periods, so that each has  *)
(*     stopped by rule 2, and with the ground's vote they make NeededG of  *)
(*     each (a Master D hears that resigned is out on its own word). Its   *)
(*     view excludes them and keeps the view it took over from as a joint  *)
(*     view (Quorum.tla's rule 3), in which every node of D's view holds   *)
(*     its lease only while D holds the vote, and D runs as a Master only  *)
(*     while it holds the vote (a heal may give it its lease back without  *)
(*     it): D's Mastership lasts as long as the vote, renewed by a later   *)
(*     designation of D, so that a later designation of another node E     *)
(*     (whose `wait` outlasts D's span) is never acted on beside D,        *)
(*     whether it reached D or not.                                        *)
(*  5. A node whose lease lapsed in a tie stands down: it runs again only  *)
(*     once it follows a newer Command, holds the vote, or is acknowledged *)
(*     by every member of every view it goes by, none going by a newer     *)
(*     epoch (the tie is over and no take-over it does not know of         *)
(*     excluded it). Without it, a node D excluded runs again as soon as a *)
(*     heal ends its tie, before D's Command reaches it; with only its own *)
(*     view heard, a member of D's view resumes beside a later designee    *)
(*     whose lower epoch excludes it (TLC, MCDesignateHeal).               *)
(*                                                                         *)
(* The price: a tie without the ground stops both sides after TieGrace     *)
(* periods (today the Master's side runs on, the other side keeps its      *)
(* tasks), and a designated Master needs the ground to renew its vote      *)
(* within VoteSpan periods for as long as the tie lasts.                   *)
(*                                                                         *)
(* Abstractions, as in Quorum.tla: the decision level. A monitor holds a   *)
(* node failed exactly while it cannot hear it (conn) and a node's lease   *)
(* reads the same instant (Lease.tla's AckBoundInv is the lemma that the   *)
(* lease's bound runs ahead of the declarations); time is counted in       *)
(* periods, global (Tick), as in Lease.tla, each node's own count in the   *)
(* runtime. `cutAge` is how long D's side has held its declarations (the   *)
(* periods since the partition last changed, a lower bound). A node that   *)
(* follows D's view knows D's vote (the runtime: D's Commands carry the    *)
(* span as a number of periods from the follower's own heartbeat that D    *)
(* acknowledges). A designee takes over in the period it may (as           *)
(* Exclusion's Master decides before the period ends). The cluster's own   *)
(* decisions by a majority (Quorum.tla) are left out, and so are crashes   *)
(* (a crash is a node cut off for good) and restarts. The ground's clock   *)
(* and the nodes' periods run at one rate (the runtime: `wait` rounded up  *)
(* by the worst drift). Receivers are the nodes whose uplink a model       *)
(* exercises: the rules read no other node's admissions.                   *)
(*                                                                         *)
(* Properties: AtMostOneRunningMasterInv and NoExcludedRunsInv (Quorum's,  *)
(* over `running`, which each step sets from the rules in force, so that a *)
(* mutant's broken rule is what they judge); DesignateLiveness: once the   *)
(* partition is final and the last designation, naming a node that holds   *)
(* half of its view, reached it with time left in its span, it runs as a   *)
(* Master holding its lease.                                               *)
(***************************************************************************)
EXTENDS Integers, FiniteSets, Sequences, QuorumRule

CONSTANTS
    Nodes,            \* the processing nodes, every one a monitor of the initial view
    Order,            \* the nodes in succession order, the initial Master first; owners of epochs
    Ground,           \* the ground: a member of every view with an even number of members
    Designees,        \* the nodes the ground may designate
    Receivers,        \* the nodes whose uplink the model exercises (the others admit nothing)
    StartConns,       \* env: the partitions the nodes may start in (the cut came first)
    Cuts,             \* env: the partitions the environment may cut the nodes into later
    MaxEnv,           \* env: at most this many partition changes (a cut, a heal, another cut)
    TieGrace,         \* periods a node runs in a tie on its standing acknowledgement from the ground
    VoteSpan,         \* periods a designation's vote lasts once its wait is over
    MaxDesignations,  \* at most this many designations
    MaxTakeOvers      \* at most this many take-overs

ASSUME Ground \notin Nodes /\ Designees \subseteq Receivers /\ Receivers \subseteq Nodes
ASSUME Order \in Seq(Nodes) /\ Len(Order) = Cardinality(Nodes)
ASSUME \A i, j \in 1..Len(Order) : i # j => Order[i] # Order[j]
ASSUME TieGrace \in Nat /\ TieGrace >= 1 /\ VoteSpan \in Nat /\ VoteSpan >= 1
ASSUME {MaxEnv, MaxDesignations, MaxTakeOvers} \subseteq Nat

\* The longest span a designation can carry (each waits for at most the spans before it).
MaxSpan == MaxDesignations * VoteSpan

(***************************************************************************)
(* A view: its epoch (an epoch belongs to one node, so it names the view), *)
(* its Master, the nodes it excludes, and the views a take-over on the     *)
(* ground's vote left joint (those carry no `joint`). Every node is a      *)
(* monitor of every view. A designation: its designee, its age since the   *)
(* ground sent it, the periods its designee waits from admitting it, and   *)
(* its span from when it was sent.                                         *)
(***************************************************************************)
CoreType == [epoch : Nat, master : Nodes, failed : SUBSET Nodes]
ViewType == [epoch : Nat, master : Nodes, failed : SUBSET Nodes, joint : SUBSET CoreType]
DesigType == [node : Nodes, age : 0..MaxSpan, wait : 0..MaxSpan, span : 1..MaxSpan]

VARIABLES
    conn,        \* env: the partition, disjoint blocks covering Nodes; a node hears its block
    envChanges,  \* env: partition changes so far
    cutAge,      \* periods since the partition last changed, up to TieGrace
    view,        \* [Nodes -> ViewType], the view a node goes by
    resigned,    \* Masters whose lease lapsed: they run as Master of that view no more
    stoodDown,   \* nodes whose lease lapsed in a tie: stopped until rule 5 lets them run
    running,     \* [Nodes -> BOOLEAN], the node runs: it holds its lease by the rules in force
    tieAge,      \* [Nodes -> 0..TieGrace], periods the node has been in a tie, in a row
    desig,       \* the ground's designations, in SEQ order (SEQ is the index)
    admitted,    \* [Nodes -> 0..MaxDesignations], the last designation the node admitted
    waitLeft,    \* [Nodes -> 0..MaxSpan], periods the node still waits on it
    takeOvers    \* take-overs so far

vars == <<conn, envChanges, cutAge, view, resigned, stoodDown, running, tieAge, desig,
          admitted, waitLeft, takeOvers>>

Partitions == StartConns \cup Cuts \cup {{Nodes}}

Pos(n) == CHOOSE i \in 1..Len(Order) : Order[i] = n
Owner(e) == Order[((e - 1) % Len(Order)) + 1]
NextEpoch(d, e) == CHOOSE e2 \in (e + 1)..(e + Len(Order)) : Owner(e2) = d

Core(V) == [epoch |-> V.epoch, master |-> V.master, failed |-> V.failed]

SetMax(S) == CHOOSE m \in S : \A x \in S : x <= m

Hears(a, b) == \E B \in conn : a \in B /\ b \in B

Members(V) == Nodes \ V.failed

IsMaster(n) == view[n].master = n /\ n \notin view[n].failed

(***************************************************************************)
(* Rule 1: the ground is a member of a view with an even number of         *)
(* members (QuorumRule's Needed over the members and the ground).          *)
(***************************************************************************)
Even(S) == Cardinality(S) % 2 = 0
NeededG(mem, x) == IF Even(mem) THEN Needed(mem \cup {Ground}, x) ELSE Needed(mem, x)

\* Voter v may hold x failed (Quorum's MayHoldFailed).
MayHoldFailed(v, x) == ~Hears(v, x) \/ x \in view[v].failed
Stale(W, x) == {v \in Members(W) \ {x} : MayHoldFailed(v, x)}

\* The views x goes by: its own and its view's joint views.
GoesBy(x) == {Core(view[x])} \cup view[x].joint

\* Rule 2: x is in a tie when, in a view it goes by with the ground a member, one vote
\* more than its stale voters would make an exclusion of it.
InTie(x) ==
    \E W \in GoesBy(x) :
        Even(Members(W)) /\ Cardinality(Stale(W, x)) + 1 >= NeededG(Members(W), x)

(***************************************************************************)
(* Rule 3: the ground's vote. ForVote(x): x holds the vote (the latest     *)
(* designation it admitted names it, its wait is over, its span is not).   *)
(***************************************************************************)
ForVote(x) ==
    LET s == admitted[x]
    IN /\ s > 0
       /\ desig[s].node = x
       /\ waitLeft[x] = 0
       /\ desig[s].age < desig[s].span

\* How the ground counts in x's lease in a view it is a member of: with x while the vote
\* is for x (`for`), or within its tie grace; against x after it.
GroundCount(x, for) == IF for THEN 0 ELSE IF tieAge[x] >= TieGrace THEN 1 ELSE 0

\* The lease (Quorum's rule 2, the ground counted by GC where it is a member).
HoldsInBy(GC(_, _), W, x, for) ==
    LET ground == IF Even(Members(W)) THEN GC(x, for) ELSE 0
    IN Cardinality(Stale(W, x)) + ground < NeededG(Members(W), x)

\* x holds its lease in its view, where only its own vote counts for it, and in each
\* joint view, where its view's Master's vote counts for it too (rule 4: the Master's
\* vote backs its view).
LeaseBy(GC(_, _), FV(_), x) ==
    /\ x \notin view[x].failed
    /\ HoldsInBy(GC, Core(view[x]), x, FV(x))
    /\ \A J \in view[x].joint : HoldsInBy(GC, J, x, FV(x) \/ FV(view[x].master))

\* Rule 4: a Master that took over on the ground's vote runs only while it holds the vote
\* (a heal may give it its lease back without it). Rule 5: a node that stood down runs
\* again only on the vote (or once it resumed).
RunningBy(GC(_, _), FV(_), x) ==
    /\ LeaseBy(GC, FV, x)
    /\ ~(IsMaster(x) /\ x \in resigned)
    /\ IsMaster(x) /\ view[x].joint # {} => FV(x)
    /\ x \in stoodDown => FV(x)

\* The lease by the cluster's acknowledgements alone (the ground counted neither way).
NoGround(x, for) == 0
NoVote(x) == FALSE
ClusterHolds(x) == LeaseBy(NoGround, NoVote, x)

(***************************************************************************)
(* Rule 4: the take-over on the ground's vote.                             *)
(***************************************************************************)
\* The nodes d's take-over excludes: the members it cannot hear, and its view's Master
\* if d hears that it resigned (its own word).
Decided(d) ==
    LET V == view[d]
    IN {c \in Members(V) \ {d} : ~Hears(d, c)} \cup
       {c \in {V.master} \ {d} : c \in resigned /\ Hears(d, c)}

\* The declarations of c that d receives, counted in view V: its own, and those of the
\* members it hears whose lease holds by the cluster (a node stopped by the ground's vote
\* alone still reports; Quorum's rule 4 otherwise).
Declarers(d, V, c) ==
    {v \in Members(V) \ {c} : (v = d \/ (Hears(d, v) /\ ClusterHolds(v))) /\ ~Hears(v, c)}

\* `weight` is what the ground's vote counts for in the quorum (mutants swap it).
TakeOverEnabledBy(GC(_, _), FV(_), weight, d) ==
    LET V == view[d]
        dec == Decided(d)
    IN /\ takeOvers < MaxTakeOvers
       /\ cutAge >= TieGrace
       /\ FV(d)
       /\ dec # {}
       /\ V.master \in dec \cup {d}
       /\ LeaseBy(GC, FV, d)
       /\ \A c \in dec :
             \/ c \in resigned /\ Hears(d, c)
             \/ Cardinality(Declarers(d, V, c)) + weight >= NeededG(Members(V), c)

TypeOK ==
    /\ conn \in Partitions
    /\ envChanges \in 0..MaxEnv
    /\ cutAge \in 0..TieGrace
    /\ view \in [Nodes -> ViewType]
    /\ resigned \subseteq Nodes
    /\ stoodDown \subseteq Nodes
    /\ running \in [Nodes -> BOOLEAN]
    /\ tieAge \in [Nodes -> 0..TieGrace]
    /\ desig \in Seq(DesigType) /\ Len(desig) <= MaxDesignations
    /\ admitted \in [Nodes -> 0..MaxDesignations]
    /\ \A x \in Nodes : admitted[x] <= Len(desig)
    /\ waitLeft \in [Nodes -> 0..MaxSpan]
    /\ takeOvers \in 0..MaxTakeOvers

InitView == [epoch |-> 1, master |-> Order[1], failed |-> {}, joint |-> {}]

Init ==
    /\ conn \in StartConns
    /\ envChanges = 0
    /\ cutAge = IF conn = {Nodes} THEN TieGrace ELSE 0
    /\ view = [n \in Nodes |-> InitView]
    /\ resigned = {}
    /\ stoodDown = {}
    /\ running = [n \in Nodes |-> TRUE]
    /\ tieAge = [n \in Nodes |-> 0]
    /\ desig = <<>>
    /\ admitted = [n \in Nodes |-> 0]
    /\ waitLeft = [n \in Nodes |-> 0]
    /\ takeOvers = 0

(***************************************************************************)
(* Actions. Each sets `running` anew from the rules in force.              *)
(***************************************************************************)
RunningNext(GC(_, _), FV(_)) == running' = [x \in Nodes |-> (RunningBy(GC, FV, x))']

\* The ground designates d: its wait outlasts every span the ground gave another node.
Designate(GC(_, _), FV(_), d) ==
    LET others == {i \in 1..Len(desig) : desig[i].node # d}
        wait == SetMax({0} \cup {desig[i].span - desig[i].age : i \in others})
    IN /\ Len(desig) < MaxDesignations
       /\ desig' = Append(desig, [node |-> d, age |-> 0, wait |-> wait, span |-> wait + VoteSpan])
       /\ UNCHANGED <<conn, envChanges, cutAge, view, resigned, stoodDown, tieAge, admitted,
                      waitLeft, takeOvers>>
       /\ RunningNext(GC, FV)

\* Node x admits designation s (its uplink: any later one may overtake it, and a node
\* refuses a SEQ at or below the last it admitted, so an earlier one is lost for good).
Admit(GC(_, _), FV(_), x, s) ==
    /\ admitted[x] < s /\ s <= Len(desig)
    /\ admitted' = [admitted EXCEPT ![x] = s]
    /\ waitLeft' = [waitLeft EXCEPT ![x] = desig[s].wait]
    /\ UNCHANGED <<conn, envChanges, cutAge, view, resigned, stoodDown, tieAge, desig,
                   takeOvers>>
    /\ RunningNext(GC, FV)

\* d takes over on the ground's vote: an epoch of its own, excluding the decided nodes,
\* the view it took over from (and that view's joint views) joint.
TakeOverBy(GC(_, _), FV(_), weight, d) ==
    /\ TakeOverEnabledBy(GC, FV, weight, d)
    /\ view' = [view EXCEPT ![d] =
                  [epoch |-> NextEpoch(d, view[d].epoch), master |-> d,
                   failed |-> view[d].failed \cup Decided(d),
                   joint |-> {Core(view[d])} \cup view[d].joint]]
    /\ resigned' = resigned \ {d}
    /\ stoodDown' = stoodDown \ {d}
    /\ takeOvers' = takeOvers + 1
    /\ UNCHANGED <<conn, envChanges, cutAge, tieAge, desig, admitted, waitLeft>>
    /\ RunningNext(GC, FV)

\* Node n hears the running Master m, whose view is newer than n's, and adopts it (rule 5:
\* it no longer stands down).
Adopt(GC(_, _), FV(_), n, m) ==
    /\ n # m /\ IsMaster(m) /\ running[m] /\ Hears(n, m)
    /\ view[m].epoch > view[n].epoch
    /\ view' = [view EXCEPT ![n] = view[m]]
    /\ stoodDown' = stoodDown \ {n}
    /\ UNCHANGED <<conn, envChanges, cutAge, resigned, tieAge, desig, admitted, waitLeft,
                   takeOvers>>
    /\ RunningNext(GC, FV)

\* Rule 5: a node that stood down resumes once every member of every view it goes by
\* acknowledges it (hears it, its view not excluding it) and none goes by a newer epoch:
\* the tie is over and no take-over it does not know of excluded it (a take-over's Master
\* is a member of the view it took over from, and acknowledges no node it excluded).
Resume(GC(_, _), FV(_), x) ==
    /\ x \in stoodDown
    /\ \A W \in GoesBy(x) :
          /\ Stale(W, x) = {}
          /\ \A v \in Members(W) : view[v].epoch <= view[x].epoch
    /\ stoodDown' = stoodDown \ {x}
    /\ UNCHANGED <<conn, envChanges, cutAge, view, resigned, tieAge, desig, admitted, waitLeft,
                   takeOvers>>
    /\ RunningNext(GC, FV)

\* A period ends (once no designee may take over: it decides within the period). Ties,
\* waits and designations age; a Master whose lease lapsed resigns for good.
TickBy(GC(_, _), FV(_), weight) ==
    /\ ~\E d \in Nodes : TakeOverEnabledBy(GC, FV, weight, d)
    /\ tieAge' = [x \in Nodes |-> IF InTie(x) THEN Min(tieAge[x] + 1, TieGrace) ELSE 0]
    /\ cutAge' = Min(cutAge + 1, TieGrace)
    /\ waitLeft' = [x \in Nodes |-> Max(0, waitLeft[x] - 1)]
    /\ desig' = [i \in 1..Len(desig) |-> [desig[i] EXCEPT !.age = Min(@ + 1, desig[i].span)]]
    /\ UNCHANGED <<conn, envChanges, view, admitted, takeOvers>>
    /\ resigned' = resigned \cup {x \in Nodes : IsMaster(x) /\ ~(LeaseBy(GC, FV, x))'}
    /\ stoodDown' = stoodDown \cup
                      {x \in Nodes : tieAge'[x] >= TieGrace /\ ~(FV(x))' /\ ~(LeaseBy(GC, FV, x))'}
    /\ RunningNext(GC, FV)

\* The partition changes (a cut, a heal, another cut).
Partition(GC(_, _), FV(_), P) ==
    /\ envChanges < MaxEnv
    /\ P # conn
    /\ conn' = P
    /\ envChanges' = envChanges + 1
    /\ cutAge' = 0
    /\ UNCHANGED <<view, resigned, stoodDown, tieAge, desig, admitted, waitLeft, takeOvers>>
    /\ RunningNext(GC, FV)

\* The next-state relation under the rules given (mutants pass broken ones).
NextBy(GC(_, _), FV(_), weight) ==
    \/ \E d \in Designees : Designate(GC, FV, d)
    \/ \E x \in Receivers, s \in 1..MaxDesignations : Admit(GC, FV, x, s)
    \/ \E d \in Nodes : TakeOverBy(GC, FV, weight, d)
    \/ \E n, m \in Nodes : Adopt(GC, FV, n, m)
    \/ \E x \in Nodes : Resume(GC, FV, x)
    \/ \E P \in Partitions : Partition(GC, FV, P)
    \/ TickBy(GC, FV, weight)

\* A period that ends changes something that matters: a count not yet at its bound.
TickMatters ==
    \/ cutAge < TieGrace
    \/ \E x \in Nodes : waitLeft[x] > 0 \/ (InTie(x) /\ tieAge[x] < TieGrace)
    \/ \E i \in 1..Len(desig) : desig[i].age < desig[i].span

\* The steps only a period's end takes (an age grows, a wait shrinks), and only d's
\* take-over (d opens an epoch of its own).
TickStep ==
    \/ cutAge' > cutAge
    \/ \E x \in Nodes : tieAge'[x] > tieAge[x]
    \/ \E x \in Nodes : waitLeft'[x] < waitLeft[x] /\ admitted'[x] = admitted[x]
    \/ \E i \in 1..Len(desig) : i <= Len(desig') /\ desig'[i].age > desig[i].age
TakeOverStep(d) == view'[d].master = d /\ view'[d].epoch > view[d].epoch

\* Weak fairness of periods and take-overs, written with their enabling conditions (which
\* imply ENABLED) and their effects (which only they have), so that each conjunct follows
\* from WF: TLC evaluates no action that primes the lease rule in a temporal formula, nor
\* an operator passed as an argument there, so a mutant writes its own with its rule.
Fairness ==
    /\ <>[](TickMatters /\ ~\E d \in Nodes : TakeOverEnabledBy(GroundCount, ForVote, 1, d))
          => []<><<TickStep>>_vars
    /\ \A d \in Nodes :
          <>[](TakeOverEnabledBy(GroundCount, ForVote, 1, d)) => []<><<TakeOverStep(d)>>_vars

Next == NextBy(GroundCount, ForVote, 1)

Spec == Init /\ [][Next]_vars

FairSpec == Spec /\ Fairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)
RunningMaster(n) == IsMaster(n) /\ running[n]

\* No two running Masters, in any views.
AtMostOneRunningMasterInv ==
    \A a, b \in Nodes : a # b => ~(RunningMaster(a) /\ RunningMaster(b))

\* No node that a running Master's view excludes runs (so no task runs twice).
NoExcludedRunsInv ==
    \A m \in Nodes : RunningMaster(m) => \A x \in view[m].failed : ~running[x]

\* d hears half of its view's members (itself included), a tie only the ground breaks, and
\* at least half of each joint view's.
Heard(d, W) == Cardinality({v \in Members(W) : Hears(d, v)})
HalfSide(d) ==
    /\ 2 * Heard(d, Core(view[d])) = Cardinality(Members(view[d]))
    /\ \A J \in view[d].joint : 2 * Heard(d, J) >= Cardinality(Members(J))

\* The premise of DesignateLiveness: the partition is final and d holds half of its view,
\* no node of its side holding it failed (a node an earlier designee excluded is no
\* candidate); the last designation names d, d admitted it, and its span leaves time for
\* d's wait and the tie grace; a take-over is left.
Headless(d) ==
    /\ envChanges = MaxEnv
    /\ d \notin view[d].failed /\ HalfSide(d)
    /\ \A v \in Nodes : Hears(d, v) => d \notin view[v].failed
    /\ Len(desig) = MaxDesignations
    /\ desig[Len(desig)].node = d
    /\ admitted[d] = Len(desig)
    /\ desig[Len(desig)].age + Max(TieGrace - cutAge, waitLeft[d]) < desig[Len(desig)].span
    /\ takeOvers < MaxTakeOvers

DesignateLiveness == \A d \in Nodes : Headless(d) ~> RunningMaster(d)
=============================================================================
