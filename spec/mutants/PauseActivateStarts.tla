------------------------ MODULE PauseActivateStarts ------------------------
(***************************************************************************)
(* Mutant of Pause: a switch's activation starts the task on its new host  *)
(* although the host holds it paused (ConfigSwitch::activate without its   *)
(* check of paused_). t1, paused at PN1, moves there by a planned switch:  *)
(* TLC must report PausedIdleInv violated.                                 *)
(***************************************************************************)
EXTENDS MCPause

AlwaysStarts(n, t) == TRUE

MutantSpec == PInit /\ [][PNextBy(NotEssential, TRUE, AlwaysStarts, TRUE)]_allVars
=============================================================================
