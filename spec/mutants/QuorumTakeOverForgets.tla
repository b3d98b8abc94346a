------------------------ MODULE QuorumTakeOverForgets ------------------------
(***************************************************************************)
(* Mutant of Quorum: an Observer that takes over makes only the view it    *)
(* took over from pending, not that view's joint views (without rule 3a).  *)
(* PN1 switches to C1, PN2 adopts it, the partition {PN1, PN4} | {PN2,     *)
(* PN3, ST1} follows; PN2 takes over in C1 and excludes PN4 on C1's        *)
(* quorum, two declarations, while PN4 still goes by D1, where its lease   *)
(* needs three stale voters: TLC must report NoExcludedRunsInv violated    *)
(* (exit 12).                                                              *)
(***************************************************************************)
EXTENDS MCQuorum

OnlyItsView(V) == {}

MutantSpec ==
    Init /\ [][NextBy(Needed, MemberVoters, JointViews, OnlyItsView, NotExcluded)]_vars
=============================================================================
