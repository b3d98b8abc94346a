--------------------------- MODULE QuorumBeforeFix ---------------------------
(***************************************************************************)
(* Mutant of Quorum: the runtime before the fix: two declarations (one     *)
(* when one voter is left) for an exclusion and the lease, no joint views, *)
(* and the declarations of a node whose lease lapsed count. TLC must       *)
(* report AtMostOneRunningMasterInv violated (exit 12), as keel-sim's run  *)
(* does: PN1 switches D1 -> C1, the partition {PN1, PN3} | {PN2, PN4, ST1} *)
(* cuts it, PN3 adopts C1, PN1 excludes PN2 with PN3's declaration, and    *)
(* PN2 takes over with PN4's: both run (TLC's shortest run is another      *)
(* cut of the same switch).                                                *)
(***************************************************************************)
EXTENDS MCQuorum

TwoDeclarations(mem, x) == IF Cardinality(mem \ {x}) >= 2 THEN 2 ELSE 1
LapsedToo(V, x, H, F) == (Members(V) \ {x}) \ F
NoJointViews(master, P, V) == {}

MutantSpec ==
    Init /\ [][NextBy(TwoDeclarations, LapsedToo, NoJointViews, InheritedViews,
                      NotExcluded)]_vars

\* keel-sim's run: PN1 (in C1) has excluded PN2, PN2 (from D1) has taken over, both run.
KeelSimRunInv ==
    ~(/\ RunningMaster(S1) /\ RunningMaster(S2)
      /\ view[S1].mons = {S1, S2, S3} /\ S2 \in view[S1].failed
      /\ view[S2].mons = {S1, S2, S3, S4} /\ S1 \in view[S2].failed)
=============================================================================
