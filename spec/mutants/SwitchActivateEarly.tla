-------------------------- MODULE SwitchActivateEarly --------------------------
(***************************************************************************)
(* Mutant of ConfigSwitch: a switch that does not wait for deactivation.   *)
(* The Master broadcasts Activate as soon as it has sent the command,      *)
(* without the "Prepared" acks, and nodes activate on the command alone,   *)
(* so a task starts on its new node while its old node still runs it.      *)
(* TLC must report NoDoubleActivationInv violated (exit 12).               *)
(***************************************************************************)
EXTENDS MCConfigSwitch

EarlyBroadcastActivate(m) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Preparing"
    /\ masterStage' = [masterStage EXCEPT ![m] = "Activating"]
    /\ msgs' = msgs \cup {ActivateMsg(epoch[m], masterSeq[m], masterConfig[m])}
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, version,
                   stored, masterConfig, masterSeq, failed, acks, crashes, phaseChanges,
                   unbooted>>

EarlyReceiveActivate(n, msg) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.kind = "Activate"
    /\ stage[n] \in {"Deactivating", "Prepared"}
    /\ msg.epoch = epoch[n] /\ msg.seq = seq[n]
    /\ stage' = [stage EXCEPT ![n] = "Activating"]
    /\ UNCHANGED <<alive, role, epoch, seq, config, active, unflushed, version, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

MutantNext ==
    \/ \E m \in Nodes : BootSwitch(m)
    \/ \E m, f \in Nodes : Exclude(m, f)
    \/ \E m \in Nodes : EarlyBroadcastActivate(m)
    \/ \E m \in Nodes : CompleteSwitch(m)
    \/ \E n \in Nodes : BecomeMaster(n)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Deactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : FlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : Ack(n, k)
    \/ \E n \in Nodes, msg \in msgs : EarlyReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Activate(n, t)
    \/ PlannedNext
    \/ EnvironmentNext

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
