------------------------- MODULE DivergedSameIdOnly -------------------------
(***************************************************************************)
(* Mutant of DivergedView: the rule before, a member passed over only when *)
(* its Prepared names another digest under the id of the receiver's view   *)
(* (seq >= 1), not for a newer switch of its epoch. PN1, the liar and      *)
(* Master of epoch 1, switches PN2 alone into (1, 1) Safe, where PN2 is a  *)
(* Worker, and crashes; PN3's copy never arrives. PN3, in (1, 0) behind    *)
(* PN2, declares PN1 and waits for ever for PN2, which it hears and whose  *)
(* Prepared names a newer id of PN3's epoch; PN2 never takes over: no      *)
(* Master ever again. TLC must report DivergedLiveness violated in         *)
(* MCDivergedViewLost (exit 13).                                           *)
(***************************************************************************)
EXTENDS MCDivergedView

\* DivergedView's Diverged without the newer switch.
SameIdOnly(n, x) == x # Owner(epoch[n]) /\ OtherCopy(n, x)

SameIdOnlyTakeOver(n) == TakeOverBy(SameIdOnly, n)

MutantNext == DNextBut \/ \E n \in Nodes : SameIdOnlyTakeOver(n)

MutantSpec ==
    /\ DInit /\ [][MutantNext]_divVars
    /\ DFairnessBut
    /\ \A n \in Nodes : WF_divVars(SameIdOnlyTakeOver(n))
=============================================================================
