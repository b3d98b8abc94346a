------------------------ MODULE TakeOverOwnEpochOnly ------------------------
(***************************************************************************)
(* Mutant of TakeOverEpoch: the take-over as it was, above the taker's own *)
(* epoch (or the one a Master it declared left follows) only, whatever     *)
(* epoch its voters follow. PN1, the lying Master, sends PN3 alone a       *)
(* Command of its epoch 4 and crashes; PN2 takes over epoch 2, below the   *)
(* epoch PN3 follows, and steps down at once, its lease lapsed on PN3's    *)
(* acknowledgements of epoch 4 (before Reclaim moves it past 4); its word  *)
(* is of epoch 2, stale for PN3, which waits for PN2, ahead of it in the   *)
(* succession of epoch 4: no Master ever again (keel-sim --liar,           *)
(* prototype3 seed 49016). TLC must report TakeOverLiveness violated in    *)
(* MCTakeOverEpoch (exit 13).                                              *)
(***************************************************************************)
EXTENDS MCTakeOverEpoch

\* The take-over before the rule: ElectionLiar's floor, the voters' epochs unread.
OwnEpochTakeOver(n) == TakeOverBy(TakeOverFloor, n)

MutantNext == TNextBut \/ \E n \in Nodes : OwnEpochTakeOver(n)

MutantSpec ==
    /\ TInit /\ [][MutantNext]_takeOverVars
    /\ TFairnessBut
    /\ \A n \in Nodes : WF_takeOverVars(OwnEpochTakeOver(n))
=============================================================================
