-------------------------- MODULE SwitchAckBeforeFlush --------------------------
(***************************************************************************)
(* Mutant of ConfigSwitch: a node acks "Prepared" once its leaving tasks   *)
(* are stopped, without waiting for their final checkpoints to reach the   *)
(* Storage node. The new owner can then start from the checkpoint before   *)
(* the final one, which arrives afterwards: the task resumes from stale    *)
(* state. TLC must report ResumeLatestCheckpointInv violated (exit 12).    *)
(***************************************************************************)
EXTENDS MCConfigSwitch

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

MutantNext ==
    \/ \E m \in Nodes : BootSwitch(m)
    \/ \E m, f \in Nodes : Exclude(m, f)
    \/ \E m \in Nodes : BroadcastActivate(m)
    \/ \E m \in Nodes : CompleteSwitch(m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Deactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : FlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : HastyAck(n, k)
    \/ \E n \in Nodes, msg \in msgs : ReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Activate(n, t)
    \/ PlannedNext
    \/ EnvironmentNext

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
