------------------------- MODULE PauseKeepsRunning -------------------------
(***************************************************************************)
(* Mutant of Pause (keel-sim's pause-keeps-running): the ground's pause is *)
(* taken but the node runs the task on. TLC must report PausedIdleInv      *)
(* violated.                                                               *)
(***************************************************************************)
EXTENDS MCPause

MutantSpec == PInit /\ [][PNextBy(NotEssential, FALSE, UnlessPaused, TRUE)]_allVars
=============================================================================
