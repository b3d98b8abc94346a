-------------------------- MODULE PauseEssential --------------------------
(***************************************************************************)
(* Mutant of Pause: the ground pauses an essential task (the check of      *)
(* NodeProtocol::ground_pause left out). TLC must report                   *)
(* EssentialNeverPausedInv violated.                                       *)
(***************************************************************************)
EXTENDS MCPause

AnyTask(t) == TRUE

MutantSpec == PInit /\ [][PNextBy(AnyTask, TRUE, UnlessPaused, TRUE)]_allVars
=============================================================================
