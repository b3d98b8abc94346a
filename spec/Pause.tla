------------------------------- MODULE Pause -------------------------------
(***************************************************************************)
(* The ground's `pause-task` and `resume-task` (docs/operations.md, "The   *)
(* commands"; ConfigSwitch::pause, resume): ConfigSwitch's two-phase       *)
(* switch with the ground pausing and resuming tasks.                      *)
(*                                                                         *)
(*  - GroundPause(t, R): the command reaches the running nodes R (the      *)
(*    uplink may miss some, or reach them one at a time: one command per   *)
(*    reach); each holds t paused. Never an essential task (refused).      *)
(*  - GroundResume(t, R): each node of R that holds t paused lets it run   *)
(*    again.                                                               *)
(*  - ConfigSwitch's `active` is what the switch places on a node; what    *)
(*    runs is `running` (ConfigSwitch::pause, activate, restart): a task   *)
(*    the switch activates starts unless the node holds it paused; a       *)
(*    pause stops it where it runs; a resume starts it where it is placed; *)
(*    a task the switch deactivates (or a crash) stops. Only a running     *)
(*    task takes a step (Execute). So a paused task stays placed: it is    *)
(*    deactivated and flushed when a switch moves it away, and restored    *)
(*    from the Storage node, not started, on a new host that holds it      *)
(*    paused; resumed, it runs from the state the node holds, the latest   *)
(*    (no other live node ran it meanwhile: NoDoubleActivationInv).        *)
(*                                                                         *)
(* Properties: PausedIdleInv, no node runs a task it holds paused          *)
(* (mutants/PauseKeepsRunning.tla: a pause that leaves the task running;   *)
(* mutants/PauseActivateStarts.tla: a switch's activation that starts a    *)
(* paused task); EssentialNeverPausedInv, no node holds an essential task  *)
(* paused (mutants/PauseEssential.tla); RunsPlacedInv, a node runs only    *)
(* what the switch placed on it (mutants/PauseResumesAnywhere.tla); and   *)
(* ConfigSwitch's (NoDoubleActivationInv, ResumeLatestCheckpointInv,       *)
(* SwitchConverges: a paused task counts as placed) with pauses anywhere.  *)
(* Witness (MCPause.tla): t1 paused at the node a switch moves it to,      *)
(* activated there and not started, resumed there and run                  *)
(* (WitnessResumedAfterMoveInv).                                           *)
(***************************************************************************)
EXTENDS ConfigSwitch

CONSTANTS
    Essential,   \* the tasks the mission marks essential: never paused
    MaxGround    \* at most this many ground commands (pauses and resumes)

ASSUME Essential \subseteq Tasks /\ MaxGround \in Nat

VARIABLES
    paused,      \* [Nodes -> SUBSET Tasks]: the tasks each node holds paused
    running,     \* [Nodes -> SUBSET Tasks]: the tasks each node runs (within `active`)
    commands,    \* ground commands so far
    hist         \* history: <<milestone, node, task>> records the witness reads

pauseVars == <<paused, running, commands, hist>>
allVars == <<vars, pauseVars>>

Milestones == {"placedPaused", "resumedPlaced", "ranResumed"}

PTypeOK ==
    /\ TypeOK
    /\ paused \in [Nodes -> SUBSET Tasks]
    /\ running \in [Nodes -> SUBSET Tasks]
    /\ commands \in 0..MaxGround
    /\ hist \subseteq (Milestones \X Nodes \X Tasks)

PInit ==
    /\ Init
    /\ paused = [n \in Nodes |-> {}]
    /\ running = [n \in Nodes |-> {}]
    /\ commands = 0
    /\ hist = {}

\* The ground pauses t at the running nodes R (an essential task never: refused); the
\* node that runs it stops it (`stops`: mutants pass FALSE).
GroundPauseBy(Allowed(_), stops, t, R) ==
    /\ commands < MaxGround
    /\ Allowed(t)
    /\ R # {} /\ R \subseteq Running
    /\ \A n \in R : t \notin paused[n]
    /\ paused' = [n \in Nodes |-> IF n \in R THEN paused[n] \cup {t} ELSE paused[n]]
    /\ running' = IF stops THEN [n \in Nodes |-> IF n \in R THEN running[n] \ {t} ELSE running[n]]
                  ELSE running
    /\ commands' = commands + 1
    /\ UNCHANGED <<vars, hist>>

NotEssential(t) == t \notin Essential

\* The ground resumes t at the running nodes R that hold it paused; where the switch
\* places it, it starts again (`placedOnly`: a mutant starts it wherever it resumes).
GroundResumeBy(placedOnly, t, R) ==
    /\ commands < MaxGround
    /\ R # {} /\ R \subseteq Running
    /\ \A n \in R : t \in paused[n]
    /\ paused' = [n \in Nodes |-> IF n \in R THEN paused[n] \ {t} ELSE paused[n]]
    /\ running' = [n \in Nodes |-> IF n \in R /\ (t \in active[n] \/ ~placedOnly)
                                  THEN running[n] \cup {t} ELSE running[n]]
    /\ commands' = commands + 1
    /\ hist' = hist \cup {<<"resumedPlaced", n, t>> :
                           n \in {x \in R : t \in active[x] /\ <<"placedPaused", x, t>> \in hist}}
    /\ UNCHANGED vars

\* A running task takes one step.
PExecute(n, t) ==
    /\ t \in running[n]
    /\ Execute(n, t)
    /\ hist' = IF <<"resumedPlaced", n, t>> \in hist THEN hist \cup {<<"ranResumed", n, t>>} ELSE hist
    /\ UNCHANGED <<paused, running, commands>>

\* ConfigSwitch's steps: what the switch activates on a node starts unless the node holds
\* it paused (`starts`: a mutant starts it regardless), what it deactivates stops (a
\* crash stops everything). An activation of a task its node holds paused is a milestone.
SwitchStepBy(starts(_, _)) ==
    /\ \/ ProtocolNext
       \/ PlannedNext
       \/ \E n \in Nodes : Crash(n)
       \/ \E n \in Nodes : Boot(n)
    /\ running' = [n \in Nodes |->
                      (running[n] \cap active'[n]) \cup
                      {t \in active'[n] \ active[n] : starts(n, t)}]
    /\ hist' = hist \cup UNION {{<<"placedPaused", n, t>> : t \in (active'[n] \ active[n]) \cap paused[n]} :
                                  n \in Nodes}
    /\ UNCHANGED <<paused, commands>>

UnlessPaused(n, t) == t \notin paused[n]

PNextBy(Allowed(_), stops, starts(_, _), placedOnly) ==
    \/ SwitchStepBy(starts)
    \/ \E n \in Nodes, t \in Tasks : PExecute(n, t)
    \/ \E t \in Tasks, R \in SUBSET Nodes : GroundPauseBy(Allowed, stops, t, R)
    \/ \E t \in Tasks, R \in SUBSET Nodes : GroundResumeBy(placedOnly, t, R)

PNext == PNextBy(NotEssential, TRUE, UnlessPaused, TRUE)

PSpec == PInit /\ [][PNext]_allVars

\* As ConfigSwitch's Fairness: the protocol's steps (with what they start and stop).
PFairness ==
    /\ WF_allVars(SwitchStepBy(UnlessPaused) /\ ProtocolNext)
    /\ \A n \in Nodes : WF_allVars(SwitchStepBy(UnlessPaused) /\ Boot(n))

PFairSpec == PSpec /\ PFairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

PausedIdleInv == \A n \in Nodes : running[n] \cap paused[n] = {}

RunsPlacedInv == \A n \in Nodes : running[n] \subseteq active[n]

EssentialNeverPausedInv == \A n \in Nodes : paused[n] \cap Essential = {}
=============================================================================
