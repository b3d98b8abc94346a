------------------------- MODULE DurableSaveAfterSend -------------------------
(***************************************************************************)
(* Mutant of Durable, rule 1 (keel-sim's save-after-send): the node sends  *)
(* the messages of a step before its state is saved. A power loss between  *)
(* the two takes it back to an epoch below one it has spoken for: TLC must *)
(* report SaidDurableInv violated (exit 12).                               *)
(***************************************************************************)
EXTENDS MCDurable

MutantSpec == Init /\ [][NextBy(FALSE, FALSE, FALSE)]_vars
=============================================================================
