------------------------- MODULE DurableReleaseEarly -------------------------
(***************************************************************************)
(* Mutant of Durable, rule 2 (keel-sim's release-held-early): the Storage  *)
(* node tells the cluster a version is stored as it receives it, before    *)
(* the write is on its disk. A power loss before the write loses a version *)
(* the cluster was told is stored: TLC must report ToldDurableInv violated *)
(* (exit 12).                                                              *)
(***************************************************************************)
EXTENDS MCDurable

MutantSpec == Init /\ [][NextBy(TRUE, FALSE, TRUE)]_vars
=============================================================================
