------------------------- MODULE HandoffAckBeforeFlush -------------------------
(***************************************************************************)
(* Mutant of Handoff: a node acks "Prepared" once its leaving tasks are    *)
(* stopped, without waiting for their final checkpoints to reach the       *)
(* Storage node its view includes (ConfigSwitch's SwitchAckBeforeFlush).   *)
(* While the Storage node is paused a host's checkpoints are lost; when it *)
(* runs again the new host starts from the one before, and the final       *)
(* checkpoint arrives afterwards: TLC must report                          *)
(* HResumeLatestCheckpointInv violated (exit 12).                          *)
(***************************************************************************)
EXTENDS MCHandoff

HastyAck(n, kind) ==
    /\ alive[n]
    /\ IF kind = "Prepared"
       THEN /\ stage[n] = "Deactivating"
            /\ \A t \in active[n] : Placement(config[n], t) = n
       ELSE ReadyToAck(n, kind)
    /\ stage' = [stage EXCEPT ![n] = IF kind = "Prepared" THEN "Prepared" ELSE "Stable"]
    /\ acks' = acks \cup {AckMsg(kind, epoch[n], seq[n], n)}
    /\ UNCHANGED <<alive, role, epoch, seq, config, active, unflushed, version, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, crashes,
                   phaseChanges, unbooted>>
    /\ UNCHANGED <<placedBefore, hostLost, handoffState>>

MutantNext ==
    \/ \E m \in Nodes : HBootSwitch(m)
    \/ \E m, f \in Nodes : HExclude(m, f)
    \/ \E m \in Nodes : DeclareStorageFailed(m)
    \/ \E m \in Nodes : ReadmitStorage(m)
    \/ \E m \in Nodes : HBroadcastActivate(m)
    \/ \E m \in Nodes : HCompleteSwitch(m)
    \/ \E n \in Nodes : HBecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : HReceiveCommand(n, msg)
    \/ \E n \in Nodes, t \in Tasks : HDeactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : HFlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : HastyAck(n, k)
    \/ \E n \in Nodes, msg \in msgs : HReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : HActivate(n, t)
    \/ HPlannedNext
    \/ HEnvironmentNext

MutantSpec == HInit /\ [][MutantNext]_everything
=============================================================================
