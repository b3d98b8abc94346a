------------------------- MODULE GroundRecoveryAnyPhase -------------------------
(***************************************************************************)
(* Mutant of Ground: a recover that does not check the phase. PN2 crashes, *)
(* PN1 enters SAFE (S1) and leaves it for A2, a configuration of phase P2  *)
(* that uses no failed node: TLC must report PhaseKeptInv violated.        *)
(***************************************************************************)
EXTENDS MCGround

AnyPhase(m, c) ==
    /\ IsMaster(m) /\ masterStage[m] = "Idle" /\ masterSeq[m] > 0
    /\ masterConfig[m] \in SafeIds
    /\ c \in ConfigIds \ SafeIds
    /\ MasterOf(c) = m
    /\ \A x \in ObserversOf(c) : x \notin failed[m]
    /\ \A t \in Tasks : Placement(c, t) \notin failed[m]
    /\ GStart(m, c, failed[m])
    /\ hist' = hist \cup {"recover"}
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted, heldOut, out, broken, declared, phase,
                   grounds>>

MutantSpec == GInit /\ [][GNextWith(AnyPhase, GroundExclude, GroundExcludeSwitch, Readmit,
                                        HandOver)]_allVars
=============================================================================
