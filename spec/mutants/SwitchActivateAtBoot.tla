------------------------- MODULE SwitchActivateAtBoot -------------------------
(***************************************************************************)
(* Mutant of ConfigSwitch: a node activates the initial configuration's    *)
(* tasks by itself when it boots, without a command (the start-up before   *)
(* the boot switch). A node that boots late may have been declared failed  *)
(* already, and its tasks started elsewhere and run on: at boot it starts  *)
(* them again, from the initial state. TLC must report                     *)
(* NoDoubleActivationInv violated (exit 12).                               *)
(***************************************************************************)
EXTENDS MCConfigSwitch

\* The nodes booted at Init run their initial tasks at once.
SelfStartInit ==
    /\ unbooted \in {B \in SUBSET (Nodes \ {Priority[1]}) :
                        Cardinality(B) <= MaxLateBoots}
    /\ alive = [n \in Nodes |-> n \notin unbooted]
    /\ role = [n \in Nodes |-> IF n = Priority[1] THEN "Master"
                               ELSE IF n \in ProcessingNodes THEN "Observer"
                               ELSE "Worker"]
    /\ epoch = [n \in Nodes |-> 1]
    /\ seq = [n \in Nodes |-> 0]
    /\ config = [n \in Nodes |-> InitialConfig]
    /\ stage = [n \in Nodes |-> "Stable"]
    /\ active = [n \in Nodes |-> IF n \in unbooted THEN {} ELSE TasksOn(InitialConfig, n)]
    /\ unflushed = [n \in Nodes |-> {}]
    /\ version = [n \in Nodes |-> [t \in Tasks |-> 0]]
    /\ stored = [t \in Tasks |-> 0]
    /\ masterStage = [n \in Nodes |-> "Idle"]
    /\ masterConfig = [n \in Nodes |-> InitialConfig]
    /\ masterSeq = [n \in Nodes |-> 0]
    /\ failed = [n \in Nodes |-> {}]
    /\ msgs = {}
    /\ acks = {}
    /\ crashes = 0
    /\ phaseChanges = 0

\* A late node starts the initial configuration's tasks at version 0 when it boots.
SelfStartBoot(n) ==
    /\ n \in unbooted
    /\ unbooted' = unbooted \ {n}
    /\ alive' = [alive EXCEPT ![n] = TRUE]
    /\ active' = [active EXCEPT ![n] = TasksOn(InitialConfig, n)]
    /\ version' = [version EXCEPT ![n] = [t \in Tasks |-> 0]]
    /\ UNCHANGED <<role, epoch, seq, config, stage, unflushed, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes, phaseChanges>>

MutantNext ==
    \/ ProtocolNext
    \/ PlannedNext
    \/ \E n \in Nodes, t \in Tasks : Execute(n, t)
    \/ \E n \in Nodes : Crash(n)
    \/ \E n \in Nodes : SelfStartBoot(n)

MutantSpec == SelfStartInit /\ [][MutantNext]_vars
=============================================================================
