------------------------- MODULE GroundRecoveryAnyMaster -------------------------
(***************************************************************************)
(* Mutant of Ground: a recover that does not check the master. PN2         *)
(* crashes, PN1 enters SAFE (S1) and switches to E, whose master is PN3:   *)
(* TLC must report DrivesOwnConfigInv violated.                            *)
(***************************************************************************)
EXTENDS MCGround

AnyMaster(m, c) ==
    /\ IsMaster(m) /\ masterStage[m] = "Idle" /\ masterSeq[m] > 0
    /\ masterConfig[m] \in SafeIds
    /\ c \in ConfigIds \ SafeIds
    /\ PhaseOf(c) = PhaseOf(masterConfig[m])
    /\ \A x \in ObserversOf(c) : x \notin failed[m]
    /\ \A t \in Tasks : Placement(c, t) \notin failed[m]
    /\ GStart(m, c, failed[m])
    /\ hist' = hist \cup {"recover"}
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted, heldOut, out, broken, declared, phase,
                   grounds>>

MutantSpec == GInit /\ [][GNextWith(AnyMaster, GroundExclude, GroundExcludeSwitch, Readmit,
                                        HandOver)]_allVars
=============================================================================
