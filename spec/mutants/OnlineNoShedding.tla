-------------------------- MODULE OnlineNoShedding --------------------------
(***************************************************************************)
(* Mutant of Online: the receivers check an online configuration as the    *)
(* graph's are checked, every task placed (placement::check with           *)
(* Shedding::forbidden). In a correct cluster PN1 crashes and PN2 takes    *)
(* over with a configuration that sheds t2, which the checker allows (a    *)
(* correct placer sheds only what does not fit, as when PN3 crashes too;   *)
(* the spec lets a correct Master pick any configuration the checker       *)
(* accepts); PN3 refuses the correct Master's Command and declares PN2     *)
(* failed: TLC must report NoHonestRefusalInv violated (exit 12).          *)
(***************************************************************************)
EXTENDS MCOnline

CheckedNoShedding(v) == Checked(v) /\ (v.config # Safe => Placed(v.config) = Tasks)

MutantSpec == Init /\ [][NextBy(MayCommand, CheckedNoShedding, Backed, PeersPrepared)]_vars
=============================================================================
