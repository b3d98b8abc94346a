--------------------------- MODULE DesignateAtOnce ---------------------------
(***************************************************************************)
(* Mutant of Designate: a later designation acted on at once, its wait     *)
(* ignored (rule 3 without `wait`). In the 2|2 cut the ground designates   *)
(* PN2, then PN3 (wait 2: PN2's span); PN2 admits the first, PN3 the       *)
(* second. After the tie grace PN1 resigns; PN2 takes over epoch 2         *)
(* (PN1 out on its own word, PN3 and PN4 on PN1's, PN2's and the ground's  *)
(* declarations) and runs on the vote, which PN2 never heard move; PN3,    *)
(* not waiting, takes over epoch 3 from PN1 and PN2 on its own, PN4's and  *)
(* the ground's declarations: two running Masters. TLC must report         *)
(* AtMostOneRunningMasterInv violated in MCDesignate (exit 12).            *)
(***************************************************************************)
EXTENDS MCDesignate

\* The vote without the wait: the latest designation the node admitted names it.
ForVoteAtOnce(x) ==
    LET s == admitted[x]
    IN s > 0 /\ desig[s].node = x /\ desig[s].age < desig[s].span

MutantSpec == Init /\ [][NextBy(GroundCount, ForVoteAtOnce, 1)]_vars
=============================================================================
