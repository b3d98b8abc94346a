------------------------- MODULE HandedViewEdge -------------------------
(***************************************************************************)
(* Mutant of HandedView: the edge binds the next switch of a handed view   *)
(* too (rule 3 at seq 0 of every epoch, the code before seed 15049's fix). *)
(* The liar PN1 hands PN2 one view and PN3 another under one id (epoch 2,  *)
(* seq 0); PN2's boot switch, true to its own copy, follows no edge from   *)
(* PN3's, and PN3 refuses it and declares PN2, a correct Master, failed:   *)
(* TLC must report NoHonestRefusalInv violated (exit 12).                  *)
(***************************************************************************)
EXTENDS MCHandedView

\* The next switch of the receiver's view from the same master, whatever that view.
AnyNextSwitch(n, v) ==
    v.epoch = view[n].epoch /\ v.master = view[n].master /\ v.seq = view[n].seq + 1

EdgeAtHandedView(n, v) == HCheckedBy(AnyNextSwitch, n, v)

MutantSpec == Init /\ [][HNextBy(EdgeAtHandedView)]_vars
=============================================================================
