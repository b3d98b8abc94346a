------------------------------ MODULE MCLeaseBig ------------------------------
(***************************************************************************)
(* Bench models of Lease beyond CI's bounds (docs/verification.md,        *)
(* "Bigger models"): MissLimit 3, loss on healthy links (MaxLoss > 0, on   *)
(* heartbeats and on the acknowledgements they carry), four and five       *)
(* monitors, two faults. The Master is S1, the Observers follow in         *)
(* succession order; the nodes beyond the monitors are Workers.            *)
(*                                                                         *)
(* Reduction, as in MCLease: one sender's heartbeats on the wire at a time *)
(* (MCOneSenderAtATime), for the exhaustive models; the models run in      *)
(* TLC's simulation mode leave it out (see MCExclusionBig).                *)
(***************************************************************************)
EXTENDS Lease, TLC

CONSTANTS S1, S2, S3, S4, S5
MCSuccession3 == <<S1, S2, S3>>
MCSuccession4 == <<S1, S2, S3, S4>>
MCSuccession5 == <<S1, S2, S3, S4, S5>>

MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* Two faults apart, as MCLease's MCCrashesApart: a crash only once every other crashed
\* node is excluded (sequential failures, as a decision graph tolerates them).
MCCrashesApart == Cardinality({n \in Nodes : ~alive[n] /\ n \notin excluded}) <= 1
=============================================================================
