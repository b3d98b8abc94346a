------------------------ MODULE QuorumFollowerOwnView ------------------------
(***************************************************************************)
(* Mutant of Quorum: only the Master goes by joint views; any other node's *)
(* lease is judged by its own view (without rule 3b). Five monitors: PN1   *)
(* switches to {PN1, PN2, PN3}, only PN2 adopts it, and the partition      *)
(* {PN1, PN2} | {PN3, PN4, PN5} follows; PN3 takes over from PN1 and PN2   *)
(* on three of the five, and PN2, whose lease in the new set needs two of  *)
(* PN1 and PN3 stale, keeps running: TLC must report NoExcludedRunsInv     *)
(* violated (exit 12).                                                     *)
(***************************************************************************)
EXTENDS MCQuorum

MasterOnly(master, P, V) == IF master THEN P ELSE {}

MutantSpec ==
    Init /\ [][NextBy(Needed, MemberVoters, MasterOnly, InheritedViews, NotExcluded)]_vars
=============================================================================
