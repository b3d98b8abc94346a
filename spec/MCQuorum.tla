------------------------------ MODULE MCQuorum ------------------------------
(***************************************************************************)
(* Models of Quorum for CI.                                                *)
(*                                                                         *)
(* MCQuorum: the Earth-observation mission's processing nodes, PN1 the     *)
(* Master, then PN2, PN3, PN4 in succession, and one Worker, ST1 (for the  *)
(* nodes that are never monitors: Storage, interface); two monitor sets,   *)
(* D1's {PN1, PN2, PN3, PN4} (the initial view) and C1's {PN1, PN2, PN3};  *)
(* any partition of the five nodes, changed twice (a cut, then a heal or   *)
(* another cut); four switches. keel-sim's run needs three switches and    *)
(* one cut (mutant QuorumBeforeFix), rule 3a's counterexample as many,     *)
(* rule 3b's four and two.                                                 *)
(*                                                                         *)
(* MCQuorum5: five monitors PN1..PN5, monitor sets {PN1, .., PN5} (the     *)
(* initial view, Needed 3) and {PN1, PN2, PN3} (Needed 2); the partition   *)
(* changed twice, three switches. Rule 4 needs five monitors: a Master     *)
(* that excluded one of four leaves it out of its lease in the pending     *)
(* view, where the three left need two stale voters, and a take-over there *)
(* needs three of four declarations, two of them from those three; of      *)
(* five, four are left and need three, but a take-over's three of five     *)
(* include only two of them.                                               *)
(***************************************************************************)
EXTENDS Quorum, TLC

\* The nodes in succession order, and the monitor sets (a .cfg cannot write a sequence).
CONSTANTS S1, S2, S3, S4, S5
MCOrder == <<S1, S2, S3, S4, S5>>
MCMonitorSetsD1C1 == {{S1, S2, S3, S4}, {S1, S2, S3}}
MCInitMonsD1 == {S1, S2, S3, S4}
MCMonitorSets5 == {{S1, S2, S3, S4, S5}, {S1, S2, S3}}
MCInitMons5 == {S1, S2, S3, S4, S5}

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses"), so the
\* state the properties guard is reached.
\* A node other than the first Master runs as Master: a take-over.
WitnessTakeOverInv == \A n \in Nodes : RunningMaster(n) => n = Order[1]
\* A running Master has excluded a node while a phase switch to another monitor set is
\* pending: an exclusion decided on joint evidence.
WitnessExcludeDuringSwitchInv ==
    ~\E m \in Nodes :
        /\ RunningMaster(m)
        /\ \E P \in pending[m] : P.mons # view[m].mons /\ P.failed # view[m].failed
\* The Master runs on through a phase switch cut by a partition: a member of the view it
\* left, which it cannot hear, has not adopted its view (where keel-sim's run starts; the
\* majority side makes progress).
WitnessSwitchCutInv ==
    ~\E m \in Nodes :
        /\ RunningMaster(m)
        /\ \E P \in pending[m] :
              /\ P.mons # view[m].mons
              /\ \E n \in Members(P) : ~Hears(m, n) /\ view[n] # view[m]
\* A Master cut off in a minority has stopped while another runs.
WitnessMinorityMasterStopsInv ==
    ~\E a, b \in Nodes : a # b /\ IsMaster(a) /\ ~running[a] /\ RunningMaster(b)
\* A node that is not the Master holds its lease in its own view but has stopped by a joint
\* view (rule 3b is not vacuous).
WitnessJointLeaseStopsInv ==
    ~\E x \in Nodes :
        /\ ~IsMaster(x) /\ x \notin view[x].failed
        /\ HoldsIn(Needed, view[x], x, {})
        /\ ~running[x]
\* A Master alone in its view runs: the last monitor of a view took over (a decider's lease
\* without the nodes it decides on), as in Lease's WitnessLastTakeOverInv.
WitnessLastMonitorInv ==
    ~\E n \in Nodes : RunningMaster(n) /\ n # Order[1] /\ Members(view[n]) = {n}
=============================================================================
