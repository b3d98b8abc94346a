--------------------------- MODULE PassOverInFlight ---------------------------
(***************************************************************************)
(* Mutant of PassOver: the pass-over does not wait for a Command on its    *)
(* way to the member behind (the spec's stand-in for the runtime's wait:   *)
(* a Command arrives within a third of a period, and a member is passed    *)
(* over only miss_limit periods after the view's Master went silent, and 2 *)
(* miss_limit more). PN1 crashes, PN2 takes over epoch 2 and crashes while *)
(* its Command is still on its way to PN3; PN4 passes PN3 over and takes   *)
(* over from epoch 2; PN3 then takes the Command, follows epoch 2, an      *)
(* Observer ahead of PN4, and takes over from epoch 2 as well: two Masters *)
(* of one view's succession, neither holding the other failed. TLC must    *)
(* report OneTakeOverPerViewInv violated in MCPassOverCrashes (exit 12).   *)
(***************************************************************************)
EXTENDS MCPassOver

\* PassOver's Behind without its last two conjuncts (nothing on its way to the member).
BehindNow(n, x) ==
    /\ x \in ObserversOf(epoch[n])
    /\ x # Owner(epoch[n])
    /\ ~fenced[x]
    /\ epoch[x] >= 1
    /\ epoch[x] < epoch[n]
    /\ alive[x]
    /\ x \notin suspects[n]

InFlightTakeOver(n) == TakeOverBy(BehindNow, n)

MutantNext == PNextBut \/ \E n \in Nodes : InFlightTakeOver(n)

MutantSpec ==
    /\ PInit /\ [][MutantNext]_passVars
    /\ PFairnessBut
    /\ \A n \in Nodes : WF_passVars(InFlightTakeOver(n))
=============================================================================
