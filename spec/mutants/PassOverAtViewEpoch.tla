------------------------- MODULE PassOverAtViewEpoch -------------------------
(***************************************************************************)
(* Mutant of PassOver: a member is passed over at the view's epoch too     *)
(* (its epoch at most the taker's, where the rule reads below it): one     *)
(* that follows the view, and takes over itself. PN1 hands PN3 epoch 3;    *)
(* PN2 and PN3, Observers of epoch 1, declare PN1 left (it follows epoch   *)
(* 3); PN3, behind PN2 in epoch 1's succession, passes it over and takes   *)
(* over from epoch 1, and PN2 takes over from epoch 1 as well: two Masters *)
(* of one view's succession, neither holding the other failed. TLC must    *)
(* report OneTakeOverPerViewInv violated in MCPassOver (exit 12).          *)
(***************************************************************************)
EXTENDS MCPassOver

\* PassOver's Behind with the epoch compared by <= instead of <.
NotAhead(n, x) ==
    /\ x \in ObserversOf(epoch[n])
    /\ x # Owner(epoch[n])
    /\ ~fenced[x]
    /\ epoch[x] >= 1
    /\ epoch[x] <= epoch[n]
    /\ alive[x]
    /\ x \notin suspects[n]
    /\ \A c \in msgs : c.epoch <= epoch[x]
    /\ NoHandOverTo(x)

AtViewEpochTakeOver(n) == TakeOverBy(NotAhead, n)

MutantNext == PNextBut \/ \E n \in Nodes : AtViewEpochTakeOver(n)

MutantSpec ==
    /\ PInit /\ [][MutantNext]_passVars
    /\ PFairnessBut
    /\ \A n \in Nodes : WF_passVars(AtViewEpochTakeOver(n))
=============================================================================
