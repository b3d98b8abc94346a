-------------------------- MODULE DivergedSameView --------------------------
(***************************************************************************)
(* Mutant of DivergedView: a member is passed over on any Prepared under   *)
(* the id of the receiver's view, the same view too (the digest not        *)
(* compared). PN1, the liar, switches PN2 and PN3 into the same (1, 1) Std *)
(* and crashes; PN3 passes PN2 over on its Prepared of that view and takes *)
(* over epoch 3, and PN2, the first Observer of the same view, takes over  *)
(* epoch 2: two Masters of one view's succession, neither holding the      *)
(* other failed. TLC must report OneTakeOverPerViewInv violated in         *)
(* MCDivergedView (exit 12).                                               *)
(***************************************************************************)
EXTENDS MCDivergedView

\* DivergedView's Diverged without the digest's comparison.
PreparedUnderId(n, x) ==
    /\ seq[n] >= 1
    /\ x # Owner(epoch[n])
    /\ \E p \in prepared : p.from = x /\ p.epoch = epoch[n] /\ p.seq = seq[n]

SameViewTakeOver(n) == TakeOverBy(PreparedUnderId, n)

MutantNext == DNextBut \/ \E n \in Nodes : SameViewTakeOver(n)

MutantSpec ==
    /\ DInit /\ [][MutantNext]_divVars
    /\ DFairnessBut
    /\ \A n \in Nodes : WF_divVars(SameViewTakeOver(n))
=============================================================================
