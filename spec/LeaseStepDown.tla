---------------------------- MODULE LeaseStepDown ----------------------------
(***************************************************************************)
(* A Master that is cut off or stalled steps down before its lease lapses  *)
(* (fault model 2, rule 3; core/fsm/node_protocol.cpp step_down_if_cut_off *)
(* and step_down_if_stalled).                                              *)
(*                                                                         *)
(* Lease.tla lets a Master run until the voters that may already hold it  *)
(* failed are as many as an exclusion needs. The runtime adds two earlier  *)
(* step-downs, each a resignation (Lease's `resigned`: its own word, on    *)
(* which its successor takes over without further evidence):              *)
(*  - cut off: the Master heard no other node for MissLimit - 1 periods in *)
(*    a row (`silentFor`), before the Observers, which declare it after    *)
(*    MissLimit periods, take over;                                        *)
(*  - stalled: the Master's own loop ran late (Exclusion's `late`): when   *)
(*    it next runs it steps down before it handles anything that arrived. *)
(* A Master that steps down stops at once: it deactivates its tasks and   *)
(* commands nothing more (running becomes FALSE in the same step), and its *)
(* successor may exclude it at once. The step-down is its own word, so it  *)
(* must be right: a Master that stepped down on less than MissLimit - 1    *)
(* silent periods would take a healthy Master out of the cluster           *)
(* (mutants/LeaseStepDownEager breaks NoFalseExclusionInv).                *)
(*                                                                         *)
(* Properties: Lease's, with the step-downs: NoExcludedRunsInv,            *)
(* AckBoundInv, and NoFalseExclusionInv (a Master steps down only when it  *)
(* is itself faulty: a healthy one hears the healthy nodes every period).  *)
(***************************************************************************)
EXTENDS Lease

VARIABLES
    silentFor,  \* [Monitors -> 0..MissLimit - 1], periods in a row a monitor heard no other
                \* node (counted up to the step-down's threshold)
    stepDowns   \* history: the early step-downs, <<Master, "cut off" or "stalled">>

stepDownVars == <<allVars, silentFor, stepDowns>>

STypeOK ==
    /\ LTypeOK
    /\ silentFor \in [Monitors -> 0..MissLimit - 1]
    /\ stepDowns \subseteq Monitors \X {"cut off", "stalled"}

SInit == LInit /\ silentFor = [m \in Monitors |-> 0] /\ stepDowns = {}

\* `silence`: the silent periods after which a Master is cut off (MissLimit - 1; a mutant
\* passes another).
CutOffBy(m, silence) == silentFor[m] >= silence

StepDownBy(m, silence) ==
    /\ m = Master
    /\ alive[m]
    /\ m \notin resigned
    /\ m \notin excluded
    /\ \E why \in {"cut off", "stalled"} :
          /\ IF why = "cut off" THEN CutOffBy(m, silence) ELSE m \in late
          /\ stepDowns' = stepDowns \cup {<<m, why>>}
    /\ resigned' = resigned \cup {m}
    /\ running' = [running EXCEPT ![m] = FALSE]
    /\ UNCHANGED <<vars, ackLoss, ackAge, silentFor>>

\* The period ends (Lease's tick); each monitor counts whether it heard anyone in it.
STick ==
    /\ LTickBy(MissLimit, Quorum, 1, TRUE)
    /\ silentFor' = [m \in Monitors |->
                       IF heard[m] = {} THEN Min(silentFor[m] + 1, MissLimit - 1) ELSE 0]
    /\ UNCHANGED stepDowns

SNextBy(silence) ==
    \/ \E n \in Nodes : SendHeartbeat(n) /\ UNCHANGED <<leaseVars, silentFor, stepDowns>>
    \/ \E m \in Monitors, n \in Nodes :
          ReceiveHeartbeat(m, n) /\ UNCHANGED <<leaseVars, silentFor, stepDowns>>
    \/ STick
    \/ \E n \in Nodes : LExcludeBy(n, MissLimit, Quorum, TRUE) /\ UNCHANGED <<silentFor, stepDowns>>
    \/ \E m \in Monitors, n \in Nodes :
          LoseHeartbeat(n, m) /\ UNCHANGED <<leaseVars, silentFor, stepDowns>>
    \/ \E n \in Nodes : Crash(n) /\ UNCHANGED <<leaseVars, silentFor, stepDowns>>
    \/ \E m \in Monitors : StepDownBy(m, silence)

SSpec == SInit /\ [][SNextBy(MissLimit - 1)]_stepDownVars
=============================================================================
