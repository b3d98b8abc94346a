---------------------- MODULE LeaseDeciderCountsDecided ----------------------
(***************************************************************************)
(* Mutant of Lease: a decider's lease counts the node it decides on. Once *)
(* one Observer is gone, the last Observer's only voter is the Master; if  *)
(* the Master crashes too, the Observer's lease lapses on the very silence *)
(* it must act on, and it never takes over: TLC must report               *)
(* CompletenessInv violated (exit 12).                                     *)
(***************************************************************************)
EXTENDS MCLease

MutantSpec == LInit /\ [][LNextBy(MissLimit, Quorum, 1, FALSE)]_allVars
=============================================================================
