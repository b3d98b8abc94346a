--------------------------- MODULE TraceHeartbeat ---------------------------
(***************************************************************************)
(* Trace validation of Heartbeat: the lines one node logged (fsm           *)
(* "heartbeat") must be a behaviour of the spec with that node as the one  *)
(* monitor (Monitors = {M}). Monitors share no state and each C++ node     *)
(* ends its periods at its own boundaries, so every node is validated on   *)
(* its own: its Tick is the spec's Tick, the other nodes' sends and the    *)
(* channel's losses are steps the node cannot log, taken here as hidden   *)
(* steps (at most MaxHidden between two lines, in a fixed node order).     *)
(*                                                                         *)
(* Each line is one spec action with the logged arguments, and the node's *)
(* logged `heard`, `missed` and `failed` must equal the spec's after it.   *)
(* What the runtime does outside the spec's vocabulary is explicit and     *)
(* narrow (spec/README.md, "Trace validation"):                            *)
(*  - a heartbeat from a node already heard in the period changes nothing  *)
(*    (the spec has one heartbeat per node and period; a real channel      *)
(*    delivers two when the sender's and the monitor's boundaries drift);  *)
(*  - DeclareFailed for a restart or a self-reported exclusion only adds   *)
(*    the node to `failed` (it may be there already: a declared node that  *)
(*    restarted or says it is excluded makes the declaration permanent);   *)
(*  - at a view change (the node's election ReceiveCommand line, or its    *)
(*    restart) the monitor may adopt the cluster's failed nodes and start  *)
(*    or stop monitoring: until its next Tick its period boundaries are    *)
(*    not counted (UncountedTick) and `failed` may grow by adoption;       *)
(*  - a declared node proven alive is forgotten (missed back to 0).        *)
(*  - the runtime's `heardOnce` is the spec's heardOnce \cup heard (the    *)
(*    runtime adds a node at the receipt, the spec at the period's end);   *)
(*    a forgotten node counts as heard once, a restart empties it, and a   *)
(*    heartbeat received without a line (M not monitoring, or the sender   *)
(*    declared for good) adds its sender (HearUnlogged);                   *)
(*  - reintegration (spec/Rejoin.tla): when the cluster readmits a node,  *)
(*    M forgets what it counted and declared of it (its Readmit line:      *)
(*    Rejoin.tla's ReadmitBy); when M itself is readmitted, it keeps only   *)
(*    the cluster's exclusions among its declarations, every count        *)
(*    restarts and every node gets the start-up grace again (its Rejoin    *)
(*    line); both are view changes;                                        *)
(*  - a node that boots after M is, to M, a node whose first heartbeats    *)
(*    were lost: no late boot is needed (MaxLateBoots = 0).                *)
(* The loss bound holds (MaxLoss = MissLimit - 1, the models' bound)      *)
(* except where the run's environment broke it: each Tick line carries     *)
(* `lossy`, the senders whose loss in the period may go beyond it (their   *)
(* link was cut, either end was down, paused or restarting, a burst of     *)
(* losses was drawn, or the sender sent nothing: keel-verify reads them    *)
(* from the run's env lines and the nodes' sends, trace/environment.py),   *)
(* and a node M holds failed is not counted: such a loss restarts the      *)
(* link's run. Elsewhere, a link whose sender sent every period and that   *)
(* lost more than MaxLoss in a row is no behaviour of the spec: a monitor  *)
(* that does not hear a live, connected node is rejected at that Tick.     *)
(***************************************************************************)
\* TraceHeartbeatData is written next to this module for each trace: it defines Log (the
\* lines, a sequence of records) and the mission's constant values. Log is a definition,
\* not a CONSTANT, so that TLC evaluates it once.
EXTENDS Heartbeat, TraceHeartbeatData, Sequences, TLC

CONSTANTS
    M,          \* the node whose lines are validated
    Order,      \* Nodes \ {M} as a sequence: the order of hidden sends and losses
    MaxHidden,  \* at most this many hidden steps between two lines
    Relax       \* diagnosis: line Relax need not match its logged variables (0: none)

VARIABLES
    l,          \* index of the next line to explain
    hidden,     \* hidden steps since the last line
    free        \* a view change happened and no Tick was logged since

traceVars == <<l, hidden, free>>

Pos(n) == CHOOSE i \in 1..Len(Order) : Order[i] = n
Before(n) == {Order[i] : i \in 1..(Pos(n) - 1)}
NextIs(a) == l <= Len(Log) /\ Log[l].action = a
\* The next line states the node's variables (a marker line does not).
NextStates == l <= Len(Log) /\ Log[l].action \in
                  {"Tick", "SendHeartbeat", "ReceiveHeartbeat", "DeclareFailed", "Readmit",
                   "Rejoin", "Withdraw"}

\* The node's logged variables equal the spec's after the step. A Tick line, and the
\* declarations it makes, log the `heard` of the period that ends (the monitor clears
\* it after them); it is compared at the Tick.
Matches(e) ==
    \/ l = Relax
    \/ /\ CASE e.action = "Tick" -> heard[M] = e.heard
            [] e.action = "DeclareFailed" /\ e.reason = "missed" -> TRUE
            [] OTHER -> heard'[M] = e.heard
       /\ failed'[M] = e.failed
       /\ \A x \in DOMAIN e.missed : missed'[M][x] = e.missed[x]
       /\ e.hasHeardOnce => heardOnce'[M] \cup heard'[M] = e.heardOnce

TraceInit == Init /\ l = 1 /\ hidden = 0 /\ free = TRUE

(***************************************************************************)
(* One logged line                                                         *)
(***************************************************************************)

ReceiveLine(e) ==
    IF e.n \in heard[M]
    THEN UNCHANGED vars
    ELSE ReceiveHeartbeat(M, e.n)

DeclareLine(e) ==
    IF e.reason = "missed"
    THEN DeclareFailed(M, e.n)
    ELSE /\ e.n \in Watched(M)
         /\ failed' = [failed EXCEPT ![M] = @ \cup {e.n}]
         /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, missed, downFor, heardOnce,
                   unbooted, clock>>

\* The node restarted: nothing of its monitor survives.
RestartLine ==
    /\ heard' = [heard EXCEPT ![M] = {}]
    /\ heardOnce' = [heardOnce EXCEPT ![M] = {}]
    /\ missed' = [missed EXCEPT ![M] = [n \in Nodes |-> 0]]
    /\ failed' = [failed EXCEPT ![M] = {}]
    /\ sent' = [sent EXCEPT ![M] = FALSE]
    /\ UNCHANGED <<alive, inFlight, lossRun, downFor, unbooted, clock>>

\* The cluster readmitted n (Rejoin.tla's ReadmitBy, as M applies it). The Command that
\* readmits n may come from n itself (a hand-over back to it): it proved n alive first
\* (Forget, a hidden step), so n may already be forgotten, heard in this period.
ReadmitLine(e) ==
    /\ e.n \in failed[M] \/ e.n \in heard[M]
    /\ failed' = [failed EXCEPT ![M] = @ \ {e.n}]
    /\ missed' = [missed EXCEPT ![M][e.n] = 0]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, downFor, heardOnce, unbooted, clock>>

\* M withdraws its declaration of n, which proved alive: Forget, logged (its Withdraw line).
WithdrawLine(e) ==
    /\ e.n \in failed[M]
    /\ failed' = [failed EXCEPT ![M] = @ \ {e.n}]
    /\ missed' = [missed EXCEPT ![M][e.n] = 0]
    /\ heard' = [heard EXCEPT ![M] = @ \cup {e.n}]
    /\ heardOnce' = [heardOnce EXCEPT ![M] = @ \cup {e.n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, downFor, unbooted, clock>>

\* M was readmitted: of its declarations it keeps the cluster's exclusions (the logged
\* `failed`, a subset of its own), every count restarts and the grace starts afresh.
RejoinLine(e) ==
    /\ e.failed \subseteq failed[M]
    /\ failed' = [failed EXCEPT ![M] = e.failed]
    /\ missed' = [missed EXCEPT ![M] = [n \in Nodes |-> 0]]
    /\ heardOnce' = [heardOnce EXCEPT ![M] = {}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, downFor, unbooted, clock>>

\* The node logs whether it counted the period: a Tick line with `suspect` (it heard no
\* other node, or ran late: self-suspicion) counted no miss. The trace follows that
\* decision where it cannot see the cause (the rule itself is model-checked in
\* Heartbeat.tla and Exclusion.tla), and holds the decision to rule 1 given what the node
\* logs it observed: a Tick that counts (CountingTick) must not log a cause to suspect
\* itself (keel-verify reads a counting Tick's `late` as "late or silent": its loop ran
\* late, or it heard no other node at all, watched or not).
Always(m) == TRUE
Never(m) == FALSE

\* A Tick that counts no miss must have its cause: the node says its loop ran late (the
\* spec's environment; not visible in the trace), or it heard none of the nodes it
\* watches (a monitor that hears only excluded nodes is silent to the trace too).
SuspectTick(e) == (e.late \/ heard[M] = {}) /\ TickBy(Never)
CountingTick(e) == ~e.late /\ TickBy(Always)

LineStep ==
    /\ l <= Len(Log)
    /\ LET e == Log[l] IN
        /\ CASE e.action = "Tick" /\ e.suspect -> SuspectTick(e) /\ Matches(e) /\ free' = FALSE
             [] e.action = "Tick" -> CountingTick(e) /\ Matches(e) /\ free' = FALSE
             [] e.action = "SendHeartbeat" -> SendHeartbeat(M) /\ Matches(e) /\ UNCHANGED free
             [] e.action = "ReceiveHeartbeat" -> ReceiveLine(e) /\ Matches(e) /\ UNCHANGED free
             [] e.action = "DeclareFailed" -> DeclareLine(e) /\ Matches(e) /\ UNCHANGED free
             [] e.action = "ViewChange" -> UNCHANGED vars /\ free' = TRUE
             [] e.action = "Restart" -> RestartLine /\ free' = TRUE
             [] e.action = "Readmit" -> ReadmitLine(e) /\ Matches(e) /\ free' = TRUE
             [] e.action = "Withdraw" -> WithdrawLine(e) /\ Matches(e) /\ UNCHANGED free
             \* The runtime empties heardOnce without heard: only failed and missed compare.
             [] e.action = "Rejoin" -> RejoinLine(e) /\ free' = TRUE
                                     /\ \A x \in DOMAIN e.missed : missed'[M][x] = e.missed[x]
             [] OTHER -> FALSE
        /\ l' = l + 1
        /\ hidden' = 0

(***************************************************************************)
(* Hidden steps: what the node cannot log                                  *)
(***************************************************************************)

\* Another node sends its heartbeat (in Order), when a receipt or the Tick needs it.
HiddenSend(n) ==
    /\ n # M
    /\ \A x \in Before(n) : sent[x]
    /\ \/ NextIs("Tick")
       \/ /\ NextIs("ReceiveHeartbeat")
          /\ Log[l].n \in Nodes \ {M}  \* (M's own heartbeat, or a stranger: no order)
          /\ (Log[l].n = n \/ n \in Before(Log[l].n))
    /\ SendHeartbeat(n)

\* The channel loses n's heartbeat (in Order), before the Tick: within the loss bound
\* (LoseHeartbeat), or beyond it where the Tick's line says the environment broke it on
\* n's link, or M holds n failed (it counts nothing of n): the link's run starts again.
HiddenLose(n) ==
    /\ n # M
    /\ \A x \in Before(n) : <<x, M>> \notin inFlight
    /\ NextIs("Tick")
    /\ IF n \in Log[l].lossy \cup failed[M]
       THEN /\ <<n, M>> \in inFlight
            /\ inFlight' = inFlight \ {<<n, M>>}
            /\ lossRun' = [lossRun EXCEPT ![M][n] = 0]
            /\ UNCHANGED <<alive, sent, heard, missed, failed, downFor, heardOnce,
                           unbooted, clock>>
       ELSE LoseHeartbeat(n, M)

\* A period boundary the monitor does not count: it had just started monitoring, or it
\* does not monitor (a Worker still sends a heartbeat every period).
UncountedTick ==
    /\ free
    /\ NextIs("SendHeartbeat")
    /\ heard' = [heard EXCEPT ![M] = {}]
    /\ heardOnce' = [heardOnce EXCEPT ![M] = @ \cup heard[M]]
    /\ sent' = [n \in Nodes |-> FALSE]
    /\ inFlight' = {}
    /\ UNCHANGED <<alive, lossRun, missed, failed, downFor, unbooted, clock>>

\* At a view change the monitor adopts a node the cluster excluded, or starts counting
\* afresh.
Adopt(n) ==
    /\ free
    /\ NextStates
    /\ n \in Watched(M) \ failed[M]
    /\ n \in Log[l].failed
    /\ failed' = [failed EXCEPT ![M] = @ \cup {n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, missed, downFor, heardOnce,
                   unbooted, clock>>

Rewatch ==
    /\ free
    /\ \E n \in Nodes : missed[M][n] # 0
    /\ missed' = [missed EXCEPT ![M] = [n \in Nodes |-> 0]]
    /\ heard' = [heard EXCEPT ![M] = {}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, failed, downFor, heardOnce,
                   unbooted, clock>>

\* A declared node proved alive (it commanded this node, or this Observer heard it). The
\* message that proved it counts as heard in the period under way (HeartbeatMonitor::forget).
Forget(n) ==
    /\ NextStates
    /\ n \in failed[M]
    /\ n \notin Log[l].failed
    /\ failed' = [failed EXCEPT ![M] = @ \ {n}]
    /\ missed' = [missed EXCEPT ![M][n] = 0]
    /\ heard' = [heard EXCEPT ![M] = @ \cup {n}]
    /\ heardOnce' = [heardOnce EXCEPT ![M] = @ \cup {n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, downFor, unbooted, clock>>

\* M heard n without a line: a heartbeat that arrived while M did not monitor, or from a
\* node M has declared for good (a restart, an exclusion). It counts as heard once.
HearUnlogged(n) ==
    /\ NextStates
    /\ Log[l].hasHeardOnce
    /\ n \in Log[l].heardOnce \ (heardOnce[M] \cup heard[M])
    /\ heardOnce' = [heardOnce EXCEPT ![M] = @ \cup {n}]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, missed, failed, downFor, unbooted,
                   clock>>

\* M heard from n for the first time by another message (a command, an ack): n is alive,
\* its start-up grace ends, and its count restarts from zero (HeartbeatMonitor::heard_from).
HearOther(n) ==
    /\ NextStates
    /\ Log[l].hasHeardOnce
    /\ n \in Log[l].heardOnce \ (heardOnce[M] \cup heard[M])
    /\ n \notin failed[M]
    /\ heardOnce' = [heardOnce EXCEPT ![M] = @ \cup {n}]
    /\ missed' = [missed EXCEPT ![M][n] = 0]
    /\ UNCHANGED <<alive, sent, inFlight, lossRun, heard, failed, downFor, unbooted, clock>>

HiddenStep ==
    /\ hidden < MaxHidden
    /\ l <= Len(Log)
    /\ \/ \E n \in Nodes : HiddenSend(n)
       \/ \E n \in Nodes : HiddenLose(n)
       \/ UncountedTick
       \/ \E n \in Nodes : Adopt(n)
       \/ Rewatch
       \/ \E n \in Nodes : Forget(n)
       \/ \E n \in Nodes : HearUnlogged(n)
       \/ \E n \in Nodes : HearOther(n)
    /\ hidden' = hidden + 1
    /\ UNCHANGED <<l, free>>

TraceNext == LineStep \/ HiddenStep

TraceSpec == TraceInit /\ [][TraceNext]_<<vars, traceVars>>

\* Violated exactly when every line has been explained: the trace is a behaviour.
TraceNotAccepted == l <= Len(Log)
\* The same verdict without a counter-example: TLC prints the marker when a state past
\* the last line is reachable, and goes on (printing a behaviour as long as the trace
\* costs more than checking it).
TraceExplained == l <= Len(Log) \/ PrintT("keel-trace: every line explained")
\* Diagnosis: violated once line Relax has been taken, with or without its variables.
NotPastRelax == l <= Relax
=============================================================================
