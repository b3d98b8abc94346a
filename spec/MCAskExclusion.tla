---------------------------- MODULE MCAskExclusion ----------------------------
(***************************************************************************)
(* Model of AskExclusion for CI (MCAskExclusion.cfg): MCLeaseWorker's      *)
(* cluster (PN1 the Master, PN2 and PN3 the Observers in that order, ST1 a *)
(* Worker watched by the three), where one node that is not the acting     *)
(* Master asks to be excluded, at any time; PN3 may have omission faults   *)
(* as a receiver (it misses heartbeats of any node: a partly deaf          *)
(* Observer whose reports are wrong).                                      *)
(*                                                                         *)
(* Reduction, as in MCLease: one sender's heartbeats on the wire at a time. *)
(***************************************************************************)
EXTENDS AskExclusion, TLC

CONSTANTS S1, S2, S3, S4
MCSuccession3 == <<S1, S2, S3>>

MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* The omission faults are PN3's; at most one node asks.
MCAskConstraint == omissive \subseteq {S3} /\ Cardinality(asked) <= 1

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses").
\* The Worker asked and is excluded on its word alone, alive and healthy (no monitor
\* declared it).
WitnessWorkerAskedInv ==
    ~\E n \in asked \ Monitors : n \in excluded /\ alive[n] /\ n \notin omissive
                                 /\ \A m \in Monitors : n \notin failed[m]
\* An Observer that asked, excluded on its word: the Master's voters shrink.
WitnessObserverAskedInv == ~\E n \in asked \cap Monitors : n \in excluded
=============================================================================
