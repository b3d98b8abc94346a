------------------------- MODULE TraceConfigSwitch -------------------------
(***************************************************************************)
(* Trace validation of ConfigSwitch: the switch lines of every node but    *)
(* the Storage node (and the Storage node's stored checkpoints), merged in *)
(* time order, must be a behaviour of the spec with the mission's          *)
(* configurations, decision graph and phase map as constants. Each line is *)
(* the spec action with the logged arguments, and the acting node's logged *)
(* variables must equal the spec's after it. The guards are the spec's:    *)
(* a node follows only a Newer command; Deactivate only in "Deactivating"  *)
(* a task the target configuration moves away; Ack only when ReadyToAck;   *)
(* BroadcastActivate only when every running node acked "Prepared";        *)
(* Activate only in "Activating" a task placed on the node, from `stored`. *)
(*                                                                         *)
(* How the runtime's lines map to the spec (spec/README.md):               *)
(*  - the initial Master's BootSwitch line is the spec's BootSwitch; a     *)
(*    node declared failed before its first line booted late (TLate: Init *)
(*    leaves it unbooted, and it boots, a hidden step, just before its     *)
(*    first line);                                                         *)
(*  - the Master's DeclareFailed / RequestPhase line is the spec's action  *)
(*    with StartSwitch; its BroadcastCommand line and the delivery of the  *)
(*    command to itself (its own ReceiveCommand line) change nothing more; *)
(*  - a Deactivate line logs the task gone from `active` before the        *)
(*    runtime marks it unflushed; the final checkpoint is the spec's       *)
(*    FlushCheckpoint when the Storage node stores it (StoreCheckpoint);   *)
(*    a task without checkpoints is flushed at once (hidden step);         *)
(*  - a periodic checkpoint (FlushCheckpoint with final=false) is the      *)
(*    spec's Execute steps up to the logged version, and the Storage node  *)
(*    storing it makes `stored` newer (the spec leaves these out);         *)
(*  - a repeated Ack (a retransmission) changes nothing;                   *)
(*  - the lease's lines (Hold, Release, LeaseLapsed: spec/Lease.tla) stop   *)
(*    or restart a node's tasks without changing a ConfigSwitch variable   *)
(*    (a held task stays active in the switch): a step that changes       *)
(*    nothing, its logged variables equal to the spec's;                  *)
(*  - a crash is the spec's Crash: an env line of the simulator, or hidden *)
(*    just before the Master declares the node or a new Master takes over; *)
(*  - a take-over (BecomeMaster) follows the runtime's election: the       *)
(*    logged epoch above every epoch seen, seq 1, straight to the target   *)
(*    configuration of the decision graph (the spec restarts the switch to *)
(*    the configuration the node knows, then declares the failure).       *)
(***************************************************************************)
\* TraceConfigSwitchData is written next to this module for each trace: it defines Log (the
\* lines, a sequence of records) and the mission's constant values. Log is a definition,
\* not a CONSTANT, so that TLC evaluates it once.
EXTENDS ConfigSwitch, TraceConfigSwitchData, Sequences, TLC

CONSTANTS
    Checkpointed,\* the tasks with checkpoints
    MasterOf(_), \* MasterOf(c): the master configuration c names
    MaxHidden,   \* at most this many hidden steps between two lines
    Relax        \* diagnosis: line Relax need not match its logged variables (0: none)

VARIABLES l, hidden

traceVars == <<l, hidden>>

NextIs(a) == l <= Len(Log) /\ Log[l].action = a

\* The acting node's logged variables (those the line has) after the step.
Matches(e) ==
    \/ l = Relax
    \/ LET n == e.n IN
       /\ "epoch" \in e.has => epoch'[n] = e.vepoch
       /\ "seq" \in e.has => seq'[n] = e.vseq
       /\ "config" \in e.has => config'[n] = e.vconfig
       /\ "stage" \in e.has => stage'[n] = e.vstage
       /\ "active" \in e.has => active'[n] = e.vactive
       /\ "unflushed" \in e.has => unflushed'[n] = e.vunflushed
       /\ "version" \in e.has =>
            \A t \in DOMAIN e.vversion \cap Checkpointed : version'[n][t] = e.vversion[t]
       /\ "masterStage" \in e.has => masterStage'[n] = e.vmasterStage
       /\ "masterConfig" \in e.has => masterConfig'[n] = e.vmasterConfig
       /\ "masterSeq" \in e.has => masterSeq'[n] = e.vmasterSeq
       /\ "failed" \in e.has => failed'[n] = e.vfailed

\* The nodes that booted late are those declared failed before their first line
\* (TLate, computed from the trace).
TraceInit == Init /\ unbooted = TLate /\ l = 1 /\ hidden = 0

\* The runtime's take-over (see the header).
TakeOver(n, e, c, f) ==
    /\ alive[n]
    /\ n \in ProcessingNodes
    /\ \A x \in Nodes : (role[x] = "Master" /\ x # n) => ~alive[x]
    /\ \A x \in Nodes : epoch[x] < e
    /\ c \in ConfigIds
    \* The configuration taken over is this node's, and uses no node it holds failed, and
    \* those are down (ConfigSwitch's failures are crashes).
    /\ MasterOf(c) = n
    /\ \A t \in Tasks : Placement(c, t) \notin f
    /\ \A x \in f : ~alive[x]
    /\ role' = [x \in Nodes |-> IF x = n THEN "Master"
                               ELSE IF role[x] = "Master" THEN "Worker" ELSE role[x]]
    /\ epoch' = [epoch EXCEPT ![n] = e]
    /\ masterSeq' = [masterSeq EXCEPT ![n] = 1]
    /\ masterConfig' = [masterConfig EXCEPT ![n] = c]
    /\ masterStage' = [masterStage EXCEPT ![n] = "Preparing"]
    /\ failed' = [failed EXCEPT ![n] = f]
    /\ msgs' = msgs \cup {Command(e, 1, c)}
    /\ seq' = [seq EXCEPT ![n] = 1]
    /\ config' = [config EXCEPT ![n] = c]
    /\ stage' = [stage EXCEPT ![n] = "Deactivating"]
    /\ UNCHANGED <<alive, active, unflushed, version, stored, acks, crashes, phaseChanges,
                   unbooted>>

\* A command the node has already applied (the Master's own): nothing changes.
Applied(n, e, s, c) ==
    /\ alive[n]
    /\ epoch[n] = e /\ seq[n] = s /\ config[n] = c
    /\ UNCHANGED vars

\* Execute steps up to version v (a periodic checkpoint line).
Steps(n, t, v) ==
    /\ alive[n]
    /\ t \in active[n]
    /\ v >= version[n][t]
    /\ version' = [version EXCEPT ![n][t] = v]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* The Storage node stores n's checkpoint of t at version v: the final one is the spec's
\* FlushCheckpoint, a periodic one makes `stored` newer.
\* The Storage node keeps only a newer version than it holds (and logs only that), and
\* only one its writer had reached.
Store(n, t, v) ==
    IF t \in unflushed[n] /\ version[n][t] = v
    THEN FlushCheckpoint(n, t)
    ELSE /\ v > stored[t]
         /\ v <= version[n][t]
         /\ stored' = [stored EXCEPT ![t] = v]
         /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, version,
                        masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                        phaseChanges, unbooted>>

AckLine(n, k) ==
    IF AckMsg(k, epoch[n], seq[n], n) \in acks /\ ~ReadyToAck(n, k)
    THEN UNCHANGED vars
    ELSE Ack(n, k)

\* Reintegration (spec/Rejoin.tla), as the runtime's switch carries it out:
\* - a restart (an env line) is a crash and a boot: the node keeps its persisted view
\*   (epoch, seq, configuration) and nothing else; it runs nothing and waits to be
\*   commanded, a Worker. It boots (HiddenBoot) just before its next line: until then
\*   it is down to the others (the Master declares it for its restart);
\* - the Master readmits r (its Readmit line) into configuration c of its own, in an
\*   epoch of its own above every epoch: a switch like a take-over's, without r among
\*   the failed (r runs again), and only into a configuration that uses no other node it
\*   holds failed.
RestartNode(n) ==
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ active' = [active EXCEPT ![n] = {}]
    /\ unflushed' = [unflushed EXCEPT ![n] = {}]
    /\ version' = [version EXCEPT ![n] = [t \in Tasks |-> 0]]
    /\ stage' = [stage EXCEPT ![n] = "Stable"]
    /\ role' = [role EXCEPT ![n] = "Worker"]
    /\ masterStage' = [masterStage EXCEPT ![n] = "Idle"]
    /\ unbooted' = unbooted \cup {n}
    /\ UNCHANGED <<epoch, seq, config, stored, masterConfig, masterSeq, failed, msgs, acks,
                   crashes, phaseChanges>>

ReadmitSwitch(m, r, e, c) ==
    /\ alive[m]
    /\ role[m] = "Master"
    /\ masterStage[m] = "Idle"
    /\ r \in failed[m]
    /\ alive[r]
    /\ \A x \in Nodes : epoch[x] < e
    /\ c \in ConfigIds
    /\ MasterOf(c) = m
    /\ \A t \in Tasks : Placement(c, t) \notin failed[m] \ {r}
    /\ epoch' = [epoch EXCEPT ![m] = e]
    /\ failed' = [failed EXCEPT ![m] = @ \ {r}]
    /\ masterSeq' = [masterSeq EXCEPT ![m] = 1]
    /\ masterConfig' = [masterConfig EXCEPT ![m] = c]
    /\ masterStage' = [masterStage EXCEPT ![m] = "Preparing"]
    /\ msgs' = msgs \cup {Command(e, 1, c)}
    /\ seq' = [seq EXCEPT ![m] = 1]
    /\ config' = [config EXCEPT ![m] = c]
    /\ stage' = [stage EXCEPT ![m] = "Deactivating"]
    /\ UNCHANGED <<alive, role, active, unflushed, version, stored, acks, crashes,
                   phaseChanges, unbooted>>

\* - the Master hands the view to r, the master of c (its HandOver line): a command of
\*   r's epoch e at seq 0 that every node adopts (the Master too, which stops driving),
\*   and r, Master of e, drives c with the Master's failed nodes but r; its first switch
\*   is its BootSwitch line (seq 1 of c).
HandOverSwitch(m, r, e, c) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Idle"
    /\ r \in failed[m]
    /\ alive[r]
    /\ \A x \in Nodes : epoch[x] < e
    /\ c \in ConfigIds
    /\ MasterOf(c) = r
    /\ \A t \in Tasks : Placement(c, t) \notin failed[m] \ {r}
    /\ msgs' = msgs \cup {Command(e, 0, c)}
    /\ role' = [role EXCEPT ![m] = "Worker", ![r] = "Master"]
    /\ masterSeq' = [masterSeq EXCEPT ![r] = 0]
    /\ masterConfig' = [masterConfig EXCEPT ![r] = c]
    /\ masterStage' = [masterStage EXCEPT ![r] = "Idle"]
    /\ failed' = [failed EXCEPT ![r] = failed[m] \ {r}]
    /\ UNCHANGED <<alive, epoch, seq, config, stage, active, unflushed, version, stored,
                   acks, crashes, phaseChanges, unbooted>>

\* The handed-over Master's first switch, once it adopted the view (seq 0 of its epoch).
HandedBootSwitch(m) ==
    /\ IsMaster(m)
    /\ masterSeq[m] = 0
    /\ seq[m] = 0
    /\ config[m] = masterConfig[m]
    /\ StartSwitch(m, masterConfig[m])
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted>>

LineStep ==
    /\ l <= Len(Log)
    /\ LET e == Log[l] IN
        /\ CASE e.action = "DeclareFailed" ->
                    /\ DeclareFailed(e.n, e.f)
                    /\ IF e.c \in ConfigIds THEN OnFailure(masterConfig[e.n], e.f) = e.c
                                            ELSE FALSE
                    /\ Matches(e)
             [] e.action = "BootSwitch" ->
                    \/ /\ e.c = InitialConfig
                       /\ epoch[e.n] = 1
                       /\ BootSwitch(e.n)
                       /\ Matches(e)
                    \/ /\ epoch[e.n] > 1
                       /\ e.c = masterConfig[e.n]
                       /\ HandedBootSwitch(e.n)
                       /\ Matches(e)
             [] e.action = "RequestPhase" -> RequestPhase(e.n, e.c) /\ Matches(e)
             [] e.action = "TakeOver" -> TakeOver(e.n, e.vepoch, e.c, e.vfailed) /\ Matches(e)
             [] e.action = "BroadcastCommand" ->
                    /\ Command(e.epoch, e.seq, e.c) \in msgs
                    /\ masterStage[e.n] = "Preparing"
                    /\ UNCHANGED vars
                    /\ Matches(e)
             [] e.action = "ReceiveCommand" ->
                    \/ Applied(e.n, e.epoch, e.seq, e.c) /\ Matches(e)
                    \/ ReceiveCommand(e.n, Command(e.epoch, e.seq, e.c)) /\ Matches(e)
             [] e.action = "Deactivate" -> Deactivate(e.n, e.t) /\ Matches(e)
             [] e.action = "FlushFinal" ->
                    /\ alive[e.n]
                    /\ e.t \notin active[e.n]
                    /\ version[e.n][e.t] = e.version
                    /\ UNCHANGED vars
                    /\ Matches(e)
             [] e.action = "Steps" -> Steps(e.n, e.t, e.version) /\ Matches(e)
             [] e.action = "Store" -> Store(e.n, e.t, e.version)
             [] e.action = "Ack" -> AckLine(e.n, e.kind) /\ Matches(e)
             [] e.action = "BroadcastActivate" -> BroadcastActivate(e.n) /\ Matches(e)
             [] e.action = "ReceiveActivate" ->
                    ReceiveActivate(e.n, ActivateMsg(e.epoch, e.seq, config[e.n])) /\ Matches(e)
             [] e.action = "Activate" ->
                    /\ Activate(e.n, e.t)
                    /\ e.t \in Checkpointed => stored[e.t] = e.version
                    /\ Matches(e)
             [] e.action = "CompleteSwitch" -> CompleteSwitch(e.n) /\ Matches(e)
             [] e.action = "Lease" -> alive[e.n] /\ UNCHANGED vars /\ Matches(e)
             [] e.action = "Crash" -> Crash(e.n)
             [] e.action = "Restart" -> RestartNode(e.n)
             [] e.action = "Readmit" -> ReadmitSwitch(e.n, e.f, e.vepoch, e.c) /\ Matches(e)
             [] e.action = "HandOver" -> HandOverSwitch(e.n, e.f, e.epoch, e.c) /\ Matches(e)
             [] OTHER -> FALSE
        /\ l' = l + 1
        /\ hidden' = 0

\* A task without checkpoints has nothing to flush: its "final checkpoint" is at once.
\* A final checkpoint of a version the Storage node already holds (a periodic write got
\* there first) changes nothing there, so the Storage node logs nothing.
HiddenFlush(n, t) ==
    /\ t \in unflushed[n]
    /\ t \in Checkpointed => stored[t] = version[n][t]
    /\ FlushCheckpoint(n, t)

\* A crash the trace does not log (a real cluster's kill), just before its consequence.
HiddenCrash(x) ==
    /\ l <= Len(Log)
    /\ \/ Log[l].action = "DeclareFailed" /\ Log[l].f = x
       \/ Log[l].action = "TakeOver" /\ role[x] = "Master" /\ x # Log[l].n
    /\ Crash(x)

\* A node whose process started late boots just before its first line (Init chose it
\* among the unbooted nodes; a node declared before it booted is one of them).
HiddenBoot(x) ==
    /\ l <= Len(Log)
    /\ Log[l].n = x
    /\ Boot(x)

HiddenStep ==
    /\ hidden < MaxHidden
    /\ \/ \E n \in Nodes, t \in Tasks : HiddenFlush(n, t)
       \/ \E x \in Nodes : HiddenCrash(x)
       \/ \E x \in Nodes : HiddenBoot(x)
    /\ hidden' = hidden + 1
    /\ UNCHANGED l

\* The spec's safety invariants hold along the trace: a line whose step would break one
\* is not explained (the trace stops there, a mismatch at that line).
TraceNext == (LineStep \/ HiddenStep) /\ NoDoubleActivationInv' /\ ResumeLatestCheckpointInv'

TraceNotAccepted == l <= Len(Log)
NotPastRelax == l <= Relax
=============================================================================
