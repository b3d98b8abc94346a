------------------------------ MODULE MCGround ------------------------------
(***************************************************************************)
(* The models of Ground: PN1, PN2, PN3 in succession (ST1 the Storage     *)
(* node, outside Nodes), one task t1; MCGround.cfg no crash and two        *)
(* accepted ground commands (exclusions and readmissions), MCGroundOne.cfg *)
(* one, MCGroundRecovery.cfg one crash and one, MCGroundRecovery0.cfg one  *)
(* crash and none, MCGroundPN1.cfg and MCGroundPN3.cfg two about one node *)
(* (GroundAboutPN1, GroundAboutPN3: witness bases); recover at any time.   *)
(* The                                                                     *)
(* mission, phase P1 (A2 is of phase P2, only as a target a                *)
(* recover must refuse):                                                   *)
(*                                                                         *)
(*   config  master  observers   t1    edges (failure -> configuration)    *)
(*   A       PN1     PN2, PN3    PN3   PN1 -> C, PN2 -> S1, PN3 -> B        *)
(*   B       PN1     PN2         PN2   PN1 -> S2, PN2 -> S1                 *)
(*   C       PN2     PN3         PN3   PN2 -> E, PN3 -> S2                  *)
(*   E       PN3     -           PN3   PN3 -> S3                            *)
(*   R       PN1     PN3         PN3   PN1 -> S3, PN3 -> S1 (no edge to it:*)
(*                                     the ground's, PN2 failed)            *)
(*   A2 (P2) PN1     PN3         PN3   (never driven)                       *)
(*   S1, S2, S3: SAFE of P1 with PN1, PN2, PN3 Master (t1 on it); its      *)
(*   Master's failure leads to the next one's SAFE.                        *)
(*                                                                         *)
(* A failure of PN2 from A has no edge (prototype3's Storage node): SAFE,  *)
(* which only `recover R` leaves (A uses PN2; A2 is another phase; E is    *)
(* PN3's). RecoveryOf walks the failed set from A (Topology::              *)
(* recovery_target without on_recovery edges). An edge a node does not    *)
(* matter to keeps the configuration.                                      *)
(***************************************************************************)
EXTENDS Ground

CONSTANTS PN1, PN2, PN3, t1

MCPriority == <<PN1, PN2, PN3>>
MCConfigIds == {"A", "B", "C", "E", "R", "A2", "S1", "S2", "S3"}
MCSafeIds == {"S1", "S2", "S3"}
MCInitialConfig == "A"

MCMasterOf(c) ==
    CASE c \in {"A", "B", "R", "A2", "S1"} -> PN1
      [] c \in {"C", "S2"} -> PN2
      [] OTHER -> PN3

MCObserversOf(c) ==
    CASE c = "A" -> {PN2, PN3}
      [] c = "B" -> {PN2}
      [] c \in {"C", "R", "A2"} -> {PN3}
      [] OTHER -> {}

MCPhaseOf(c) == IF c = "A2" THEN "P2" ELSE "P1"

MCPlacement(c, t) ==
    CASE c = "B" -> PN2
      [] c \in MCSafeIds -> MCMasterOf(c)
      [] OTHER -> PN3

MCEdge(c, f) ==
    CASE c = "A" -> (IF f = PN1 THEN "C" ELSE IF f = PN2 THEN "S1" ELSE "B")
      [] c = "B" -> (IF f = PN1 THEN "S2" ELSE IF f = PN2 THEN "S1" ELSE "B")
      [] c = "C" -> (IF f = PN2 THEN "E" ELSE IF f = PN3 THEN "S2" ELSE "C")
      [] c = "E" -> (IF f = PN3 THEN "S3" ELSE "E")
      [] c = "R" -> (IF f = PN1 THEN "S3" ELSE IF f = PN3 THEN "S1" ELSE "R")
      [] c = "A2" -> (IF f = PN1 THEN "S2" ELSE IF f = PN3 THEN "S1" ELSE "A2")
      [] c = "S1" -> (IF f = PN1 THEN "S2" ELSE "S1")
      [] c = "S2" -> (IF f = PN2 THEN "S3" ELSE "S2")
      [] OTHER -> "S3"

MCOnFailure(c, f) == MCEdge(c, f)

MCOnPhase(c) == {}

MCRecoveryOf(c, r, F) == Walk(MCInitialConfig, InOrder(F))

(***************************************************************************)
(* Witnesses: invariants TLC must find violated (manifest "witnesses").     *)
(***************************************************************************)
\* GroundRecovery: a Master left SAFE for a configuration the ground named (R), and drives
\* it with PN2 failed.
WitnessGroundRecoveryInv ==
    ~\E m \in Nodes : IsMaster(m) /\ "recover" \in hist /\ masterConfig[m] = "R"
                      /\ PN2 \in failed[m] /\ masterStage[m] = "Idle"
\* RefuseGroundCommand: a Master in SAFE, between switches, refuses a recover naming a
\* configuration of its phase (one that uses a failed node, or another node's).
WitnessRefuseGroundCommandInv ==
    ~\E m \in Nodes : IsMaster(m) /\ masterConfig[m] \in SafeIds /\ masterStage[m] = "Idle"
                      /\ masterSeq[m] > 0 /\ RecoveryRefused(m, "A")
\* GroundExclude: a node the Master holds out is out on the ground's word, excluded and
\* heard (out): the Master would readmit it but for the ground.
WitnessGroundExcludeInv ==
    ~\E m, r \in Nodes : IsMaster(m) /\ masterStage[m] = "Idle" /\ r \in out
                         /\ r \in heldOut[m] /\ r \in failed[m]
                         /\ RecoveryOf(masterConfig[m], r, failed[m] \ {r}) \notin SafeIds
\* GroundExcludeSwitch: the Master excluded a node for the ground's hold (its trace line
\* `Exclude` with `ground`), and runs the configuration that excludes it.
WitnessGroundExcludeSwitchInv ==
    ~\E m, x \in Nodes : IsMaster(m) /\ masterStage[m] = "Idle" /\ "groundExcluded" \in hist
                         /\ x \in heldOut[m] /\ x \in failed[m] /\ x \notin broken
                         /\ masterConfig[m] \notin SafeIds
\* GroundExcludeSwitch refused: a running node the Master holds out stays not excluded,
\* the Master between switches, because its walk for it (its own edge, the nodes it holds
\* out and its Pending nodes) leads to SAFE.
WitnessHeldNotExcludedInv ==
    ~\E m, x \in Nodes : IsMaster(m) /\ masterSeq[m] > 0 /\ masterStage[m] = "Idle"
                         /\ masterConfig[m] \notin SafeIds
                         /\ x \in MasterHeld(m) /\ alive[x]
                         /\ ~MasterWalkOk(m, x)
\* GroundExclude refused: the Master's check refuses to exclude a node out of a
\* configuration that is not SAFE, the exclusions held already counted.
WitnessExcludeRefusedInv ==
    ~\E m, x \in Nodes : IsMaster(m) /\ masterConfig[m] \notin SafeIds /\ heldOut[m] # {}
                         /\ x \notin heldOut[m] \cup ViewFailed(m)
                         /\ Walk(config[m], <<x>>) \notin SafeIds
                         /\ ~ExcludeAccepted(m, x)
\* GroundReadmit: a node the ground excluded and let back was readmitted.
WitnessGroundReadmitInv == ~({"readmitOut", "readmitted"} \subseteq hist)
\* ... or handed the mastership back: the first Master, out on the ground's word and let
\* back by it, is handed the view and Master again.
WitnessHandedBackInv ==
    ~({"readmitOut", "handedOver"} \subseteq hist /\ IsMaster(PN1) /\ PN1 \notin heldOut[PN2]
      /\ "exclude" \in hist)
\* The constraints of MCGroundPN1.cfg and MCGroundPN3.cfg: the ground's commands hold out
\* or let back PN1 only (the first Master), or PN3 only (a Worker holding t1). Their
\* behaviours are some of MCGround's, so a witness they reach is reachable there, in a
\* fraction of its states: the CI bases of the witnesses that need two commands.
GroundAboutPN1 == \A n \in Nodes : heldOut[n] \subseteq {PN1}
GroundAboutPN3 == \A n \in Nodes : heldOut[n] \subseteq {PN3}
=============================================================================
