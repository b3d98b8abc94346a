------------------------- MODULE GroundHandOverHeld -------------------------
(***************************************************************************)
(* Mutant of Ground: a Master that hands the view to a node it holds out.  *)
(* The ground excludes PN1, the Master, which resigns; PN2 takes over (C)  *)
(* and hands the view back to PN1 while it holds PN1 out: TLC must report  *)
(* NoHandOverHeldProp violated.                                            *)
(***************************************************************************)
EXTENDS MCGround

NoHold(m) == {}

HandOverAny(m, r) == HandOverBy(NoHold, m, r)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, GroundExclude, GroundExcludeSwitch,
                                        Readmit, HandOverAny)]_allVars
=============================================================================
