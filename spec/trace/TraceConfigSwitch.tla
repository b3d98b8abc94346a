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
(*  - the Master's Exclude / RequestPhase line is the spec's action        *)
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
(*  - partitions, one-way blocks, deafness and pauses only decide which    *)
(*    messages arrive: no line (the spec's network may lose any message);  *)
(*    a node the cluster excludes while its process runs is fenced at that *)
(*    exclusion (Fence: the spec's Crash) and its later lines change       *)
(*    nothing (FencedLine) until it restarts or is readmitted;             *)
(*  - a Master's resignation (Resign, Resigned) stops and flushes its      *)
(*    tasks and lets its successor exclude it (ResignSwitch); a Worker's   *)
(*    AskExclusion changes nothing (the Master's Exclude fences it);       *)
(*  - safe mode is a configuration per phase and Master (SafeIds: the      *)
(*    phase's essential tasks on the Master), entered by the decision      *)
(*    graph, left by a readmission or a ground command                     *)
(*    (GroundRecoverySwitch);                                              *)
(*  - with the Storage node excluded, a stopped task's state stays with    *)
(*    its last host (HiddenHandOff), the next host gathers it (AskHolders) *)
(*    and a state out of reach is a reported loss (StateOutOfReach).       *)
(***************************************************************************)
\* TraceConfigSwitchData is written next to this module for each trace: it defines Log (the
\* lines, a sequence of records) and the mission's constant values. Log is a definition,
\* not a CONSTANT, so that TLC evaluates it once.
EXTENDS ConfigSwitch, TraceConfigSwitchData, Sequences, TLC, QuorumRule

CONSTANTS
    Checkpointed,\* the tasks with checkpoints
    MasterOf(_), \* MasterOf(c): the master configuration c names
    SafeIds,     \* the safe-mode pseudo-configurations (one per phase and Master)
    PhaseOf(_),  \* PhaseOf(c): the phase configuration c belongs to
    ObserversOf(_), \* ObserversOf(c): the observers configuration c names
    MonitorsOf(_), \* MonitorsOf(c): the monitors (master, observers) a Master in c
                 \* counts: c's own; for a SAFE id, those of every configuration of
                 \* its phase (the runtime's SAFE view keeps the one it came from)
    RecoveryOf(_, _, _), \* RecoveryOf(c, r, F): where readmitting r in c with F left failed
                 \* leads (the mission's on_recovery edge, else the walk of F from the
                 \* phase's initial configuration; "SAFE" when that is safe mode)
    MaxHidden,   \* at most this many hidden steps between two lines
    LineageBase, \* a logged version is rank(lineage) * LineageBase + count (keel-verify)
    Relax        \* diagnosis: line Relax need not match its logged variables (0: none)

VARIABLES l, hidden,
    fenced,   \* the nodes the cluster excluded while their process ran (see Fence)
    resigned, \* the Masters that stepped down on their own (see ResignSwitch)
    reported, \* [Nodes -> SUBSET Nodes]: the nodes each node's monitor has declared
              \* (its heartbeat DeclareFailed lines, the Report lines here)
    declaring,\* [Nodes -> SUBSET Nodes]: of them, the declarations each monitor still
              \* holds: withdrawn when the node proved alive (its heartbeat Withdraw
              \* line), forgotten at a readmission (heartbeat Readmit) or at its own
              \* (Rejoin: all but the view's exclusions) and at a restart. A decider's
              \* own declaration counts only while it holds it; another monitor's report
              \* counts as `reported` says (the Master keeps a report two periods)
    said,     \* the nodes that gave their own word since their last readmission: a
              \* restart (its env line) or `excluded` some monitor declared them for, a
              \* Resign, an AskExclusion
    restarts, \* the nodes that restarted (an env Restart line): the only ones a
              \* monitor may declare for a restart (a monitor may learn of a restart
              \* after the readmission that followed it, so this set only grows)
    excluded, \* the nodes some Master's view has excluded so far (it only grows): the
              \* only ones a take-over may find failed already (`was`)
    heldOut,  \* [Nodes -> SUBSET Nodes]: the nodes the ground holds out, as each node took
              \* the ground's commands (its GroundExclude and GroundReadmit lines): a
              \* Master never readmits (nor hands a view to) a node it holds out
    vetting,  \* [Nodes -> [vetted: SUBSET Nodes, backed: <<epoch, seq, SUBSET Nodes>>]]:
              \* rule 5's, per node: the nodes excluded by the last Command it followed
              \* that kept it (Nodes when unknown: after a restart), and its last Backed
              \* line (see BackedComplete)
    written,  \* [Tasks -> Nat]: the highest version of each task a StoreCheckpoint line
              \* of the Storage node logged: on its disk (core/node/driver.hpp, rule 2),
              \* so what a restarted Storage node recovers is never below it (Recovered)
    holding,  \* the nodes whose lease lapsed and that hold their tasks (a Hold line) until
              \* they release them (a Release line), restart, or hold none any more
              \* (spec/Lease.tla): a node that holds takes no step (Steps)
    paused,   \* [Nodes -> SUBSET Tasks]: the tasks the ground paused, as each node took
              \* its pause-task and resume-task (GroundPause and GroundResume lines): a
              \* node takes no step of a task it holds paused (Steps). A restart forgets
              \* them here: the node reads back the pauses it saved, from a state file
              \* that may have gone back, or none at a cold start
    pausesRead, \* the nodes that restarted since: what they hold paused is not known,
              \* so their pause and resume lines are taken as they come
    selfOut,  \* the nodes whose last adopted view (a ReceiveCommand line) excludes
              \* them: each says `excluded` in its heartbeats until it adopts another,
              \* a readmission it never heard or not (OwnWordHeard)
    received, \* what each node said, as another node logged it: <<"Command", from,
              \* epoch, 0>> of a Command received (a ReceiveCommand line: its sender
              \* had saved that epoch), <<"Prepared", p, epoch, seq>> of a member's
              \* Prepared (a ReceiveActivate line's `peers`: p had saved that view)
    prepared  \* <<n, epoch, seq>> of every Prepared a node's Ack line sent (a Master's
              \* of a switch of its own it superseded too)

GroundLines == {"GroundExclude", "GroundReadmit", "GroundPause", "GroundResume"}
\* A monitor's declarations, as its heartbeat lines give them: a declaration (Report), a
\* withdrawal, a Rejoin (its own readmission).
MonitorLines == {"Report", "Withdraw", "Rejoin"}

traceVars == <<l, hidden, fenced, resigned, reported, said, restarts, excluded, heldOut, vetting,
              written, selfOut, paused, holding, declaring, pausesRead, received, prepared>>

NextIs(a) == l <= Len(Log) /\ Log[l].action = a

\* The spec's FlushCheckpoint is the store and its acknowledgement at once; the runtime
\* keeps a task unflushed until the Storage node's ack arrives, so a line the node logs
\* in between (the Master's next command, received first) still lists it: a task it
\* stopped, whose state the Storage node holds at the version the node ran.
Unacked(n) == {t \in Checkpointed : t \notin active'[n] /\ stored'[t] = version'[n][t]}
\* The runtime also holds that acknowledgement until the Storage node's write is durable
\* (core/node/driver.hpp, rule 2), so a Storage node that fails first (a power loss before
\* the write, a full disk) never sends it: the node's final checkpoint stays unflushed in
\* its lines until it adopts a view that excludes the Storage node, then it keeps the
\* state as the task's hand-off (the spec's HiddenHandOff, taken when the Storage node went
\* down). While the Storage node is down, a task the node stopped may be listed so.
Orphaned(n) == IF alive'[Storage] THEN {} ELSE {t \in Checkpointed : t \notin active'[n]}

\* The acting node's logged variables (those the line has) after the step.
Matches(e) ==
    \/ l = Relax
    \/ LET n == e.n IN
       /\ "epoch" \in e.has => epoch'[n] = e.vepoch
       /\ "seq" \in e.has => seq'[n] = e.vseq
       /\ "config" \in e.has => config'[n] = e.vconfig
       /\ "stage" \in e.has => stage'[n] = e.vstage
       /\ "active" \in e.has => active'[n] = e.vactive
       /\ "unflushed" \in e.has => /\ unflushed'[n] \subseteq e.vunflushed
                                   /\ e.vunflushed \ unflushed'[n] \subseteq Unacked(n) \cup Orphaned(n)
       /\ "version" \in e.has =>
            \A t \in DOMAIN e.vversion \cap Checkpointed : version'[n][t] = e.vversion[t]
       /\ "masterStage" \in e.has => masterStage'[n] = e.vmasterStage
       /\ "masterConfig" \in e.has => masterConfig'[n] = e.vmasterConfig
       /\ "masterSeq" \in e.has => masterSeq'[n] = e.vmasterSeq
       /\ "failed" \in e.has => failed'[n] = e.vfailed

\* The nodes that booted late are those declared failed before their first line
\* (TLate, computed from the trace).
TraceInit == Init /\ unbooted = TLate /\ l = 1 /\ hidden = 0 /\ fenced = {} /\ resigned = {}
             /\ reported = [n \in Nodes |-> {}] /\ said = {} /\ restarts = {}
             /\ excluded = {} /\ heldOut = [n \in Nodes |-> {}]
             /\ vetting = [n \in Nodes |-> [vetted |-> {}, backed |-> <<0, 0, {}>>]]
             /\ written = [t \in Tasks |-> 0] /\ selfOut = {} /\ paused = [n \in Nodes |-> {}]
             /\ holding = {} /\ declaring = [n \in Nodes |-> {}] /\ pausesRead = {}
             /\ received = {} /\ prepared = {}

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

\* A command of its own that the Master superseded before delivering it to itself (two
\* declarations in a row: the spec's StartSwitch applies each at once, the runtime's
\* participant takes them from its queue): nothing changes; only the driver's variables
\* compare (the participant's catch up with the next command, Applied).
ParticipantVars == {"epoch", "seq", "config", "stage", "active", "unflushed", "version"}
Superseded(n, e, s, c) ==
    /\ IsMaster(n)
    /\ Command(e, s, c) \in msgs
    /\ ~Newer(e, s, epoch[n], seq[n])
    /\ <<e, s>> # <<epoch[n], seq[n]>>
    /\ UNCHANGED vars

\* Execute steps up to version v (a periodic checkpoint line). Steps stay in the state's
\* lineage: only a start opens a lineage (an Activate line that says `opens`), and only a
\* restore from the Storage node adopts another (an Activate line). A task the node holds
\* paused takes no step (the ground's pause-task: its version stays where it stopped), and
\* neither does any task of a node that holds its tasks (the lease lapsed: Lease.tla).
Steps(n, t, v) ==
    /\ alive[n]
    /\ t \in active[n]
    /\ v >= version[n][t]
    /\ (t \in paused[n] \/ n \in holding) => v = version[n][t]
    /\ v \div LineageBase = version[n][t] \div LineageBase
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
    \* A hand-off kept while the Storage node was excluded (HiddenHandOff), sent to it once
    \* a view includes it again: the version `stored` already stands for.
    ELSE IF v = stored[t] /\ v > 0 THEN UNCHANGED vars
    \* An excluded Storage node (down in the spec) that still runs stores what was sent to
    \* it before (a paused one reads its queue): no one restores from it until it is
    \* readmitted, and `stored` already stands for a newer hand-off (HiddenHandOff). Only
    \* versions their writer reached.
    ELSE IF ~alive[Storage] /\ v < stored[t] THEN v <= version[n][t] /\ UNCHANGED vars
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
\*   the failed (r runs again), into the configuration the decision graph names
\*   (RecoveryOf), which uses no other node it holds failed.
\* A crash line: ConfigSwitch's Crash without its budget (MaxCrashes bounds the models,
\* not what a run may do: a whole-cluster power cycle crashes every node, and each boots
\* again with a Restart line).
CrashLine(n) ==
    /\ alive[n]
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ active' = [active EXCEPT ![n] = {}]
    /\ unflushed' = [unflushed EXCEPT ![n] = {}]
    /\ UNCHANGED <<role, epoch, seq, config, stage, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes, phaseChanges, unbooted>>

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
    \* Not alive[r]: the Master goes by what it heard, and r may have died since (a power
    \* loss just before the line); its restart is seen and decided as any.
    /\ \A x \in Nodes : epoch[x] < e
    /\ c \in ConfigIds
    /\ c = RecoveryOf(masterConfig[m], r, failed[m] \ {r})
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
    \* Not alive[r], as in ReadmitSwitch: r may have lost power just before the line. Its
    \* next boot refuses the hand-over (it names the boot it was meant for), so no
    \* line of r's follows from it; r is seen to restart and taken over from.
    /\ \A x \in Nodes : epoch[x] < e
    /\ c \in ConfigIds
    /\ c = RecoveryOf(masterConfig[m], r, failed[m] \ {r})
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

\* A fenced node's lines (see Fence): it adopts the commands the Master broadcast (which
\* exclude it), stops what it held, sends the final checkpoint of what it stopped (the
\* Storage node's Store line has its own guards), and its lease's and resignation's
\* lines (it may learn of its exclusion only later): steps that change no ConfigSwitch
\* variable (the spec's crashed node does nothing). Any other line of it (an Activate, a
\* checkpoint of a task it runs, an Ack, a Master's step) has no step: an excluded node
\* runs nothing and takes no part.
\* The exclusion-evidence rule (spec/Quorum.tla, rule 1; docs/fault-model.md) at the
\* Master's Exclude line, which logs why it excludes f: the node's own word (`own`:
\* it restarted, resigned or says it is excluded: `said`), or the members `mem` of the view it
\* drives and the declarations `ev` among them that counted. The members are monitors of
\* the configuration it drives that the view has not excluded, and the Master itself (all
\* of them but the nodes that gave their own word: the runtime leaves out a node its
\* monitor holds failed for good; in SAFE, whose base configuration the trace does not
\* name, at most the monitors of the phase's configurations); the
\* declarations are of members other than f, each one a node whose monitor declared f
\* (its heartbeat DeclareFailed line: `reported`); and there are Needed(mem, f) of them,
\* Quorum.tla's count. A Master that excludes on too few declarations, on a non-member's
\* or on one nobody made is caught at its line. The ground's hold is evidence too
\* (`ground`: Ground.tla's GroundExcludeSwitch): the Master excludes a node it holds out
\* (its GroundExclude line), into a configuration that is not SAFE (the Master's walk for
\* all it holds out and its pending declarations is the runtime's; spec/Ground.tla).
\* With heartbeat.tie_grace (TTieGrace > 0, spec/Designate.tla) the ground is one voter more
\* where the view decided in has an even number of monitors it has not excluded (the line's
\* `gm`, held to that count where the trace names the configuration) or the members counted
\* are even (GroundIn); its vote completes the declarations only where `gm` holds, for a
\* decider that held the vote and had declared the node itself tie_grace periods before
\* (`voteOk`, keel-verify's _vote_held).
GroundIn(e) == TTieGrace > 0 /\ (e.gm \/ Cardinality(e.mem) % 2 = 0)
NeededG(e, x) == IF GroundIn(e) THEN Needed(e.mem \cup {"ground"}, x) ELSE Needed(e.mem, x)
GmTruthful(e, c, F) ==
    /\ e.gm => TTieGrace > 0
    /\ c \notin SafeIds => (e.gm <=> (TTieGrace > 0 /\ Cardinality(MonitorsOf(c) \ F) % 2 = 0))

EvidenceSuffices(e) ==
    LET m == e.n
        c == masterConfig[m]
    IN \/ e.own /\ e.f \in said
       \/ e.ground /\ e.f \in heldOut[m] /\ e.c \notin SafeIds
       \/ /\ m \in e.mem
          /\ e.mem \subseteq (MonitorsOf(c) \ failed[m]) \cup {m}
          /\ c \notin SafeIds => ((MonitorsOf(c) \ failed[m]) \ said) \subseteq e.mem
          /\ e.ev \subseteq e.mem \ {e.f}
          /\ \A r \in e.ev : e.f \in reported[r]
          /\ m \in e.ev => e.f \in declaring[m]
          \* and no other reporter's declaration had ended too long before to count (a
          \* report counts two of the decider's periods: keel-verify's _expired_reports)
          /\ DOMAIN e.expired = {}
          /\ GmTruthful(e, c, failed[m])
          /\ e.vote => e.voteOk /\ e.gm /\ m \in e.ev
          /\ Cardinality(e.ev) + (IF e.vote THEN 1 ELSE 0) >= NeededG(e, e.f)

\* The same rule at a take-over (Quorum.tla: a take-over is the Master's exclusion,
\* decided by its successor): its BecomeMaster line logs the failed nodes of the view it
\* takes over (`was`: nodes some view excluded before), the members of that view (`mem`)
\* and, per node it excludes besides,
\* the declarations that counted (`evOf`), and the members it passed over for going by an
\* older epoch (`passed`, NodeProtocol::diverged_members: no members of the take-over).
\* Each such node gave its own word, or Needed(mem,
\* x) members other than x declared it; the members are monitors of the configuration the
\* node went by (in full, but those `was` holds failed or that gave their own word, when it
\* is no SAFE id) and the node itself. A Master that reclaims its view in a newer epoch
\* (Election's reclaim, the same line) excludes no one anew: `was` is its whole failed set.
TakeOverEvidence(e) ==
    LET n == e.n
        c == config[n]
        ev(x) == IF x \in DOMAIN e.evOf THEN e.evOf[x] ELSE {}
    IN /\ e.was \subseteq e.vfailed
       /\ e.was \subseteq excluded
       /\ GmTruthful(e, c, e.was)
       /\ e.voted # {} => e.voteOk /\ e.gm
       /\ e.voted \subseteq e.vfailed \ e.was
       \* A member passed over (it goes by an older epoch than the taker's, which the
       \* election job checks on its own line of the take-over) is no member of the
       \* take-over, and no voter.
       /\ \A p \in e.passed : p # n /\ p \notin e.mem
       \* A member passed over for a newer switch of the taker's epoch (`newer`,
       \* ConfigSwitch::prepared_newer_switch): its Prepared of a switch of that epoch
       \* newer than the taker's view came before (DivergedView.tla's NewerSwitch).
       /\ e.newer \subseteq e.passed
       /\ \A p \in e.newer : \E a \in acks : /\ a.kind = "Prepared" /\ a.from = p
                                             /\ a.epoch = epoch[n] /\ a.seq > seq[n]
       \* A member passed over for never preparing the taker's view (`unprepared`,
       \* NodeProtocol::never_prepared, at seq >= 2): no Prepared of it names that view. The
       \* runtime guesses from what it received; a member whose Prepared it sent were all
       \* lost on the way is rejected here: the guess was wrong (docs/fault-model.md).
       /\ e.unprepared \subseteq e.passed
       /\ e.unprepared # {} => seq[n] >= 2
       /\ \A p \in e.unprepared : AckMsg("Prepared", epoch[n], seq[n], p) \notin acks
       /\ \A x \in e.vfailed \ e.was :
            \/ x \in said
            \/ /\ n \in e.mem
               /\ e.mem \subseteq MonitorsOf(c) \cup {n}
               /\ c \notin SafeIds => (((MonitorsOf(c) \ e.was) \ said) \ e.passed) \subseteq e.mem
               /\ ev(x) \subseteq e.mem \ {x}
               /\ \A r \in ev(x) : x \in reported[r]
               /\ n \in ev(x) => x \in declaring[n]
               /\ x \notin DOMAIN e.expired
               /\ x \in e.voted => n \in ev(x)
               /\ Cardinality(ev(x)) + (IF x \in e.voted THEN 1 ELSE 0) >= NeededG(e, x)

\* A monitor's declaration for the node's own word must be one the node gave: it
\* restarted (an env Restart line of it came before), or some Master's view
\* excludes it or it resigned or asked to be excluded, or the last view it adopted excludes
\* it (`selfOut`: a readmission it never heard; what its heartbeat's `excluded` says), or it left the declarer's view (reason "left": its switch epoch is above the
\* declarer's, or below it: a Master handed a view it never took). A monitor that forged a
\* restart or an exclusion to make a node excludable without evidence is caught at its
\* line. A declaration for a Command refused as no Master's (reason "wrong", fault model
\* 3) never belongs on a trace: every node of a validated run is honest, so it is a check that
\* refused an honest Command (keel-sim's NoHonestRefusalInv), and the line is rejected.
OwnWordHeard(e) ==
    /\ e.kind # "wrong"
    /\ e.kind = "restarted" => e.f \in restarts
    /\ e.kind = "excluded" => e.f \in said \/ e.f \in selfOut \/ \E m \in Nodes : e.f \in failed[m]
    /\ e.kind = "left" => epoch[e.f] # epoch[e.n]

\* Rule 4 (ValueFault.tla's PeersPrepared, docs/fault-model.md): a node takes the
\* Activate of its switch only once every other node its view does not exclude prepared
\* that very view. Its ReceiveActivate line logs the members whose Prepared it holds
\* (`peers`) and the nodes its view excludes (`out`): together every node but itself, and
\* each of the peers acked Prepared in this switch (its Ack line came before). A node that
\* starts on the Master's word alone (mutant no-peer-prepared) is caught at its line when
\* a member's Prepared has not reached it. (A trace of a build before rule 4, whose lines
\* log neither field, is not held to it: `logsPeers`.)
PeersPreparedLine(e) ==
    /\ e.peers \cup e.out \cup {e.n} = Nodes
    /\ \A p \in e.peers : AckMsg("Prepared", epoch[e.n], seq[e.n], p) \in acks

\* Rule 5 (fault model 3): a node follows a Command that adds an exclusion to the view it
\* last checked only when the exclusion is backed at it. Its Backed line, logged before it
\* adopts the view, names for each such node the backing it went by, each held here to
\* the lines before it: a declaration ("reported", by the node itself or another node but
\* the Command's sender: its heartbeat DeclareFailed line, `reported`), the node's own
\* word ("word": `said`), or a member's Prepared of that very switch ("vouched", by a node
\* but the sender: its Ack line). Silence at the receiver and the last monitor's clause
\* are on no line, and are taken as logged. A node that followed an exclusion only the
\* sender declared, or named a backing no line shows, is caught at its Backed line.
BackedLine(e) ==
    \A x \in DOMAIN e.bkKind :
        CASE e.bkKind[x] = "reported" -> e.bkBy[x] # e.from /\ x \in reported[e.bkBy[x]]
          [] e.bkKind[x] = "word" -> x \in said
          [] e.bkKind[x] = "vouched" ->
                 e.bkBy[x] # e.from /\ AckMsg("Prepared", e.epoch, e.seq, e.bkBy[x]) \in acks
          [] e.bkKind[x] \in {"silent", "last"} -> TRUE
          [] OTHER -> FALSE

\* Rule 5, complete: a node that follows another node's Command (its ReceiveCommand
\* line, which names the sender and the view's excluded nodes) that keeps it but excludes
\* nodes beyond those of the last such Command it followed, logged a Backed line of that
\* Command naming each of them just before. A node that followed an exclusion unchecked
\* (the mutant unbacked-exclusions logs no Backed line) is caught at its ReceiveCommand
\* line. What it checks against is unknown after a restart (its saved view): until it
\* follows a Command again, nothing is held to it. (A trace of a build whose
\* ReceiveCommand lines name no sender is not held to it: `logsFrom`.)
BackedComplete(e) ==
    LET added == (e.out \ vetting[e.n].vetted) \ {e.n}
        checked == /\ e.action = "ReceiveCommand"
                   /\ e.logsFrom
                   /\ e.from # e.n
                   /\ e.n \notin e.out
                   /\ added # {}
    IN checked => /\ vetting[e.n].backed[1] = e.epoch
                  /\ vetting[e.n].backed[2] = e.seq
                  /\ added \subseteq vetting[e.n].backed[3]

FencedLine(e) ==
    /\ e.n \in fenced
    /\ e.action \in {"ReceiveCommand", "Deactivate", "FlushFinal", "Lease", "Resign",
                     "Resigned", "AskExclusion"}
    /\ e.action = "ReceiveCommand" => Command(e.epoch, e.seq, e.c) \in msgs
    /\ e.action \in {"Resign", "AskExclusion"} => e.f = e.n
    /\ UNCHANGED vars

\* Safe mode (configuration SAFE). The runtime's SAFE view places the essential tasks of
\* its phase on its Master and nothing else: a configuration like any other, so the
\* mapping gives each (phase, Master) one, SafeIds, whose placement says exactly that
\* (ConfigSwitch takes the configurations and the decision graph as constants: SafeIds
\* are more of them, and OnFailure leads there where the runtime goes to SAFE: a SAFE
\* edge, no edge for a node that matters, an edge to a configuration another node is
\* the master of). Entering SAFE is then the spec's Exclude (or a take-over into
\* the SAFE configuration of the new Master); leaving it is a readmission (ReadmitSwitch,
\* into a configuration of the Master's own that uses no other node it holds failed) or
\* a ground command (GroundRecoverySwitch).
\*
\* The runtime starts a switch at every declaration, also when the decision graph keeps
\* the configuration (a node that matters to nothing, a failure in SAFE): a switch to
\* the configuration the cluster is in. That is the spec's Exclude with OnFailure
\* leading to a copy of the configuration under another id (same placement, same
\* master): a ConfigSwitch behaviour up to the copy's name; the switch moves no task.
ExcludeSame(m, f) ==
    /\ IsMaster(m)
    /\ masterSeq[m] > 0
    /\ ~alive[f]
    /\ f \notin failed[m]
    /\ OnFailure(masterConfig[m], f) = masterConfig[m]
    /\ failed' = [failed EXCEPT ![m] = @ \cup {f}]
    /\ StartSwitch(m, masterConfig[m])
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, acks,
                   crashes, phaseChanges, unbooted>>

\* A ground command (GroundRecovery line) leaves SAFE for c, as the runtime checks it: the
\* Master, between switches, in SAFE; c a configuration of the phase SAFE was entered in,
\* whose master is this Master and whose observers and task hosts it holds none failed.
\* A planned switch: the spec's RequestPhase with c among OnPhase(SAFE), without the
\* models' budget of phase changes (a bound on the state space no property reads).
GroundRecoveryAllowed(m, c) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Idle"
    /\ masterSeq[m] > 0
    /\ masterConfig[m] \in SafeIds
    /\ c \in ConfigIds \ SafeIds
    /\ PhaseOf(c) = PhaseOf(masterConfig[m])
    /\ MasterOf(c) = m
    /\ \A x \in ObserversOf(c) : x \notin failed[m]
    /\ \A t \in Tasks : Placement(c, t) \notin failed[m]

GroundRecoverySwitch(m, c) ==
    /\ GroundRecoveryAllowed(m, c)
    /\ StartSwitch(m, c)
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted>>

\* Node n, activating task t while the Storage node is excluded, asks the other members
\* for the state handed off (its AskHolders line): no variable changes; the Activate line
\* that follows must start from `stored` (the newest hand-off, HiddenHandOff), as from
\* the Storage node.
AskHolders(n, t) ==
    /\ alive[n]
    /\ ~alive[Storage]
    /\ stage[n] = "Activating"
    /\ Placement(config[n], t) = n
    /\ t \notin active[n]
    /\ UNCHANGED vars

\* The runtime's report that t's newest state is out of reach (its StateOutOfReach line):
\* the Storage node is excluded and the last host's hand-off is gone with it (crashed,
\* excluded), so n starts t from v, what the members still hold. ConfigSwitch has no
\* such step: its Storage node never fails, and an unavoidable loss is outside its fault
\* model. The trace takes it only on the runtime's word and only when it is a loss that
\* cannot be avoided: the Storage node down, and no running member holding a newer state
\* of t (a node that ran t and stopped it keeps its state until it runs t again: a
\* restore below it is caught here). `stored` then says what the cluster has (v): the
\* spec's invariants hold from there on.
StateOutOfReach(n, t, v) ==
    /\ alive[n]
    /\ ~alive[Storage]
    /\ stage[n] = "Activating"
    /\ Placement(config[n], t) = n
    /\ t \notin active[n]
    /\ \A h \in Nodes : alive[h] /\ t \notin active[h] => version[h][t] <= v
    /\ stored' = [stored EXCEPT ![t] = v]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active, unflushed, version,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* Node n starts task t without the Storage node, from the state `stored` stands for (the
\* newest hand-off, HiddenHandOff, or what StateOutOfReach left), and opens a new lineage
\* of it (spec/Handoff.tla, "Lineages"): the task runs at v, the same count in a lineage
\* newer than that of every state of t in the cluster (versions are mapped so that
\* lineage rank * base + count orders them: keel-verify's switch.py). ConfigSwitch's
\* Activate, but for the version, which the lineage renames.
OpenLineage(n, t, v) ==
    /\ alive[n]
    /\ ~alive[Storage]
    /\ stage[n] = "Activating"
    /\ Placement(config[n], t) = n
    /\ t \notin active[n]
    /\ t \in Checkpointed
    /\ v > stored[t]
    /\ \A h \in Nodes : version[h][t] < v
    /\ active' = [active EXCEPT ![n] = @ \cup {t}]
    /\ version' = [version EXCEPT ![n][t] = v]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, unflushed, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

\* Resignation. A Master whose lease lapsed steps down (its Resign line): it drives no
\* switch any more, stops its tasks and flushes their final checkpoints, and its word
\* lets its successor exclude it and take over (the take-over fences it, see Fence). A
\* Worker or Observer (or a Master handed the view, before its boot switch:
\* AsksExclusion) asks the Master to exclude it (its AskExclusion line: nothing
\* changes; it holds its tasks, a lease line, and the Master's Exclude of it fences
\* it). A node speaks only for itself: the line's node is the one resigning.
\* In ConfigSwitch a node stops its tasks in a switch or by crashing. A resignation is a
\* crash announced in advance: the node stops its tasks (Deactivate, without a switch's
\* stage or placement), flushes them (FlushCheckpoint: `stored` gets the versions it
\* ran, which the spec's invariants check against every other node), and is excluded
\* as a crashed node is (Fence). Stopping a task cannot put it on two nodes, and a flush
\* stores the version of the one node that ran it: the invariants are checked after
\* every step. From the Resign line on, the node may only stop and flush
\* (ResignedLine): a resigned Master that drives a switch, acks or activates is caught.
\* Who may ask: a node that is not the Master; and a Master handed the view that has not
\* made its boot switch (masterSeq 0), which gives it up when it cannot get every voter's
\* acknowledgement in time (NodeProtocol::enforce_lease, hand_overs_given_up): it has
\* commanded nothing, and the first Observer takes over on its word (fencing it: Fence).
AsksExclusion(n) == ~IsMaster(n) \/ masterSeq[n] = 0

ResignSwitch(n, who) ==
    /\ who = n
    /\ IsMaster(n)
    /\ stage' = [stage EXCEPT ![n] = "Stable"]
    /\ UNCHANGED <<alive, role, epoch, seq, config, active, unflushed, version, stored,
                   masterStage, masterConfig, masterSeq, failed, msgs, acks, crashes,
                   phaseChanges, unbooted>>

ResignDeactivate(n, t) ==
    /\ alive[n]
    /\ t \in active[n]
    /\ active' = [active EXCEPT ![n] = @ \ {t}]
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \cup {t}]
    /\ UNCHANGED <<alive, role, epoch, seq, config, stage, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes, phaseChanges,
                   unbooted>>

\* Its Resigned line: every final checkpoint stored ("flushed"), or, past the deadline,
\* the rest abandoned (lost, as in a crash).
ResignedLine(e) ==
    /\ alive[e.n]
    /\ CASE e.action = "Deactivate" -> ResignDeactivate(e.n, e.t) /\ Matches(e)
         [] e.action = "FlushFinal" ->
                /\ e.t \notin active[e.n]
                /\ version[e.n][e.t] = e.version
                /\ UNCHANGED vars
                /\ Matches(e)
         [] e.action = "Lease" -> UNCHANGED vars
         [] e.action = "Resigned" ->
                /\ IF e.kind = "flushed"
                   THEN unflushed[e.n] \cap Checkpointed = {} /\ UNCHANGED vars
                   ELSE /\ unflushed' = [unflushed EXCEPT ![e.n] = {}]
                        /\ UNCHANGED <<alive, role, epoch, seq, config, stage, active,
                                       version, stored, masterStage, masterConfig,
                                       masterSeq, failed, msgs, acks, crashes,
                                       phaseChanges, unbooted>>
                /\ Matches([e EXCEPT !.has = @ \ {"unflushed"}])
         [] OTHER -> FALSE

LineStep ==
    /\ l <= Len(Log)
    /\ LET e == Log[l] IN
        /\ IF e.n \in fenced /\ e.action \notin {"Crash", "Restart", "Store", "Recovered", "Restored", "HeardPrepared", "Backed", "Refused"} \cup MonitorLines \cup GroundLines
              /\ ~(e.action = "TakeOver" /\ e.warm)
           THEN FencedLine(e)
           ELSE IF e.n \in resigned /\ e.action \notin {"Crash", "Restart", "Store", "Recovered", "Restored", "HeardPrepared", "Backed", "Refused"} \cup MonitorLines \cup GroundLines
           THEN ResignedLine(e) ELSE
           CASE e.action = "Exclude" ->
                    /\ IF e.c \in ConfigIds THEN OnFailure(masterConfig[e.n], e.f) = e.c
                                            ELSE FALSE
                    /\ EvidenceSuffices(e)
                    /\ IF e.c = masterConfig[e.n] THEN ExcludeSame(e.n, e.f)
                                                 ELSE Exclude(e.n, e.f)
                    /\ Matches(e)
             [] e.action = "GroundRecovery" -> GroundRecoverySwitch(e.n, e.c) /\ Matches(e)
             \* A refused ground command (RefuseGroundCommand, "?" for no configuration)
             \* changes nothing, and is refused only when GroundRecoverySwitch would not
             \* be taken: refusing a command the spec allows is caught.
             [] e.action = "RefuseGround" ->
                    /\ ~GroundRecoveryAllowed(e.n, e.c)
                    /\ UNCHANGED vars
             [] e.action = "AskHolders" -> AskHolders(e.n, e.t) /\ Matches(e)
             [] e.action = "StateOutOfReach" -> StateOutOfReach(e.n, e.t, e.version) /\ Matches(e)
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
             [] e.action = "TakeOver" ->
                    \* Not into safe mode where the nodes' placer places the essential
                    \* tasks with this node Master, from the online configuration it ran
                    \* (failure_target; keel-verify asks keel-place: `placerPlaces`).
                    /\ ~e.placerPlaces
                    /\ TakeOver(e.n, e.vepoch, e.c, e.vfailed) /\ TakeOverEvidence(e) /\ Matches(e)
             [] e.action = "BroadcastCommand" ->
                    /\ Command(e.epoch, e.seq, e.c) \in msgs
                    /\ masterStage[e.n] = "Preparing"
                    /\ UNCHANGED vars
                    /\ Matches(e)
             \* A Command whose view excludes its receiver is a fenced node's line
             \* (FencedLine): the node was fenced at its exclusion, or is now (HiddenCrash).
             [] e.action = "ReceiveCommand" ->
                 /\ e.n \notin e.out
                 /\ \/ Applied(e.n, e.epoch, e.seq, e.c) /\ Matches(e)
                    \/ Superseded(e.n, e.epoch, e.seq, e.c)
                       /\ Matches([e EXCEPT !.has = @ \ ParticipantVars])
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
             \* A restarted Storage node's checkpoint of t as read back from its disk: never
             \* below a StoreCheckpoint line it logged (that line stood for a durable write).
             [] e.action = "Recovered" -> e.version >= written[e.t] /\ UNCHANGED vars
             \* A restarted node's state as read back from its disk: never older than
             \* what it said that others logged (Durable.tla's SaidDurableInv: the node's
             \* state is durable before a message that depends on it leaves; a driver
             \* that sends first loses, at a power loss, a state it said). Its epoch
             \* (`saved`) is at least that of any Command of its received; its view at
             \* least that of any Prepared of its a member held. (A Master commands a
             \* view before it holds it itself: its Command binds its epoch only.)
             \* A member's Prepared received: one the member acked (an Ack step of it, in
             \* `acks`); nothing changes but `received`.
             [] e.action = "HeardPrepared" ->
                    /\ <<e.from, e.epoch, e.seq>> \in prepared
                    /\ UNCHANGED vars
             \* A restart that read back a state that went back on purpose (keel-sim's
             \* rolled-back restart: a lost write, a restored file) is the environment's
             \* doing: held to what the node says from then on only.
             [] e.action = "Restored" ->
                    /\ \A r \in received : r[2] = e.n /\ ~e.rolledBack =>
                          IF r[1] = "Command" THEN r[3] <= e.saved
                          ELSE r[3] < e.epoch \/ (r[3] = e.epoch /\ r[4] <= e.seq)
                    /\ UNCHANGED vars
             [] e.action = "Ack" ->
                    \/ AckLine(e.n, e.kind) /\ Matches(e)
                    \* The Master's participant acks a switch of its own it has superseded
                    \* (see Superseded): an ack no switch waits for; nothing changes.
                    \/ /\ IsMaster(e.n)
                       /\ "seq" \in e.has /\ "epoch" \in e.has
                       /\ Newer(epoch[e.n], seq[e.n], e.vepoch, e.vseq)
                       /\ UNCHANGED vars
                       /\ Matches([e EXCEPT !.has = @ \ ParticipantVars])
             [] e.action = "BroadcastActivate" -> BroadcastActivate(e.n) /\ Matches(e)
             [] e.action = "ReceiveActivate" ->
                    /\ ReceiveActivate(e.n, ActivateMsg(e.epoch, e.seq, config[e.n]))
                    /\ e.logsPeers => PeersPreparedLine(e)
                    /\ Matches(e)
             [] e.action = "Activate" ->
                    /\ e.t \in Checkpointed => stored[e.t] = e.version
                    /\ IF e.opens THEN OpenLineage(e.n, e.t, e.opened) ELSE Activate(e.n, e.t)
                    /\ Matches(e)
             [] e.action = "CompleteSwitch" -> CompleteSwitch(e.n) /\ Matches(e)
             [] e.action = "Lease" -> alive[e.n] /\ UNCHANGED vars /\ Matches(e)
             \* A fenced node's process dies: the spec's node is down already.
             [] e.action = "Crash" -> IF e.n \in fenced THEN UNCHANGED vars ELSE CrashLine(e.n)
             [] e.action = "Restart" -> RestartNode(e.n)
             [] e.action = "Resign" -> ResignSwitch(e.n, e.f) /\ Matches(e)
             [] e.action = "AskExclusion" ->
                    alive[e.n] /\ AsksExclusion(e.n) /\ e.f = e.n /\ UNCHANGED vars /\ Matches(e)
             [] e.action = "Readmit" ->
                    e.f \notin heldOut[e.n] /\ ReadmitSwitch(e.n, e.f, e.vepoch, e.c) /\ Matches(e)
             [] e.action = "HandOver" ->
                    e.f \notin heldOut[e.n] /\ HandOverSwitch(e.n, e.f, e.epoch, e.c) /\ Matches(e)
             \* The ground's exclude and readmit (core/node/ground.hpp) as a node took them:
             \* they change no switch variable, only what the node holds out.
             [] e.action \in {"GroundExclude", "GroundReadmit"} -> UNCHANGED vars
             \* The ground's pause-task and resume-task as a node took them: a task it does
             \* not hold paused already, one it does. They change no switch variable.
             [] e.action = "GroundPause" ->
                    (e.t \notin paused[e.n] \/ e.n \in pausesRead) /\ UNCHANGED vars
             [] e.action = "GroundResume" ->
                    (e.t \in paused[e.n] \/ e.n \in pausesRead) /\ UNCHANGED vars
             [] e.action = "Report" -> OwnWordHeard(e) /\ UNCHANGED vars
             \* They change no switch variable, only what the monitor still holds declared.
             [] e.action \in {"Withdraw", "Rejoin"} -> UNCHANGED vars
             [] e.action = "Backed" -> BackedLine(e) /\ UNCHANGED vars
             \* Rules 1 to 3 (fault model 3): a node that refused a message as malformed,
             \* unauthorized or no Master's, or heard a member prepare another view under
             \* its view's id, logs a Refused line. Every node of a validated run is honest,
             \* so the line is a check wrong about an honest message: rejected.
             [] e.action = "Refused" -> FALSE
             [] OTHER -> FALSE
        /\ BackedComplete(e)
        /\ l' = l + 1
        /\ hidden' = 0
        /\ vetting' = CASE e.action = "ReceiveCommand" /\ e.logsFrom /\ e.n \notin e.out ->
                             [vetting EXCEPT ![e.n].vetted = e.out]
                        [] e.action = "Restart" -> [vetting EXCEPT ![e.n].vetted = Nodes]
                        [] e.action = "Backed" ->
                             [vetting EXCEPT ![e.n].backed = <<e.epoch, e.seq, DOMAIN e.bkKind>>]
                        [] OTHER -> vetting
        /\ fenced' = IF e.action = "Restart" THEN fenced \ {e.n} ELSE fenced
        /\ resigned' = CASE e.action = "Resign" /\ e.n \notin fenced -> resigned \cup {e.n}
                          [] e.action = "Restart" -> resigned \ {e.n}
                          [] OTHER -> resigned
        /\ reported' = IF e.action = "Report" THEN [reported EXCEPT ![e.n] = @ \cup {e.f}]
                                              ELSE reported
        /\ declaring' = CASE e.action = "Report" -> [declaring EXCEPT ![e.n] = @ \cup {e.f}]
                          [] e.action = "Withdraw" -> [declaring EXCEPT ![e.n] = @ \ {e.f}]
                          [] e.action = "Rejoin" -> [declaring EXCEPT ![e.n] = @ \cap e.vfailed]
                          [] e.action = "Restart" -> [declaring EXCEPT ![e.n] = {}]
                          [] OTHER -> declaring
        /\ said' = CASE e.action = "Report" /\ e.kind # "missed" -> said \cup {e.f}
                      [] e.action \in {"Resign", "AskExclusion"} -> said \cup {e.n}
                      \* A restart is the node's word too: a node that hears its new boot
                      \* backs its exclusion by it, monitor or not (no Report line then).
                      [] e.action = "Restart" -> said \cup {e.n}
                      [] e.action \in {"Readmit", "HandOver"} -> said \ {e.f}
                      [] OTHER -> said
        /\ restarts' = IF e.action = "Restart" THEN restarts \cup {e.n} ELSE restarts
        /\ excluded' = excluded \cup UNION {failed'[x] : x \in Nodes}
        /\ heldOut' = CASE e.action = "GroundExclude" -> [heldOut EXCEPT ![e.n] = @ \cup {e.f}]
                        [] e.action = "GroundReadmit" -> [heldOut EXCEPT ![e.n] = @ \ {e.f}]
                        [] OTHER -> heldOut
        \* The lease's lines (`kind`: Hold, Release or LeaseLapsed). A node whose tasks all
        \* left it holds nothing: what a later Command activates there starts only at its
        \* Release (logged when it holds some), so nothing steps meanwhile either way.
        /\ holding' = CASE e.action = "Lease" /\ e.kind = "Hold" -> holding \cup {e.n}
                        [] e.action = "Lease" /\ e.kind = "Release" -> holding \ {e.n}
                        [] e.action = "Restart" -> holding \ {e.n}
                        [] active'[e.n] = {} -> holding \ {e.n}
                        [] OTHER -> holding
        /\ paused' = CASE e.action = "GroundPause" -> [paused EXCEPT ![e.n] = @ \cup {e.t}]
                       [] e.action = "GroundResume" -> [paused EXCEPT ![e.n] = @ \ {e.t}]
                       [] e.action = "Restart" -> [paused EXCEPT ![e.n] = {}]
                       [] OTHER -> paused
        /\ pausesRead' = IF e.action = "Restart" THEN pausesRead \cup {e.n} ELSE pausesRead
        /\ written' = IF e.action = "Store" /\ e.version > written[e.t]
                      THEN [written EXCEPT ![e.t] = e.version] ELSE written
        /\ selfOut' = CASE e.action = "ReceiveCommand" /\ e.logsFrom ->
                             IF e.n \in e.out THEN selfOut \cup {e.n} ELSE selfOut \ {e.n}
                        [] e.action = "Restart" -> selfOut \ {e.n}
                        [] OTHER -> selfOut
        /\ received' = CASE e.action = "ReceiveCommand" /\ e.logsFrom /\ e.from # e.n ->
                             received \cup {<<"Command", e.from, e.epoch, 0>>}
                        [] e.action = "ReceiveActivate" /\ e.logsPeers ->
                             received \cup {<<"Prepared", p, e.epoch, e.seq>> : p \in e.peers \ {e.n}}
                        [] e.action = "HeardPrepared" ->
                             received \cup {<<"Prepared", e.from, e.epoch, e.seq>>}
                        [] e.action = "Restored" /\ e.rolledBack -> {r \in received : r[2] # e.n}
                        [] OTHER -> received
        /\ prepared' = IF e.action = "Ack" /\ e.kind = "Prepared" /\ "seq" \in e.has /\ "epoch" \in e.has
                       THEN prepared \cup {<<e.n, e.vepoch, e.vseq>>} ELSE prepared

\* A task without checkpoints has nothing to flush: its "final checkpoint" is at once.
\* A final checkpoint of a version the Storage node already holds (a periodic write got
\* there first) changes nothing there, so the Storage node logs nothing.
HiddenFlush(n, t) ==
    /\ t \in unflushed[n]
    /\ t \in Checkpointed => stored[t] = version[n][t]
    /\ FlushCheckpoint(n, t)
    /\ UNCHANGED <<fenced, resigned, reported, said, restarts, excluded, heldOut, vetting, written, selfOut, paused, holding, declaring, pausesRead, received, prepared>>

\* A node the cluster excludes just before the trace's line that excludes it (the Master's
\* Exclude of it, or a take-over that holds it failed or replaces it as Master),
\* without a crash line: a crash the trace does not log (a real cluster's kill), or a node
\* whose process runs on, cut off by a partition or a one-way block, deaf, paused, or
\* resigned. Either way the spec's Crash, but for the crash budget (an environment bound
\* of the models that no property reads): the node's tasks stop and what it had not
\* flushed is lost. For a running process this is Lease.tla's guarantee (an excluded node
\* that is alive has stopped before the cluster decides against it: the lease lapsed, or
\* it gave its word) and the runtime's (a node whose view excludes it stops what it held,
\* flushes nothing and hands off nothing: the lineage it held is abandoned). From then on
\* its lines are FencedLine steps; it comes back by a restart (its env line) or a
\* readmission (HiddenRevive).
Fence(x) ==
    /\ alive[x]
    /\ alive' = [alive EXCEPT ![x] = FALSE]
    /\ active' = [active EXCEPT ![x] = {}]
    /\ unflushed' = [unflushed EXCEPT ![x] = {}]
    /\ fenced' = fenced \cup {x}
    /\ UNCHANGED <<resigned, reported, said, restarts, excluded, heldOut, vetting, written, selfOut, paused, holding, declaring, pausesRead, received, prepared>>
    /\ UNCHANGED <<role, epoch, seq, config, stage, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes, phaseChanges,
                   unbooted>>

HiddenCrash(x) ==
    /\ l <= Len(Log)
    /\ \/ Log[l].action = "Exclude" /\ Log[l].f = x
       \/ Log[l].action = "TakeOver" /\ x # Log[l].n
          /\ (role[x] = "Master" \/ x \in Log[l].vfailed)
       \* A node that learns of its exclusion from the Command itself: it booted (late,
       \* or restarted) after the Exclude or take-over that excluded it, so no Master's
       \* line fenced it; from this Command on it runs nothing (prototype3 seed 71, a
       \* Storage node that booted into a view that excluded it).
       \/ Log[l].action = "ReceiveCommand" /\ Log[l].n = x /\ x \in Log[l].out
    /\ Fence(x)

\* A fenced node that the Master readmits (its Readmit or HandOver line) is a restarted
\* node: RestartNode (nothing active, Stable, a Worker, its persisted view) and Boot, just
\* before the line, as for a node that restarted and was readmitted (spec/Rejoin.tla).
\* So is a fenced node that warm-boots (its take-over line, `warm`: every node idle, a
\* fenced one too, MasterElection's WarmBoot, which the election job checks): it comes
\* back as the Master of a view that excludes no one.
HiddenRevive(x) ==
    /\ l <= Len(Log)
    /\ \/ Log[l].action \in {"Readmit", "HandOver"} /\ Log[l].f = x
       \/ Log[l].action = "TakeOver" /\ Log[l].warm /\ Log[l].n = x
    /\ x \in fenced
    /\ alive' = [alive EXCEPT ![x] = TRUE]
    /\ active' = [active EXCEPT ![x] = {}]
    /\ unflushed' = [unflushed EXCEPT ![x] = {}]
    /\ version' = [version EXCEPT ![x] = [t \in Tasks |-> 0]]
    /\ stage' = [stage EXCEPT ![x] = "Stable"]
    /\ role' = [role EXCEPT ![x] = "Worker"]
    /\ masterStage' = [masterStage EXCEPT ![x] = "Idle"]
    /\ fenced' = fenced \ {x}
    /\ resigned' = resigned \ {x}
    /\ vetting' = [vetting EXCEPT ![x].vetted = Nodes]
    /\ UNCHANGED <<reported, said, restarts, excluded, heldOut, written, selfOut, paused, holding, declaring, pausesRead, received, prepared>>
    /\ UNCHANGED <<epoch, seq, config, stored, masterConfig, masterSeq, failed, msgs, acks,
                   crashes, phaseChanges, unbooted>>

\* A node whose process started late boots just before its first line (Init chose it
\* among the unbooted nodes; a node declared before it booted is one of them).
HiddenBoot(x) ==
    /\ l <= Len(Log)
    /\ Log[l].n = x
    /\ Boot(x)
    /\ UNCHANGED <<fenced, resigned, reported, said, restarts, excluded, heldOut, vetting, written, selfOut, paused, holding, declaring, pausesRead, received, prepared>>

\* The Storage node excluded (down in the spec: crashed, or fenced: see Fence), a
\* deactivated task's final state stays with the node that ran it (the runtime's hand-off)
\* and is what the task's next host gathers from the holders (AskHolders). `stored` is the
\* newest state handed off, wherever it is kept: this is the spec's FlushCheckpoint, the
\* holder standing in for the Storage node.
HiddenHandOff(n, t) ==
    /\ ~alive[Storage]
    /\ t \in Checkpointed
    /\ FlushCheckpoint(n, t)
    /\ UNCHANGED <<fenced, resigned, reported, said, restarts, excluded, heldOut, vetting, written, selfOut, paused, holding, declaring, pausesRead, received, prepared>>

\* A running task's steps are logged only through its checkpoints (FlushCheckpoint lines,
\* Steps), and it writes none while the node's view excludes the Storage node: the
\* spec's Execute steps up to the version the node's next line logs (never down, only a
\* task the node runs).
HiddenSteps(n, t) ==
    /\ l <= Len(Log)
    /\ Log[l].n = n
    /\ "version" \in Log[l].has
    /\ t \in DOMAIN Log[l].vversion \cap Checkpointed
    /\ Log[l].vversion[t] > version[n][t]
    /\ Steps(n, t, Log[l].vversion[t])
    /\ UNCHANGED <<fenced, resigned, reported, said, restarts, excluded, heldOut, vetting, written, selfOut, paused, holding, declaring, pausesRead, received, prepared>>

HiddenStep ==
    /\ hidden < MaxHidden
    /\ \/ \E n \in Nodes, t \in Tasks : HiddenFlush(n, t)
       \/ \E n \in Nodes, t \in Tasks : HiddenHandOff(n, t)
       \/ \E n \in Nodes, t \in Tasks : HiddenSteps(n, t)
       \/ \E x \in Nodes : HiddenCrash(x)
       \/ \E x \in Nodes : HiddenBoot(x)
       \/ \E x \in Nodes : HiddenRevive(x)
    /\ hidden' = hidden + 1
    /\ UNCHANGED l

\* The spec's safety invariants hold along the trace: a line whose step would break one
\* is not explained (the trace stops there, a mismatch at that line).
TraceNext == (LineStep \/ HiddenStep) /\ NoDoubleActivationInv' /\ ResumeLatestCheckpointInv'

TraceNotAccepted == l <= Len(Log)
\* The same verdict without a counter-example: TLC prints the marker when a state past
\* the last line is reachable, and goes on (printing a behaviour as long as the trace
\* costs more than checking it).
TraceExplained == l <= Len(Log) \/ PrintT("keel-trace: every line explained")
NotPastRelax == l <= Relax
=============================================================================
