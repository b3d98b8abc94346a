---------------------------- MODULE MCGroundWalk ----------------------------
(***************************************************************************)
(* A model of Ground in which the Master's walk matters (MCGroundWalk.cfg):*)
(* PN1, PN2, PN3 in succession (ST1 the Storage node, outside Nodes), one  *)
(* task t1, one crash (of PN2) and one accepted ground command; every      *)
(* failure comes before the ground's exclusions and is known to the node   *)
(* deciding each (MCWalkConstraint), so SafeByFailuresInv must hold. The   *)
(* mission, phase P1:                                                      *)
(*                                                                         *)
(*   config  master  observers   t1    edges (failure -> configuration)    *)
(*   A       PN1     PN2, PN3    PN3   PN1 -> C, PN2 -> D, PN3 -> B        *)
(*   B       PN1     PN2         PN2   PN1 -> S2, PN2 -> S1                *)
(*   C       PN2     PN3         PN3   PN2 -> S3, PN3 -> S2                *)
(*   D       PN1     PN3         PN3   PN1 -> S3, PN3 -> S1                *)
(*   S1, S2, S3: SAFE of P1 with PN1, PN2, PN3 Master (t1 on it); its      *)
(*   Master's failure leads to the next one's SAFE.                        *)
(*                                                                         *)
(* No single failure reaches SAFE; PN2 with PN3, or with PN1, does. The    *)
(* ground's hold of PN3 is safe alone (A to B), but not with a crash of    *)
(* PN2 under way (B to S1, where PN2 alone leads to D); its exclusion of   *)
(* PN1, the Master, neither (A to C to S3): the walks refuse them, and     *)
(* without them the cluster enters SAFE (mutants GroundExcludeNoWalk,      *)
(* GroundExcludeNoPending, GroundResignNoPending). An edge a node does not *)
(* matter to keeps the configuration.                                      *)
(***************************************************************************)
EXTENDS Ground

CONSTANTS PN1, PN2, PN3, t1

MCPriority == <<PN1, PN2, PN3>>
MCConfigIds == {"A", "B", "C", "D", "S1", "S2", "S3"}
MCSafeIds == {"S1", "S2", "S3"}
MCInitialConfig == "A"

MCMasterOf(c) ==
    CASE c \in {"A", "B", "D", "S1"} -> PN1
      [] c \in {"C", "S2"} -> PN2
      [] OTHER -> PN3

MCObserversOf(c) ==
    CASE c = "A" -> {PN2, PN3}
      [] c = "B" -> {PN2}
      [] c \in {"C", "D"} -> {PN3}
      [] OTHER -> {}

MCPhaseOf(c) == "P1"

MCPlacement(c, t) ==
    CASE c = "B" -> PN2
      [] c \in MCSafeIds -> MCMasterOf(c)
      [] OTHER -> PN3

MCEdge(c, f) ==
    CASE c = "A" -> (IF f = PN1 THEN "C" ELSE IF f = PN2 THEN "D" ELSE "B")
      [] c = "B" -> (IF f = PN1 THEN "S2" ELSE IF f = PN2 THEN "S1" ELSE "B")
      [] c = "C" -> (IF f = PN2 THEN "S3" ELSE IF f = PN3 THEN "S2" ELSE "C")
      [] c = "D" -> (IF f = PN1 THEN "S3" ELSE IF f = PN3 THEN "S1" ELSE "D")
      [] c = "S1" -> (IF f = PN1 THEN "S2" ELSE "S1")
      [] c = "S2" -> (IF f = PN2 THEN "S3" ELSE "S2")
      [] OTHER -> "S3"

MCOnFailure(c, f) == MCEdge(c, f)

MCOnPhase(c) == {}

MCRecoveryOf(c, r, F) == Walk(MCInitialConfig, InOrder(F))

\* The steps that decide a ground exclusion: Master m excludes a node it holds out that its
\* monitor has not declared (GroundExcludeSwitch), or the acting Master x steps down on the
\* ground's exclude (it stops, not crashed).
GroundDecision(m) ==
    \/ IsMaster(m) /\ (failed'[m] \ failed[m]) \cap (MasterHeld(m) \ declared[m]) # {}
    \/ IsMaster(m) /\ alive[m] /\ ~alive'[m] /\ m \notin broken'

\* Every failure before the ground's exclusions, and known to the node deciding each: a
\* crash (of PN2, the one the walks must count) only before the first exclusion decided
\* for the ground (a Master's or a resignation), and each decision by a node whose monitor
\* declared, or whose view excludes, every crashed node.
MCWalkConstraint ==
    /\ broken' # broken => /\ {"groundExcluded", "resigned"} \cap hist = {}
                           /\ broken' \subseteq {PN2}
    /\ \A m \in Nodes :
           GroundDecision(m) => broken \subseteq declared[m] \cup failed[m] \cup ViewFailed(m)

\* Witness: the Master holds out a node it has not excluded, because its walk with the
\* crash its monitor declared leads to SAFE, while the node's own edge would not:
\* GroundExcludeSwitch is refused by the walk.
WitnessWalkRefusedInv ==
    ~\E m, x \in Nodes : IsMaster(m) /\ masterSeq[m] > 0 /\ masterStage[m] = "Idle"
                         /\ x \in MasterHeld(m) /\ broken # {}
                         /\ OnFailure(masterConfig[m], x) \notin SafeIds
                         /\ ~MasterWalkOk(m, x)
=============================================================================
