----------------------- MODULE ResignedKeepsUnflushed -----------------------
(***************************************************************************)
(* Mutant of Resign: at its deadline a resigned Master says it left        *)
(* (`excluded` in its heartbeats) without abandoning the final checkpoints *)
(* still unacknowledged (advance_resign without abandon_flushes): its      *)
(* successor takes over while it still claims them: TLC must report        *)
(* ResignedLeftCleanInv violated (exit 12).                                *)
(***************************************************************************)
EXTENDS MCResign

MutantSpec == RInit /\ [][RNextBy(TRUE, FALSE, Acting)]_allVars
=============================================================================
