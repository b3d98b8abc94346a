------------------------- MODULE GroundReadmitHeld -------------------------
(***************************************************************************)
(* Mutant of Ground: a Master that readmits a node it holds out. The       *)
(* ground excludes PN3, which PN1, the Master, holds out and excludes by   *)
(* a switch of its own (B); PN1 then readmits it while it holds it out:   *)
(* TLC must report NoReadmitHeldProp violated.                            *)
(***************************************************************************)
EXTENDS MCGround

NoHold(m) == {}

ReadmitAny(m, r) == ReadmitBy(NoHold, m, r)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, GroundExclude, GroundExcludeSwitch,
                                        ReadmitAny, HandOver)]_allVars
=============================================================================
