------------------------- MODULE GroundRecoveryUsesFailed -------------------------
(***************************************************************************)
(* Mutant of Ground: a recover that does not check the failed set. PN2     *)
(* crashes, PN1 enters SAFE (S1) and switches to A, whose observer PN2 is  *)
(* failed: TLC must report ValidUnderFailedInv violated.                   *)
(***************************************************************************)
EXTENDS MCGround

UsesFailed(m, c) ==
    /\ IsMaster(m) /\ masterStage[m] = "Idle" /\ masterSeq[m] > 0
    /\ masterConfig[m] \in SafeIds
    /\ c \in ConfigIds \ SafeIds
    /\ PhaseOf(c) = PhaseOf(masterConfig[m])
    /\ MasterOf(c) = m
    /\ GStart(m, c, failed[m])
    /\ hist' = hist \cup {"recover"}
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted, heldOut, out, broken, declared, phase,
                   grounds>>

MutantSpec == GInit /\ [][GNextWith(UsesFailed, GroundExclude, GroundExcludeSwitch, Readmit,
                                        HandOver)]_allVars
=============================================================================
