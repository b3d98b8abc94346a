------------------------ MODULE DesignateAdmittedOnly ------------------------
(***************************************************************************)
(* Mutant of Designate, the natural design: no standing acknowledgement;   *)
(* a node counts the ground's vote against itself only once it admitted a  *)
(* designation of another node (rule 2 replaced), so a node the command    *)
(* never reached runs on in the tie for ever. The ground designates PN3;   *)
(* only PN3 admits it; after the tie grace PN3 takes over epoch 3 from     *)
(* PN1 on its own and PN4's declarations and the ground's vote, while PN1, *)
(* never reached, holds its lease (two stale voters of three) and runs as  *)
(* the Master of epoch 1. TLC must report AtMostOneRunningMasterInv        *)
(* violated in MCDesignate (exit 12).                                      *)
(***************************************************************************)
EXTENDS MCDesignate

\* The ground counts against x only once x admitted a designation naming another node.
AdmittedAgainst(x, for) ==
    IF for THEN 0
    ELSE IF admitted[x] > 0 /\ desig[admitted[x]].node # x THEN 1 ELSE 0

MutantSpec == Init /\ [][NextBy(AdmittedAgainst, ForVote, 1)]_vars
=============================================================================
