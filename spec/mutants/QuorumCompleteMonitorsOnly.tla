--------------------- MODULE QuorumCompleteMonitorsOnly ---------------------
(***************************************************************************)
(* Mutant of Quorum: a switch completes once the view's members (its       *)
(* monitors) have adopted it, without the Workers and the monitors the     *)
(* switch dropped. TLC must report NoExcludedRunsInv violated (exit 12).   *)
(***************************************************************************)
EXTENDS MCQuorum

MembersOnly(V) == Members(V)

MutantSpec ==
    Init /\ [][NextBy(Needed, MemberVoters, JointViews, InheritedViews, MembersOnly)]_vars
=============================================================================
