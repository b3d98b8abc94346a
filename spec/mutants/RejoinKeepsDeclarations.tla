------------------------ MODULE RejoinKeepsDeclarations ------------------------
(***************************************************************************)
(* Mutant of Rejoin: a readmission leaves the other monitors' declarations *)
(* of the readmitted node (their counts restart, their reports stand). A   *)
(* restarted node, readmitted, is excluded again on two stale reports      *)
(* while it is healthy: TLC must report RNoFalseExclusionInv violated      *)
(* (exit 12).                                                              *)
(***************************************************************************)
EXTENDS MCRejoin

MutantSpec == RInit /\ [][RNextBy(FALSE)]_everything
=============================================================================
