-------------------------- MODULE OnlineNoShedding --------------------------
(***************************************************************************)
(* Mutant of Online: the receivers check an online configuration as the    *)
(* graph's are checked, every task placed (placement::check with           *)
(* Shedding::forbidden). In a correct cluster, PN3 crashes and PN1's       *)
(* placer sheds t2 (t1 takes PN2, the one node left capable of either);    *)
(* PN2 refuses the correct Master's Command and declares PN1 failed: TLC   *)
(* must report NoHonestRefusalInv violated (exit 12).                      *)
(***************************************************************************)
EXTENDS MCOnline

CheckedNoShedding(v) == Checked(v) /\ (v.config # Safe => Placed(v.config) = Tasks)

MutantSpec == Init /\ [][NextBy(MayCommand, CheckedNoShedding, Backed, PeersPrepared)]_vars
=============================================================================
