------------------------- MODULE OnlineNoOwnership -------------------------
(***************************************************************************)
(* Mutant of Online: a Command is followed from the master its view names, *)
(* whoever owns its epoch. PN2 takes over from the lying PN1 in epoch 2,   *)
(* which PN2 owns, and PN3 follows PN1's view of epoch 2, which the        *)
(* checker accepts: TLC must report OneMasterPerEpochInv violated (exit    *)
(* 12).                                                                    *)
(***************************************************************************)
EXTENDS MCOnline

AnyOwner(s, v) == s = v.master

MutantSpec == Init /\ [][NextBy(AnyOwner, Checked, Backed, PeersPrepared)]_vars
=============================================================================
