----------------------- MODULE DurableIgnoreFailedWrite -----------------------
(***************************************************************************)
(* Mutant of Durable, rule 3 (keel-sim's ignore-failed-write): a write     *)
(* that failed is taken for a written one: what waited for it is told and  *)
(* the Storage node flies on. The version told is on no disk: TLC must     *)
(* report ToldDurableInv violated (exit 12).                               *)
(***************************************************************************)
EXTENDS MCDurable

MutantSpec == Init /\ [][NextBy(FALSE, TRUE, TRUE)]_vars
=============================================================================
