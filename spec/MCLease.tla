------------------------------- MODULE MCLease -------------------------------
(***************************************************************************)
(* Models of Lease for CI.                                                 *)
(*                                                                         *)
(* MCLease: the paper's prototype, PN1 the Master, PN2 and PN3 the         *)
(* Observers in that order, ST1 watched only; one node crashes or one has *)
(* omission faults of any shape, in both directions: cut off from any of   *)
(* the others (a partition of one, healing and failing again), mute, deaf *)
(* or starved. The omissive node may be excluded; it must have stopped.    *)
(*                                                                         *)
(* Reduction, as in MCExclusion: one sender's heartbeats (and their        *)
(* acknowledgements) on the wire at a time.                                *)
(***************************************************************************)
EXTENDS Lease, TLC

CONSTANTS S1, S2, S3, S4
MCSuccession3 == <<S1, S2, S3>>

MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* MCLeaseWorker: the omission faults are ST1's, a Worker watched by three monitors.
MCOmissiveWorker == omissive \subseteq {S4}

\* MCLeaseFirst: MCLease's runs whose omission fault is the first Master's (a state
\* constraint: its behaviours are MCLease's, so what it reaches MCLease reaches), the base
\* of the witnesses and mutants that need no other faulty node.
MCOmissiveFirst == omissive \subseteq {S1}

\* MCLeaseCrashes: two crashes, one after the other was excluded (sequential failures,
\* as a decision graph tolerates them): the last two monitors, then the last one.
MCCrashesApart == Cardinality({n \in Nodes : ~alive[n] /\ n \notin excluded}) <= 1

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses").
\* A node that is alive lost its lease (it stopped).
WitnessLapseInv == \A x \in Nodes : alive[x] => x \in resigned \/ HoldsLease(x)
\* A Master resigned on its lapsed lease.
WitnessResignInv == resigned = {}
\* An excluded node is alive (the property's premise is reached).
WitnessExcludedAliveInv == \A n \in excluded : ~alive[n]
\* The first Master is excluded while alive: a take-over from a live Master.
WitnessLiveTakeOverInv == ~(Succession[1] \in excluded /\ alive[Succession[1]])
\* The last two monitors: one Observer excluded, then the Master, by the other Observer.
WitnessLastTakeOverInv == ~(Succession[1] \in excluded /\ Succession[3] \in excluded)
=============================================================================
