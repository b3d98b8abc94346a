------------------------ MODULE OnlineNoPeerPrepared ------------------------
(***************************************************************************)
(* Mutant of Online: a node starts its view's tasks without its peers'     *)
(* "Prepared" of that view (no rule 4). The lying Master PN1 sends PN2 a   *)
(* switch that swaps t1 and t2, which the checker accepts; PN2 starts t2   *)
(* while PN3, which has not received it, still runs t2: TLC must report    *)
(* NoDoubleActivationInv violated (exit 12).                               *)
(***************************************************************************)
EXTENDS MCOnline

NoPeers(n) == TRUE

MutantSpec == Init /\ [][NextBy(MayCommand, Checked, Backed, NoPeers)]_vars
=============================================================================
