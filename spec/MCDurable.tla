----------------------------- MODULE MCDurable -----------------------------
(***************************************************************************)
(* Model of Durable for CI (MCDurable.cfg): three versions, three epochs, *)
(* two power losses (of either node), and a disk that may fail once.       *)
(***************************************************************************)
EXTENDS Durable

\* Witness: the Storage node lost power after it told a version (and the version is
\* still what the cluster resumes from: ToldDurableInv is about this state).
WitnessToldThenLostInv == ~(told >= 1 /\ ~sUp /\ ~stopped)

\* Witness: a failed write stopped the Storage node (rule 3's fail-stop is reached).
WitnessFailStopInv == ~(stopped /\ made = MaxVersion)

\* Witness: the node restarted after it had spoken for a newer epoch than its first, and
\* runs again (SaidDurableInv is about this state).
WitnessRestartAfterSayingInv == ~(rebooted /\ nUp /\ said >= 2)
=============================================================================
