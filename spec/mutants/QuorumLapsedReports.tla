------------------------- MODULE QuorumLapsedReports -------------------------
(***************************************************************************)
(* Mutant of Quorum: a member's declarations count whether or not it holds *)
(* its lease (without rule 4). Five monitors: PN1 excludes PN3 on a        *)
(* majority, a second partition puts PN3 and PN5 with PN2, and PN2, still  *)
(* in the view before the exclusion, takes over on its own, PN5's and the  *)
(* excluded PN3's declarations, while PN1 holds its lease with PN3 left    *)
(* out: TLC must report AtMostOneRunningMasterInv violated (exit 12).      *)
(***************************************************************************)
EXTENDS MCQuorum

LapsedToo(V, x, H, F) == (Members(V) \ {x}) \ F

MutantSpec ==
    Init /\ [][NextBy(Needed, LapsedToo, JointViews, InheritedViews, NotExcluded)]_vars
=============================================================================
