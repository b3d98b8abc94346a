----------------------- MODULE PauseResumesAnywhere -----------------------
(***************************************************************************)
(* Mutant of Pause: a resume starts the task at every node that held it    *)
(* paused, placed there or not (ConfigSwitch::resume without its check of  *)
(* active_). TLC must report RunsPlacedInv violated.                       *)
(***************************************************************************)
EXTENDS MCPause

MutantSpec == PInit /\ [][PNextBy(NotEssential, TRUE, UnlessPaused, FALSE)]_allVars
=============================================================================
