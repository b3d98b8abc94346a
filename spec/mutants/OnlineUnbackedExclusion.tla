---------------------- MODULE OnlineUnbackedExclusion ----------------------
(***************************************************************************)
(* Mutant of Online: a receiver follows a view whose failed set no crash   *)
(* and no declaration backs. The lying Master PN1 sends (1, 1) excluding   *)
(* PN2, running and correct, with t1 on PN3 and t2 shed: the checker       *)
(* accepts it under the failed set it names, and PN2 switches to it: TLC   *)
(* must report ValidConfigInv violated (exit 12). Checked without it, by   *)
(* hand, NoDoubleActivationInv fails too (263 states): PN3 waits for no    *)
(* "Prepared" of PN2's and starts t1, which PN2 still runs.                *)
(***************************************************************************)
EXTENDS MCOnline

Unbacked(s, v) == TRUE

MutantSpec == Init /\ [][NextBy(MayCommand, Checked, Unbacked, PeersPrepared)]_vars
=============================================================================
