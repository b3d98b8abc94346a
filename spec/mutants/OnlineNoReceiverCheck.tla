----------------------- MODULE OnlineNoReceiverCheck -----------------------
(***************************************************************************)
(* Mutant of Online: the receivers skip the checker (Accepts, and          *)
(* NoPlacement for SAFE) and follow any view from its epoch's owner whose  *)
(* exclusions are backed. The lying Master PN1 sends (1, 1) into SAFE,     *)
(* with no node failed, where every placement of the initial one is still  *)
(* valid (TLC's shortest; a task on a node not capable of it, an           *)
(* overloaded node, a failed or foreign master are as near), and PN2       *)
(* switches to it: TLC must report ValidConfigInv violated (exit 12).      *)
(***************************************************************************)
EXTENDS MCOnline

Unchecked(v) == TRUE

MutantSpec == Init /\ [][NextBy(MayCommand, Unchecked, Backed, PeersPrepared)]_vars
=============================================================================
