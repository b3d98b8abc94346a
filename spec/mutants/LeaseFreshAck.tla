---------------------------- MODULE LeaseFreshAck ----------------------------
(***************************************************************************)
(* Mutant of Lease: a node takes a monitor's acknowledgement as the        *)
(* monitor's count now, forgetting the period it spent on the way (in the *)
(* runtime: measuring the lease from the acknowledgement's arrival, not    *)
(* from the send time of the heartbeat it acknowledges). The monitor may   *)
(* have counted one more miss meanwhile, and the node runs one period too  *)
(* long: TLC must report NoExcludedRunsInv violated (exit 12).             *)
(***************************************************************************)
EXTENDS MCLease

MutantSpec == LInit /\ [][LNextBy(MissLimit, Quorum, 0, TRUE)]_allVars
=============================================================================
