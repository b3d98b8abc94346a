------------------------ MODULE QuorumNonMembersCount ------------------------
(***************************************************************************)
(* Mutant of Quorum: the declarations of any monitor of any configuration  *)
(* that the view does not exclude count, not only the view's members'.     *)
(* TLC must report NoExcludedRunsInv violated (exit 12).                   *)
(***************************************************************************)
EXTENDS MCQuorum

AnyMonitor(V, x, H, F) == ((((UNION MonitorSets) \ V.failed) \ {x}) \cap H) \ F

MutantSpec ==
    Init /\ [][NextBy(Needed, AnyMonitor, JointViews, InheritedViews, NotExcluded)]_vars
=============================================================================
