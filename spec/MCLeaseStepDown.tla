--------------------------- MODULE MCLeaseStepDown ---------------------------
(***************************************************************************)
(* Model of LeaseStepDown for CI: MCLease's cluster (PN1 the Master, PN2  *)
(* and PN3 the Observers; one node cut off, mute, deaf or starved), with  *)
(* the Master's early step-downs.                                          *)
(***************************************************************************)
EXTENDS LeaseStepDown, TLC

CONSTANTS S1, S2, S3, S4
MCSuccession3 == <<S1, S2, S3>>

MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* The omission faults are the Master's, as a receiver: cut off from any of the others,
\* deaf or starved (the cfg has MuteToo = FALSE: a Master that cannot send still hears
\* everyone, is never cut off, and stops by its lease, MCLease). A healthy Master must
\* never step down (NoFalseExclusionInv).
MCOmissiveMaster == omissive \subseteq {S1}

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses").
\* A cut-off Master stepped down while it still held its lease: the early rule acts first.
WitnessCutOffStepDownInv == \A r \in stepDowns : r[2] = "cut off" => ~HoldsLease(r[1])
\* A stalled Master stepped down, and its successor took over.
WitnessStalledStepDownInv == \A r \in stepDowns : r[2] = "stalled" => r[1] \notin excluded
=============================================================================
