----------------------- MODULE QuorumReportsToExcluded -----------------------
(***************************************************************************)
(* Mutant of Quorum: a node reports its declarations also to a node its    *)
(* view excludes, and they count there. Five monitors: PN1 excludes PN2 on *)
(* three declarations, the partition changes to {PN1, PN4} | {PN2, PN3,    *)
(* PN5}, and PN2, which does not know it, takes over on its own, PN3's and *)
(* PN5's declarations (PN5 adopted PN1's view, which excludes PN2), while  *)
(* PN1 holds its lease: TLC must report AtMostOneRunningMasterInv violated *)
(* (exit 12).                                                              *)
(***************************************************************************)
EXTENDS MCQuorum

ToExcludedToo(V, x, H, F) == (Members(V) \ {x}) \cap H

MutantSpec ==
    Init /\ [][NextBy(Needed, ToExcludedToo, JointViews, InheritedViews, NotExcluded)]_vars
=============================================================================
