----------------------------- MODULE MCExclusion -----------------------------
(***************************************************************************)
(* Models of Exclusion for CI.                                             *)
(*                                                                         *)
(* MCExclusion: the paper's prototype, PN1 the Master, PN2 and PN3 the     *)
(* Observers in that order, ST1 watched only; one node crashes (the Master *)
(* too: a take-over) or one has omission faults of any shape (it may lose *)
(* any heartbeat sent to it): a partly deaf or starved Observer declares   *)
(* healthy nodes, or the Master.                                           *)
(* MCExclusionDeaf: PN1 the Master, PN2 the only Observer, ST1 and IF1     *)
(* watched; one crash and one node deaf or stalled a period at a time:     *)
(* once the Observer crashed, the Master is the last monitor and a single  *)
(* declaration suffices, so only self-suspicion keeps a deaf or late       *)
(* Master from excluding everyone.                                         *)
(*                                                                         *)
(* Reduction, as in MCHeartbeat: sends, receipts and losses within a       *)
(* period commute; one sender's heartbeats on the wire at a time cover     *)
(* every reachable value of what the properties read.                      *)
(***************************************************************************)
EXTENDS Exclusion, TLC

\* The succession orders of the two models (a .cfg cannot write a sequence).
CONSTANTS S1, S2, S3
MCSuccession3 == <<S1, S2, S3>>
MCSuccession2 == <<S1, S2>>

MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses"), so the
\* properties above are not vacuous and the faults are really explored.
\* A node is excluded.
WitnessExclusionInv == excluded = {}
\* A declaration is withdrawn: a monitor held a node failed and then heard it (the
\* partly deaf monitor's false declarations are reached, and undone).
WitnessFalseDeclarationInv == ~\E m \in Monitors, n \in Nodes :
                                   n \in failed[m] /\ alive[n] /\ n \notin omissive
\* A deaf and a stalled period of the Master happen after the Observer crashed.
WitnessDeafMasterInv == ~(Master \in deaf /\ \E m \in Monitors \ {Master} : ~alive[m])
WitnessLateMasterInv == ~(Master \in late /\ \E m \in Monitors \ {Master} : ~alive[m])
\* The first Master is excluded: a successor took over.
WitnessTakeOverInv == Succession[1] \notin excluded
=============================================================================
