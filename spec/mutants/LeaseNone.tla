------------------------------ MODULE LeaseNone ------------------------------
(***************************************************************************)
(* Mutant of Lease: no lease (the rule before fault model 2): a node runs  *)
(* whatever its acknowledgements say, a Master never resigns. A node cut  *)
(* off from the monitors is excluded and keeps running: TLC must report   *)
(* NoExcludedRunsInv violated (exit 12).                                   *)
(***************************************************************************)
EXTENDS MCLease

\* A lease longer than any bound can grow: it never ends.
MutantSpec == LInit /\ [][LNextBy(MaxAge + 1, Quorum, 1, TRUE)]_allVars
=============================================================================
