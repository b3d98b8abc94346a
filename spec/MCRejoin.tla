------------------------------ MODULE MCRejoin ------------------------------
(***************************************************************************)
(* Models of Rejoin for CI.                                                *)
(*                                                                         *)
(* MCRejoin: the paper's prototype (PN1 the Master, PN2 and PN3 the        *)
(* Observers, ST1 watched only). One node at a time crashes, restarts and *)
(* is readmitted, again and again (the Master too); any node may instead  *)
(* have omission faults that come and go (cut off, then heard again), and *)
(* be excluded and readmitted while alive.                                 *)
(*                                                                         *)
(* Reduction, as in MCLease: one sender's heartbeats on the wire at a time.*)
(***************************************************************************)
EXTENDS Rejoin, TLC

CONSTANTS S1, S2, S3, S4
MCSuccession3 == <<S1, S2, S3>>

MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* MCRejoinWorker: the omission faults are ST1's, a Worker watched by three monitors.
MCOmissiveWorker == omissive \subseteq {S4}

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses").
\* A node restarted.
WitnessRestartInv == rebooted = {}
\* A node was readmitted.
WitnessReadmitInv == rejoined = {}
\* A readmitted node runs again (its voters acknowledged it).
WitnessRejoinRunsInv == \A n \in rejoined : ~running[n]
\* The first Master, readmitted, is the Master again and runs.
WitnessMasterBackInv == ~(S1 \in rejoined /\ Master = S1 /\ running[S1])
=============================================================================
