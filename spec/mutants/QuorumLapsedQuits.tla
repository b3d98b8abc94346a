-------------------------- MODULE QuorumLapsedQuits --------------------------
(***************************************************************************)
(* Mutant of Quorum under a healing partition: a Master whose lease        *)
(* lapsed stops for good (the runtime's resignation), and nothing else     *)
(* takes its place once the cut heals: its resignation is taken as its     *)
(* word only by a node that cannot hear it, as a declaration is, so after  *)
(* a heal no node takes over. A cut that heals before the other side took  *)
(* over leaves no running Master for good: TLC must report                 *)
(* HealedOneMasterLiveness violated (exit 13). (Quorum's Master instead    *)
(* runs again once its lease holds again; the runtime's resigns and its    *)
(* successor takes over on its word, which the successor hears in its      *)
(* heartbeats: Lease.tla.)                                                 *)
(***************************************************************************)
EXTENDS MCQuorumLive

VARIABLE quit  \* the Masters that stopped for good
mvars == <<vars, quit>>

\* A quit node holds no lease (its stale voters are never fewer than none), and an exclusion
\* or a take-over of it needs no declaration (its word; the take-over still needs the taker
\* not to hear it).
QuitNeeded(mem, x) == IF x \in quit THEN 0 ELSE Needed(mem, x)

\* A Master that was not running in the step before quits (set first: the lease of the next
\* state reads quit').
Quits == quit' = quit \cup {m \in Nodes : IsMaster(m) /\ ~running[m]}

MutantNext ==
    Quits /\ NextBy(QuitNeeded, MemberVoters, JointViews, InheritedViews, NotExcluded)

MutantFairness ==
    /\ \A n, m \in Nodes : WF_mvars(Quits /\ Adopt(QuitNeeded, JointViews, n, m))
    /\ \A m \in Nodes : WF_mvars(Quits /\ Complete(QuitNeeded, JointViews, NotExcluded, m))

MutantSpec == Init /\ quit = {} /\ [][MutantNext]_mvars /\ MutantFairness
=============================================================================
