------------------------------ MODULE MCResign ------------------------------
(***************************************************************************)
(* Model of Resign for CI (MCResign.cfg): MCConfigSwitch's cluster (PN1    *)
(* the Master, PN2 and PN3 the Observers, two checkpointed tasks that a    *)
(* planned phase change swaps crosswise, each executing one step), where   *)
(* the acting Master may resign at any point of any switch and its        *)
(* successor takes over once it is done; a crash besides (the resigning    *)
(* Master's while it flushes, or another node's).                          *)
(***************************************************************************)
EXTENDS MCConfigSwitch, Resign

\* ConfigSwitch's reduction (MCView), with the resignations.
MCResignView == <<MCView, resign, how, gave, lost>>

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses").
\* A Master that ran tasks resigned, all of them flushed, and its successor runs.
WitnessResignFlushedInv ==
    ~\E m, n \in Nodes : how[m] = "flushed" /\ gave[m] # {} /\ IsMaster(n) /\ masterSeq[n] > 0
                         /\ masterStage[n] = "Idle"
\* A Master resigned and abandoned a final checkpoint of a version the Storage node did
\* not hold (the deadline came first): lost, as in a crash, and the switch went on.
WitnessResignAbandonedInv == ~\E m \in Nodes : how[m] = "abandoned" /\ lost[m]
=============================================================================
