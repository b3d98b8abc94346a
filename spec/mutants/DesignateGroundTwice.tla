------------------------- MODULE DesignateGroundTwice -------------------------
(***************************************************************************)
(* Mutant of Designate: the ground's vote counted twice, as the            *)
(* tie-breaking member and again in place of a missing monitor: a designee *)
(* counts it as two declarations, and in its lease as an acknowledgement   *)
(* that cancels a stale voter. In the 1|3 cut {PN1, PN2, PN4} | {PN3} the  *)
(* ground designates PN3, alone: its own declaration and the vote make     *)
(* three of PN1, PN2 and PN4, its lease holds (three stale voters less     *)
(* one), and it takes over epoch 3 while PN1, the Master of the majority   *)
(* side and in no tie, runs on. TLC must report AtMostOneRunningMasterInv  *)
(* violated in MCDesignate with StartConns the 1|3 cut (exit 12).          *)
(***************************************************************************)
EXTENDS MCDesignate

\* The vote for x cancels a stale voter besides counting with x.
GroundCountTwice(x, for) == IF for THEN -1 ELSE IF tieAge[x] >= TieGrace THEN 1 ELSE 0

MutantSpec == Init /\ [][NextBy(GroundCountTwice, ForVote, 2)]_vars
=============================================================================
