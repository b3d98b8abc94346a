---------------------- MODULE DivergedNoNeverPrepared -----------------------
(***************************************************************************)
(* Mutant of DivergedView: the rule before, a member passed over only when *)
(* its Prepared names another digest under the id of the receiver's view   *)
(* or a newer switch of its epoch, not when it never prepared the          *)
(* receiver's view. PN1, the liar and Master of epoch 1, switches PN2      *)
(* alone into (1, 1) Safe, where PN2 is a Worker, then PN3 alone into      *)
(* (1, 2), where PN2 is the first Observer, and crashes. PN3 declares PN1  *)
(* and waits for ever for PN2, which it hears and whose newest Prepared    *)
(* names an older switch of PN3's epoch; PN2 never takes over: no Master   *)
(* ever again. TLC must report DivergedLiveness violated in                *)
(* MCDivergedViewTwoIds (exit 13).                                         *)
(***************************************************************************)
EXTENDS MCDivergedView

\* DivergedView's Diverged without NeverPrepared.
NoNeverPrepared(n, x) == x # Owner(epoch[n]) /\ (OtherCopy(n, x) \/ NewerSwitch(n, x))

NoNeverPreparedTakeOver(n) == TakeOverBy(NoNeverPrepared, n)

MutantNext == DNextBut \/ \E n \in Nodes : NoNeverPreparedTakeOver(n)

MutantSpec ==
    /\ DInit /\ [][MutantNext]_divVars
    /\ DFairnessBut
    /\ \A n \in Nodes : WF_divVars(NoNeverPreparedTakeOver(n))
=============================================================================
