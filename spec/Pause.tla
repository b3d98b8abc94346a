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
(*  - A node takes no step of a task it holds paused (PExecute: the rule). *)
(*    Paused, a task stays what the switch places on the node: it is       *)
(*    deactivated and flushed when a switch moves it away, and activated   *)
(*    (restored from the Storage node) on its new host, which holds it     *)
(*    paused too when the command reached it, and does not run it. A       *)
(*    resumed task runs from the state the node holds, which is the        *)
(*    latest: no other live node ran it meanwhile (NoDoubleActivationInv). *)
(*                                                                         *)
(* Properties: ConfigSwitch's (NoDoubleActivationInv,                      *)
(* ResumeLatestCheckpointInv, SwitchConverges: a paused task counts as     *)
(* placed) hold with pauses anywhere, and PausedIdleInv: no node ever took *)
(* a step of a task it held paused (`ranPaused`, a history variable set by *)
(* a step that breaks the rule; mutants/PauseKeepsRunning.tla takes them), *)
(* EssentialNeverPausedInv: no node holds an essential task paused         *)
(* (mutants/PauseEssential.tla pauses one). Witness: a task paused on its  *)
(* host, moved by a switch to a node that holds it paused, resumed there   *)
(* and run (WitnessResumedAfterMoveInv).                                   *)
(***************************************************************************)
EXTENDS ConfigSwitch

CONSTANTS
    Essential,   \* the tasks the mission marks essential: never paused
    MaxGround    \* at most this many ground commands (pauses and resumes)

ASSUME Essential \subseteq Tasks /\ MaxGround \in Nat

VARIABLES
    paused,      \* [Nodes -> SUBSET Tasks]: the tasks each node holds paused
    commands,    \* ground commands so far
    ranPaused,   \* history: some node took a step of a task it held paused
    hist         \* history: the milestones the witness names

pauseVars == <<paused, commands, ranPaused, hist>>
allVars == <<vars, pauseVars>>

Milestones == {"placedPaused", "resumedPlaced", "ranResumed"}

PTypeOK ==
    /\ TypeOK
    /\ paused \in [Nodes -> SUBSET Tasks]
    /\ commands \in 0..MaxGround
    /\ ranPaused \in BOOLEAN
    /\ hist \subseteq Milestones

PInit ==
    /\ Init
    /\ paused = [n \in Nodes |-> {}]
    /\ commands = 0
    /\ ranPaused = FALSE
    /\ hist = {}

\* The ground pauses t at the running nodes R (an essential task never: refused).
GroundPauseBy(Allowed(_), t, R) ==
    /\ commands < MaxGround
    /\ Allowed(t)
    /\ R # {} /\ R \subseteq Running
    /\ \A n \in R : t \notin paused[n]
    /\ paused' = [n \in Nodes |-> IF n \in R THEN paused[n] \cup {t} ELSE paused[n]]
    /\ commands' = commands + 1
    /\ UNCHANGED <<vars, ranPaused, hist>>

NotEssential(t) == t \notin Essential

\* The ground resumes t at the running nodes R that hold it paused.
GroundResume(t, R) ==
    /\ commands < MaxGround
    /\ R # {} /\ R \subseteq Running
    /\ \A n \in R : t \in paused[n]
    /\ paused' = [n \in Nodes |-> IF n \in R THEN paused[n] \ {t} ELSE paused[n]]
    /\ commands' = commands + 1
    /\ hist' = IF "placedPaused" \in hist /\ \E n \in R : t \in active[n]
               THEN hist \cup {"resumedPlaced"} ELSE hist
    /\ UNCHANGED <<vars, ranPaused>>

\* Task t runs one step on n; `guarded`: only if n does not hold it paused (the rule).
PExecuteBy(guarded, n, t) ==
    /\ guarded => t \notin paused[n]
    /\ Execute(n, t)
    /\ ranPaused' = (ranPaused \/ t \in paused[n])
    /\ hist' = IF "resumedPlaced" \in hist THEN hist \cup {"ranResumed"} ELSE hist
    /\ UNCHANGED <<paused, commands>>

\* ConfigSwitch's steps, the pauses unchanged. An activation of a task its node holds
\* paused is a milestone (the task moved to a node that took the pause).
SwitchStep ==
    /\ \/ ProtocolNext
       \/ PlannedNext
       \/ \E n \in Nodes : Crash(n)
       \/ \E n \in Nodes : Boot(n)
    /\ UNCHANGED <<paused, commands, ranPaused>>
    /\ hist' = IF \E n \in Nodes : (active'[n] \ active[n]) \cap paused[n] # {}
               THEN hist \cup {"placedPaused"} ELSE hist

PNextBy(Allowed(_), guarded) ==
    \/ SwitchStep
    \/ \E n \in Nodes, t \in Tasks : PExecuteBy(guarded, n, t)
    \/ \E t \in Tasks, R \in SUBSET Nodes : GroundPauseBy(Allowed, t, R)
    \/ \E t \in Tasks, R \in SUBSET Nodes : GroundResume(t, R)

PNext == PNextBy(NotEssential, TRUE)

PSpec == PInit /\ [][PNext]_allVars

\* As ConfigSwitch's Fairness: the protocol's steps, the pauses unchanged.
PFairness ==
    /\ WF_allVars(ProtocolNext /\ UNCHANGED pauseVars)
    /\ \A n \in Nodes : WF_allVars(Boot(n) /\ UNCHANGED pauseVars)

PFairSpec == PSpec /\ PFairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

PausedIdleInv == ~ranPaused

EssentialNeverPausedInv == \A n \in Nodes : paused[n] \cap Essential = {}

\* Witness: a task paused, moved to a node that holds it paused, resumed there, and run.
WitnessResumedAfterMoveInv == "ranResumed" \notin hist
=============================================================================
