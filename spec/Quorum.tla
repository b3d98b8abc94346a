------------------------------- MODULE Quorum -------------------------------
(***************************************************************************)
(* Majority quorums and joint views: one running Master across a phase     *)
(* switch cut by a partition (fault model 2).                              *)
(*                                                                         *)
(* Lease.tla lets a node run only while fewer of its voters may hold it    *)
(* failed than an exclusion of it needs, so it stops before the cluster    *)
(* may replace it. It assumes every node knows the cluster's exclusions at *)
(* once and that there is one fixed monitor set. Neither holds when a      *)
(* switch is under way: a node goes by the view it adopted last, and a     *)
(* phase switch may change the monitor set. keel-sim found the run on the  *)
(* Earth-observation mission: views D1 (Master PN1, Observers PN2, PN3,    *)
(* PN4) and C1 (Master PN1, Observers PN2, PN3). PN1 starts the switch     *)
(* D1 -> C1 and the partition {PN1, PN3} | {PN2, PN4} cuts it before PN2   *)
(* and PN4 adopt C1. PN1, in C1, holds its lease (one of its two voters is *)
(* cut off) and excludes PN2 on its own and PN3's declarations; PN2, in    *)
(* D1, takes over on its own and PN4's declarations (two of D1's four      *)
(* monitors: the rule was two declarations, one when one voter is left),   *)
(* and its lease, PN1 decided out, holds as well: two running Masters.     *)
(*                                                                         *)
(* The fix, which the runtime implements (core/fsm/node_protocol.cpp):     *)
(*  1. Majority quorum. An exclusion of x in view V needs declarations     *)
(*     from Needed(Members(V), x) of V's members: the members are V's      *)
(*     monitors (Master and Observers) that V has not excluded, x counted  *)
(*     when it is one; a majority of them, at most the voters (the members *)
(*     but x), at least one (2 members: 1, so both sides of a 1|1 split    *)
(*     stop; 3: 2; 4: 3; 5: 3). Only the members' declarations count.      *)
(*  2. The lease uses the same Needed: x runs in V while fewer than        *)
(*     Needed(Members(V) \ without, x) of its voters there, but those in   *)
(*     `without`, may hold it failed. A decider needs its lease with the   *)
(*     nodes it decides on left out (an Observer taking over: the Master   *)
(*     and the Observers ahead of it).                                     *)
(*  3. Joint views. A Master's switch (a phase switch, an exclusion, a     *)
(*     take-over) is under way until every node the new view does not      *)
(*     exclude has adopted it; meanwhile the views since its last          *)
(*     completed switch are pending: some node may still go by one. The    *)
(*     Master runs only while its lease holds in its view and in every     *)
(*     pending view (the nodes its view excluded since left out), and it   *)
(*     excludes a node only with evidence in each.                         *)
(* TLC showed three more rules necessary (each mutant named below breaks   *)
(* without its rule):                                                      *)
(*  3a. A view carries the views pending when its Master made it (`joint`, *)
(*     sent in the Command). An Observer taking over knows of no other     *)
(*     views its Master's nodes may go by: its pending views are the view  *)
(*     it took over from and that view's joint views.                      *)
(*     (QuorumTakeOverForgets: PN2 takes over in C1 while PN4 still goes   *)
(*     by D1, then excludes PN4 on C1's quorum, two declarations, where    *)
(*     PN4's lease in D1 needs three stale voters.)                        *)
(*  3b. Every node, not only the Master, runs only while its lease holds   *)
(*     in its view and in its view's joint views (the Master, which knows  *)
(*     when its switch completes: in its pending views). (QuorumFollower-  *)
(*     OwnView: five monitors; PN1 switches to C {PN1, PN2, PN3}, only PN2 *)
(*     adopts it, the partition {PN1, PN2} | {PN3, PN4, PN5} follows; PN3  *)
(*     takes over from PN1 and PN2 on three of the five, and PN2, whose    *)
(*     lease in C needs two of PN1 and PN3, keeps running.)                *)
(*  4. A node's declarations count only while it holds its lease (a node   *)
(*     whose lease lapsed reports nothing). Rule 3 leaves the nodes the    *)
(*     Master excluded out of its lease in a pending view; such a node     *)
(*     may not know it and still declare there. (QuorumLapsedReports: five *)
(*     monitors; PN1 excludes PN3 on three declarations, the partition     *)
(*     changes to {PN1, PN4} | {PN2, PN3, PN5}, and PN2, still in the view *)
(*     before, takes over on its own, PN5's and PN3's declarations, while  *)
(*     PN1 holds its lease: in the five without PN3 it needs three.)       *)
(* A node also reports to no node its view excludes, as the runtime's      *)
(* report_declared does (QuorumReportsToExcluded: in the same run PN1      *)
(* excludes PN2, and PN5, which adopted that view, vouches for PN2's       *)
(* take-over).                                                             *)
(* Without rules 1 and 3 (QuorumBeforeFix) TLC finds keel-sim's run;       *)
(* without joint views (QuorumNoJointLease), with a non-member's           *)
(* declaration counted (QuorumNonMembersCount), or with a switch complete  *)
(* once its monitors adopted it (QuorumCompleteMonitorsOnly), it finds two *)
(* running Masters or an excluded node running. With rules 2 to 4 in       *)
(* place it finds neither in the CI models under the old count (two        *)
(* declarations) either: the majority is what keeps the larger side of a   *)
(* 2|2 or 2|3 split running (with two declarations every node there loses  *)
(* its lease, and by rule 4 no one can decide).                            *)
(*                                                                         *)
(* Abstractions. This is the decision level: time is left out. Lease.tla   *)
(* shows, with time, that a node's lease lapses before the declarations an *)
(* exclusion of it needs exist (AckBoundInv); here a monitor holds a node  *)
(* failed exactly while it cannot hear it (conn, a partition of the nodes  *)
(* that the environment changes at most MaxEnv times), a decider receives  *)
(* the declarations of the nodes it hears, and a node's lease is read from *)
(* the same instant: v may hold x failed while v cannot hear x, or while v *)
(* goes by a view that excludes x (no monitor acknowledges an excluded     *)
(* node). The monitors whose declarations a decider counted adopt its new  *)
(* view in the same step: its Command answers their reports on a link that *)
(* carried them a moment ago (the environment does not cut it within one   *)
(* message delay; see docs/fault-model.md). Any other node adopts a newer view when it  *)
(* hears a running Master that drives it (Adopt), so a partition may cut a *)
(* switch anywhere. A crash is a node cut off from all for good, which     *)
(* covers it (a cut-off node may still run). A Master whose lease lapsed   *)
(* stops and may run again when its lease holds again (it need not resign, *)
(* as the runtime's does).                                                 *)
(*                                                                         *)
(* Properties: AtMostOneRunningMasterInv, no two nodes each Master of its  *)
(* own view and running; NoExcludedRunsInv, no node that a running         *)
(* Master's view excludes runs (so no task runs twice). Both are about     *)
(* `running`, which each step sets from the lease rule in force, so a      *)
(* mutant's broken rule is what the properties judge.                      *)
(*                                                                         *)
(* The rules are parameters of NextBy, one operator each, so that a mutant *)
(* swaps one: NeededOp (rule 1's count), CountedOp (whose declarations     *)
(* count: rule 1, rule 4, the reports), GoesByOp (the views besides its    *)
(* own that a node's lease and a Master's evidence must hold in: rules 3   *)
(* and 3b), InheritOp (what an Observer that takes over makes pending      *)
(* besides its view: rule 3a), MustAdoptOp (who must adopt a view for its  *)
(* switch to complete: rule 3).                                            *)
(***************************************************************************)
EXTENDS Naturals, FiniteSets, Sequences, QuorumRule

CONSTANTS
    Nodes,        \* every processing node: the monitors of any configuration, and Workers
    Order,        \* the nodes in succession order, the initial Master first; the owners of epochs
    MonitorSets,  \* the monitor sets (Master and Observers) of the mission's configurations
    InitMons,     \* the monitor set of the initial view (its Master is Order[1])
    MaxEnv,       \* environment: at most this many partition changes
    MaxDecisions  \* at most this many switches started (phase switches, exclusions, take-overs)

ASSUME Order \in Seq(Nodes) /\ Len(Order) = Cardinality(Nodes)
ASSUME \A i, j \in 1..Len(Order) : i # j => Order[i] # Order[j]
ASSUME MonitorSets \subseteq SUBSET Nodes /\ InitMons \in MonitorSets /\ Order[1] \in InitMons
ASSUME MaxEnv \in Nat /\ MaxDecisions \in Nat

(***************************************************************************)
(* A view is what a Master's Command carries: its id <<epoch, seq>> (an    *)
(* epoch belongs to one node, so an id names one view), its monitor set    *)
(* (the configuration's Master and Observers), its Master, the nodes it    *)
(* excludes (`failed`, as the runtime's View) and the views pending at its *)
(* Master when it made it (`joint`, rule 3a; those carry no `joint`).      *)
(***************************************************************************)
CoreType == [epoch : Nat, seq : Nat, mons : SUBSET Nodes, master : Nodes, failed : SUBSET Nodes]
ViewType == [epoch : Nat, seq : Nat, mons : SUBSET Nodes, master : Nodes, failed : SUBSET Nodes,
             joint : SUBSET CoreType]

VARIABLES
    conn,        \* env: the partition, a set of disjoint blocks covering Nodes; a node hears
                 \* exactly the nodes of its block
    view,        \* [Nodes -> ViewType], the view a node goes by (adopted, or made as its Master)
    pending,     \* [Nodes -> SUBSET CoreType], a Master's views since its last completed switch
    running,     \* [Nodes -> BOOLEAN], the node runs: it holds its lease by the rule in force
    envChanges,  \* env: partition changes so far
    decisions    \* switches started so far

vars == <<conn, view, pending, running, envChanges, decisions>>


\* Every partition of the nodes into blocks (evaluated once: a constant).
Partitions ==
    {{{n \in Nodes : f[n] = i} : i \in {f[k] : k \in Nodes}} :
        f \in [Nodes -> 1..Cardinality(Nodes)]}

Pos(n) == CHOOSE i \in 1..Len(Order) : Order[i] = n
\* Epoch e belongs to one node (MasterElection's Owner); a take-over claims the taker's next.
Owner(e) == Order[((e - 1) % Len(Order)) + 1]
NextEpoch(d, e) == CHOOSE e2 \in (e + 1)..(e + Len(Order)) : Owner(e2) = d

Core(V) == [epoch |-> V.epoch, seq |-> V.seq, mons |-> V.mons, master |-> V.master,
            failed |-> V.failed]
Newer(V, W) == V.epoch > W.epoch \/ (V.epoch = W.epoch /\ V.seq > W.seq)

Hears(a, b) == \E B \in conn : a \in B /\ b \in B

\* The members of view V: its monitors that it does not exclude.
Members(V) == V.mons \ V.failed

\* Rule 1's count, Needed(mem, x): spec/QuorumRule.tla (the trace spec checks it too).

\* Rule 1: only the declarations of V's members (x left out) count; rule 4: only those of
\* the nodes in H, which hold their lease; and none of the nodes in F, whose views exclude
\* the decider (a node reports to no node its view excludes: report_declared).
MemberVoters(V, x, H, F) == ((Members(V) \ {x}) \cap H) \ F

\* n is the Master of the view it goes by.
IsMaster(n) == view[n].master = n /\ n \notin view[n].failed

\* Rules 3 and 3b: the views besides its own view V that a node's lease must hold in, and a
\* Master's evidence, from whether it is V's Master and its pending views P: a Master's
\* pending views, any other node's view's joint views. (The operators that a mutant swaps
\* read no variable, so that TLC still names each step's action.)
JointViews(master, P, V) == IF master THEN P ELSE V.joint

\* Rule 3a: what an Observer taking over from view V makes pending besides V.
InheritedViews(V) == V.joint

\* Completion: the nodes that must have adopted view V, all it does not exclude.
NotExcluded(V) == Nodes \ V.failed

(***************************************************************************)
(* Declarations and the lease                                              *)
(***************************************************************************)

\* Monitor v declares x failed (its report, or its own count at the limit).
Declares(v, x) == ~Hears(v, x)

\* Voter v may hold x failed: x's lease cannot count on v's acknowledgement.
MayHoldFailed(v, x) == ~Hears(v, x) \/ x \in view[v].failed

\* Rule 2: x's lease holds in view V with the voters in `without` left out.
HoldsIn(NeededOp(_, _), V, x, without) ==
    Cardinality({v \in (Members(V) \ without) \ {x} : MayHoldFailed(v, x)})
        < NeededOp(Members(V) \ without, x)

\* The views besides its own that x goes by, by the rule GoesByOp.
GoesBy(GoesByOp(_, _, _), x) == GoesByOp(IsMaster(x), pending[x], view[x])

\* Whether x runs: not excluded in its view, its lease holding in its view and in the views
\* it also goes by, with the nodes its view excluded since left out there.
LeaseBy(NeededOp(_, _), GoesByOp(_, _, _), x) ==
    /\ x \notin view[x].failed
    /\ HoldsIn(NeededOp, view[x], x, {})
    /\ \A P \in GoesBy(GoesByOp, x) : HoldsIn(NeededOp, P, x, view[x].failed \ P.failed)

\* The declarations of x decider d receives, counted in view V: its own, and those of the
\* nodes it hears, as far as CountedOp counts them.
Reporters(CountedOp(_, _, _, _), d, V, x) ==
    LET holding == {n \in Nodes : running[n]} \cup {d}
        refusing == {n \in Nodes : d \in view[n].failed}
    IN {v \in CountedOp(V, x, holding, refusing) : (v = d \/ Hears(d, v)) /\ Declares(v, x)}

EvidenceIn(NeededOp(_, _), CountedOp(_, _, _, _), d, V, x) ==
    Cardinality(Reporters(CountedOp, d, V, x)) >= NeededOp(Members(V), x)

TypeOK ==
    /\ conn \in Partitions
    /\ view \in [Nodes -> ViewType]
    /\ pending \in [Nodes -> SUBSET CoreType]
    /\ running \in [Nodes -> BOOLEAN]
    /\ envChanges \in 0..MaxEnv
    /\ decisions \in 0..MaxDecisions

InitView == [epoch |-> 1, seq |-> 0, mons |-> InitMons, master |-> Order[1], failed |-> {},
             joint |-> {}]

Init ==
    /\ conn = {Nodes}
    /\ view = [n \in Nodes |-> InitView]
    /\ pending = [n \in Nodes |-> {}]
    /\ running = [n \in Nodes |-> TRUE]
    /\ envChanges = 0
    /\ decisions = 0

(***************************************************************************)
(* Protocol. Every step sets `running` anew from the lease rule in force.  *)
(***************************************************************************)

RunningNext(NeededOp(_, _), GoesByOp(_, _, _)) ==
    running' = [x \in Nodes |-> (LeaseBy(NeededOp, GoesByOp, x))']

\* Decider d makes view `new`, leaving its view pending (with `left`); the nodes in `told`
\* (whose declarations it counted) adopt `new` at once when it is newer than theirs.
Decide(d, new, left, told) ==
    /\ view' = [n \in Nodes |->
                  IF n = d \/ (n \in told /\ Newer(new, view[n])) THEN new ELSE view[n]]
    /\ pending' = [n \in Nodes |->
                     IF n = d THEN left
                     ELSE IF n \in told /\ Newer(new, view[n]) THEN {}
                     ELSE pending[n]]
    /\ decisions' = decisions + 1
    /\ UNCHANGED <<conn, envChanges>>

\* The running Master m, with no switch under way, switches to a configuration with monitor
\* set S (a phase change).
PhaseSwitch(NeededOp(_, _), GoesByOp(_, _, _), m, S) ==
    /\ decisions < MaxDecisions
    /\ IsMaster(m) /\ running[m] /\ pending[m] = {}
    /\ S # view[m].mons /\ m \in S
    /\ Decide(m, [view[m] EXCEPT !.seq = @ + 1, !.mons = S, !.joint = {Core(view[m])}],
              {Core(view[m])}, {})
    /\ RunningNext(NeededOp, GoesByOp)

\* The running Master m excludes x, with evidence in its view and in each view it also goes
\* by that does not exclude x already (rules 1 and 3).
Exclude(NeededOp(_, _), CountedOp(_, _, _, _), GoesByOp(_, _, _), m, x) ==
    LET left == pending[m] \cup {Core(view[m])}
        told == UNION {Reporters(CountedOp, m, V, x) :
                          V \in {Core(view[m])} \cup GoesBy(GoesByOp, m)}
    IN /\ decisions < MaxDecisions
       /\ IsMaster(m) /\ running[m]
       /\ x # m /\ x \notin view[m].failed
       /\ EvidenceIn(NeededOp, CountedOp, m, view[m], x)
       /\ \A P \in GoesBy(GoesByOp, m) : x \in P.failed \/ EvidenceIn(NeededOp, CountedOp, m, P, x)
       /\ Decide(m, [view[m] EXCEPT !.seq = @ + 1, !.failed = @ \cup {x}, !.joint = left],
                 left, told)
       /\ RunningNext(NeededOp, GoesByOp)

\* The position of c in the succession after view V's Master.
SuccPos(V, c) == (Pos(c) - Pos(V.master) + Len(Order)) % Len(Order)

\* Observer d takes over from its view's Master: it declares the Master and every member
\* ahead of it in the succession, has evidence on each in its view, and holds its lease
\* with them left out (rule 2). Its view excludes them all, in its next epoch.
TakeOver(NeededOp(_, _), CountedOp(_, _, _, _), GoesByOp(_, _, _), InheritOp(_), d) ==
    LET V == view[d]
        ahead == {c \in Members(V) \ {V.master, d} : SuccPos(V, c) < SuccPos(V, d)}
        decided == {V.master} \cup ahead
        left == {Core(V)} \cup InheritOp(V)
        told == UNION {Reporters(CountedOp, d, V, c) : c \in decided}
    IN /\ decisions < MaxDecisions
       /\ d \in Members(V) /\ d # V.master
       /\ \A c \in decided : Declares(d, c) /\ EvidenceIn(NeededOp, CountedOp, d, V, c)
       /\ HoldsIn(NeededOp, V, d, decided)
       /\ Decide(d, [epoch |-> NextEpoch(d, V.epoch), seq |-> 0, mons |-> V.mons, master |-> d,
                     failed |-> V.failed \cup decided, joint |-> left],
                 left, told)
       /\ RunningNext(NeededOp, GoesByOp)

\* Node n hears the running Master m, whose view is newer than n's, and adopts it (a Master
\* of an older view steps down).
Adopt(NeededOp(_, _), GoesByOp(_, _, _), n, m) ==
    /\ n # m /\ IsMaster(m) /\ running[m] /\ Hears(n, m)
    /\ Newer(view[m], view[n])
    /\ view' = [view EXCEPT ![n] = view[m]]
    /\ pending' = [pending EXCEPT ![n] = {}]
    /\ UNCHANGED <<conn, envChanges, decisions>>
    /\ RunningNext(NeededOp, GoesByOp)

\* Master m's switch completes: every node that must adopt its view has.
Complete(NeededOp(_, _), GoesByOp(_, _, _), MustAdoptOp(_), m) ==
    /\ IsMaster(m) /\ pending[m] # {}
    /\ \A n \in MustAdoptOp(view[m]) : view[n] = view[m]
    /\ pending' = [pending EXCEPT ![m] = {}]
    /\ UNCHANGED <<conn, view, envChanges, decisions>>
    /\ RunningNext(NeededOp, GoesByOp)

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* The partition changes (a cut, a heal, another cut).
Partition(NeededOp(_, _), GoesByOp(_, _, _), P) ==
    /\ envChanges < MaxEnv
    /\ P # conn
    /\ conn' = P
    /\ envChanges' = envChanges + 1
    /\ UNCHANGED <<view, pending, decisions>>
    /\ RunningNext(NeededOp, GoesByOp)

\* The next-state relation with the given rules (mutants pass a broken one).
NextBy(NeededOp(_, _), CountedOp(_, _, _, _), GoesByOp(_, _, _), InheritOp(_), MustAdoptOp(_)) ==
    \/ \E m \in Nodes, S \in MonitorSets : PhaseSwitch(NeededOp, GoesByOp, m, S)
    \/ \E m, x \in Nodes : Exclude(NeededOp, CountedOp, GoesByOp, m, x)
    \/ \E d \in Nodes : TakeOver(NeededOp, CountedOp, GoesByOp, InheritOp, d)
    \/ \E n, m \in Nodes : Adopt(NeededOp, GoesByOp, n, m)
    \/ \E m \in Nodes : Complete(NeededOp, GoesByOp, MustAdoptOp, m)
    \/ \E P \in Partitions : Partition(NeededOp, GoesByOp, P)

Next == NextBy(Needed, MemberVoters, JointViews, InheritedViews, NotExcluded)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

RunningMaster(n) == IsMaster(n) /\ running[n]

\* No two running Masters, in any views.
AtMostOneRunningMasterInv ==
    \A a, b \in Nodes : a # b => ~(RunningMaster(a) /\ RunningMaster(b))

\* No node that a running Master's view excludes runs.
NoExcludedRunsInv ==
    \A m \in Nodes : RunningMaster(m) => \A x \in view[m].failed : ~running[x]
=============================================================================
