----------------------------- MODULE LeaseOneAck -----------------------------
(***************************************************************************)
(* Mutant of Lease: one fresh acknowledgement keeps the lease (it ends     *)
(* only when every voter may hold the node failed). A Worker that one of   *)
(* its three monitors still hears is excluded on the other two's           *)
(* declarations and keeps running: TLC must report NoExcludedRunsInv       *)
(* violated (exit 12).                                                     *)
(***************************************************************************)
EXTENDS MCLease

AllOf(V) == IF V = {} THEN 1 ELSE Cardinality(V)

MutantSpec == LInit /\ [][LNextBy(MissLimit, AllOf, 1, TRUE)]_allVars
=============================================================================
