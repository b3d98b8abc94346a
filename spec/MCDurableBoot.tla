---------------------------- MODULE MCDurableBoot ----------------------------
(***************************************************************************)
(* Model of DurableBoot for CI (MCDurableBoot.cfg): MCDurable's, three     *)
(* versions, three epochs, two power losses (of either node), a disk that  *)
(* may fail once, with the Storage node's boot reading its disk back.      *)
(***************************************************************************)
EXTENDS DurableBoot

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses").
\* A boot recovers a version the Storage node had told the cluster it stored.
WitnessRecoveredToldInv == ~(sBoots >= 1 /\ toldAtBoot >= 1 /\ recovered >= toldAtBoot)
\* A boot recovers a version newer than any it had told: written, and the power lost
\* before what waited for it was released (the check is >=, not =).
WitnessRecoveredUntoldInv == ~(sBoots >= 1 /\ recovered > toldAtBoot)
=============================================================================
