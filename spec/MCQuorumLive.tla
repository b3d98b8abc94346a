---------------------------- MODULE MCQuorumLive ----------------------------
(***************************************************************************)
(* Liveness of Quorum under a partition that heals: once the partition has *)
(* healed for good, exactly one node runs as a Master, for good            *)
(* (HealedOneMasterLiveness).                                              *)
(*                                                                         *)
(* The faults recur a bounded number of times, then stop: the environment  *)
(* cuts and heals the nodes at most MaxEnv times (Quorum's own bound), and *)
(* the property's premise is that the last change left them whole. The     *)
(* protocol is weakly fair where the property needs it: a node that hears  *)
(* a running Master of a newer view adopts it (Adopt), and a Master whose  *)
(* view every node it must reach has adopted completes its switch          *)
(* (Complete). No decision (a phase switch, an exclusion, a take-over) is  *)
(* made fair: after a heal no node declares another (a monitor holds a     *)
(* node failed exactly while it cannot hear it), so none is needed, and    *)
(* the property says that the views the cut left behind, whatever they     *)
(* are, come together under one running Master without one.                *)
(*                                                                         *)
(* The constants are MCQuorum's (the Earth-observation mission's           *)
(* processing nodes PN1..PN4, D1 and C1, a Worker ST1).                    *)
(***************************************************************************)
EXTENDS MCQuorum

\* Weak fairness of the protocol's adoptions and completions, under the rules given.
FairnessBy(NeededOp(_, _), GoesByOp(_, _, _), MustAdoptOp(_)) ==
    /\ \A n, m \in Nodes : WF_vars(Adopt(NeededOp, GoesByOp, n, m))
    /\ \A m \in Nodes : WF_vars(Complete(NeededOp, GoesByOp, MustAdoptOp, m))

LiveSpec == Spec /\ FairnessBy(Needed, JointViews, NotExcluded)

\* The nodes that run as a Master.
RunningMasters == {n \in Nodes : RunningMaster(n)}

\* Once the partition has healed for good, exactly one running Master, for good.
HealedOneMasterLiveness ==
    <>[](conn = {Nodes}) => <>[](Cardinality(RunningMasters) = 1)

\* Witness: after a heal, the Master is a node that took over during a cut (the cluster came
\* together under a Master other than the first), and every node goes by its view.
WitnessHealedTakeOverInv ==
    ~(/\ conn = {Nodes} /\ envChanges >= 2
      /\ \E m \in Nodes : RunningMaster(m) /\ m # Order[1] /\ \A n \in Nodes : view[n] = view[m])
=============================================================================
