---------------------------- MODULE PassOverNone ----------------------------
(***************************************************************************)
(* Mutant of PassOver: no pass-over; an Observer takes over only once      *)
(* every node ahead of it is declared. PN1, the Master, hands PN3 epoch 3; *)
(* PN3 takes it and commands, PN2 follows it, and PN3 crashes before PN4   *)
(* follows: PN4 missed its Commands for good. PN1, an Observer of epoch 3  *)
(* behind PN4, declares PN3 and waits for ever for PN4, which it hears;    *)
(* PN4 runs as a Worker of epoch 1 and never takes over; PN2, a Worker of  *)
(* epoch 3, waits for PN4 and PN1: no Master ever again (keel-sim --liar   *)
(* --loss 5%, prototype3 seed 826, on four nodes). TLC must report         *)
(* PassOverLiveness violated in MCPassOver (exit 13).                      *)
(***************************************************************************)
EXTENDS MCPassOver

\* No member is passed over.
NoPass(n, x) == FALSE

NoPassTakeOver(n) == TakeOverBy(NoPass, n)

MutantNext == PNextBut \/ \E n \in Nodes : NoPassTakeOver(n)

MutantSpec ==
    /\ PInit /\ [][MutantNext]_passVars
    /\ PFairnessBut
    /\ \A n \in Nodes : WF_passVars(NoPassTakeOver(n))
=============================================================================
