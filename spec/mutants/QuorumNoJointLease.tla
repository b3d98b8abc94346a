------------------------- MODULE QuorumNoJointLease -------------------------
(***************************************************************************)
(* Mutant of Quorum: no joint views: a Master judges its lease and its     *)
(* evidence by the view it drives only, and every other node by its own    *)
(* view (keel-sim's no-joint-views), majority quorums kept. TLC must       *)
(* report AtMostOneRunningMasterInv violated (exit 12).                    *)
(***************************************************************************)
EXTENDS MCQuorum

NoJointViews(master, P, V) == {}

MutantSpec ==
    Init /\ [][NextBy(Needed, MemberVoters, NoJointViews, InheritedViews, NotExcluded)]_vars
=============================================================================
