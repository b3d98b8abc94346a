------------------------- MODULE GroundReadmitPending -------------------------
(***************************************************************************)
(* Ground with the rule before, sent only while the cluster agrees on its  *)
(* view (the old spec's ViewAgreed), the readmit at any time: the node the *)
(* ground names resigns on its own check, which walks the nodes held out   *)
(* that the view has not excluded and then the node (no Pending nodes).    *)
(* TLC must report SafeOnlyByFailureInv violated.                          *)
(***************************************************************************)
EXTENDS MCGround

\* The ground sends an exclude only while every running node is in the view of a running
\* Master between switches.
ViewAgreed ==
    \E m \in Nodes :
        /\ IsMaster(m)
        /\ masterStage[m] = "Idle"
        /\ masterSeq[m] > 0
        /\ \A n \in Nodes : alive[n] => /\ epoch[n] = epoch[m] /\ seq[n] = masterSeq[m]
                                     /\ config[n] = masterConfig[m]

HeldAnd(n, x) == (heldOut[n] \ ViewFailed(n)) \cup {x}

AnyNode(x) == TRUE

OldRule(x) ==
    /\ ViewAgreed
    /\ GroundExcludeBy(LAMBDA n, y : ExcludeAcceptedBy(HeldAnd, n, y), AnyNode, x)

MutantSpec == GInit /\ [][GNextWith(GroundRecovery, OldRule, GroundExcludeSwitch, Readmit,
                                    HandOver)]_allVars
=============================================================================
