---------------------------- MODULE DivergedNone ----------------------------
(***************************************************************************)
(* Mutant of DivergedView: no pass-over of a member that prepared another  *)
(* view; an Observer takes over only once every Observer ahead of it is    *)
(* declared. PN1, the liar and Master of epoch 1, switches PN3 into        *)
(* (1, 1) Std, where PN2 is the first Observer, and PN2 into (1, 1) Safe,  *)
(* where PN2 is a Worker, and crashes. PN3 declares PN1 and waits for ever *)
(* for PN2, which it hears; PN2 never takes over: no Master ever again     *)
(* (keel-sim --liar, prototype3 seed 30979). TLC must report               *)
(* DivergedLiveness violated in MCDivergedView (exit 13).                  *)
(***************************************************************************)
EXTENDS MCDivergedView

\* No member is passed over.
NoPass(n, x) == FALSE

NoPassTakeOver(n) == TakeOverBy(NoPass, n)

MutantNext == DNextBut \/ \E n \in Nodes : NoPassTakeOver(n)

MutantSpec ==
    /\ DInit /\ [][MutantNext]_divVars
    /\ DFairnessBut
    /\ \A n \in Nodes : WF_divVars(NoPassTakeOver(n))
=============================================================================
