---------------------------- MODULE MCExclusionBig ----------------------------
(***************************************************************************)
(* Bench models of Exclusion beyond CI's bounds (docs/verification.md,    *)
(* "Bigger models"): MissLimit 3, loss on healthy links (MaxLoss > 0), four *)
(* and five monitors, two faults. The Master is S1, the Observers follow   *)
(* in succession order; the nodes beyond the monitors are watched only.    *)
(*                                                                         *)
(* Reduction, as in MCExclusion: one sender's heartbeats on the wire at a  *)
(* time (MCOneSenderAtATime), for the exhaustive models. The models run in *)
(* TLC's simulation mode leave it out: a random trace ends at the first    *)
(* step the action constraint refuses, so there it would only shorten the *)
(* traces, and every interleaving is a behaviour of the spec anyway.       *)
(***************************************************************************)
EXTENDS Exclusion, TLC

\* The succession orders (a .cfg cannot write a sequence).
CONSTANTS S1, S2, S3, S4, S5
MCSuccession3 == <<S1, S2, S3>>
MCSuccession4 == <<S1, S2, S3, S4>>
MCSuccession5 == <<S1, S2, S3, S4, S5>>

MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* Two crashes apart, as MCLease's MCCrashesApart: a crash only once every other crashed
\* node is excluded (sequential failures, as a decision graph tolerates them).
\* CompletenessInv's bound is for one failure at a time: with two crashes together, the
\* Master's among them, the other waits for the take-over (TLC, MissLimit 2: a crashed node
\* not yet excluded 6 periods after its crash, ExcludeBound being 5).
MCCrashesApart == Cardinality({n \in Nodes : ~alive[n] /\ n \notin excluded}) <= 1
=============================================================================
