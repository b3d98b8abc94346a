------------------------------- MODULE Ground -------------------------------
(***************************************************************************)
(* The ground's commands (docs/operations.md, "The commands"; fault model  *)
(* 2, item 3): `recover CONFIG`, `exclude NODE`, `readmit NODE`, and the   *)
(* rule that a Master never readmits, nor hands its view to, a node it     *)
(* holds out. The module extends ConfigSwitch (its two-phase switch, its   *)
(* properties) with the ground, the runtime's take-over and reintegration  *)
(* into the graph's configurations (TraceConfigSwitch's TakeOver,          *)
(* ReadmitSwitch and HandOverSwitch, here as steps of a spec), and a       *)
(* resignation on the ground's word.                                       *)
(*                                                                         *)
(* Configurations. A configuration id names a master (MasterOf), observers *)
(* (ObserversOf), a phase (PhaseOf) and the hosts of its tasks (Placement);*)
(* SafeIds are safe mode, one per phase and Master (its essential tasks on *)
(* the Master). A view is a configuration and a failed set: the Master's   *)
(* is `failed`; each node's is that of the switch it adopted (`views`      *)
(* records the failed set each switch was started with). The decision      *)
(* graph is OnFailure; Walk follows its edges for a sequence of nodes      *)
(* (Topology::walk); RecoveryOf(c, r, F) is where readmitting r leads      *)
(* (Topology::recovery_target).                                            *)
(*                                                                         *)
(* The ground's commands reach every running node at once (the uplink;     *)
(* core/node/ground.hpp checked the signature). The acting Master judges   *)
(* an exclusion on its own view, the one the cluster switches from:        *)
(*  - GroundRecovery(m, c): Master m, between switches, in SAFE, switches  *)
(*    to c, a configuration of the phase SAFE was entered in, whose master *)
(*    is m and which places nothing (observers, tasks) on a node m holds   *)
(*    failed; the failed set is kept (ReconfigurationManager::             *)
(*    ground_recovery; TraceConfigSwitch's GroundRecoveryAllowed).         *)
(*    Anything else is refused: RefuseGroundCommand, nothing changes       *)
(*    (NodeProtocol::request_recovery: RecoveryRefused is its reasons).    *)
(*  - GroundExclude(x): every node whose check passes holds x out          *)
(*    (heldOut). The check (NodeProtocol::ground_exclude): unless x is     *)
(*    failed in the node's view or the view is SAFE, the walk of the graph *)
(*    from the view's configuration for the nodes it holds out that the    *)
(*    view has not excluded, the nodes its monitor declared failed that    *)
(*    the view has not excluded yet (Pending: a real failure under way)    *)
(*    and x must not lead to SAFE. A node whose check fails changes        *)
(*    nothing. x does not resign, unless it is the acting Master and its   *)
(*    own check passes: it steps down (its own view is the authoritative   *)
(*    one), and its successor takes over.                                  *)
(*  - GroundExcludeSwitch(m, x): Master m, between switches, takes a node  *)
(*    it holds out that its view has not excluded: when the walk from its  *)
(*    view for all of them and its Pending nodes stays out of SAFE, it     *)
(*    starts the exclusion switch of x (the graph's failure edge, as       *)
(*    ConfigSwitch's Exclude, the ground's hold the evidence: the trace    *)
(*    line `Exclude` with `ground`); x, which the view excludes, stops as  *)
(*    any excluded node. Otherwise x stays held out and not excluded (the  *)
(*    Master tries again after its next switch).                           *)
(*  - GroundReadmit(x): every node that holds x out lets it back; one that *)
(*    does not refuses it (nothing changes).                               *)
(*  - Readmit(m, r) and HandOver(m, r): Master m, between switches, takes  *)
(*    r back (r resigned or was excluded on the ground's word, and is      *)
(*    heard: the `out` nodes) into RecoveryOf's configuration, in an epoch *)
(*    above every epoch: its own (ReadmitSwitch) or, when r is that        *)
(*    configuration's master, r's (HandOverSwitch; r then makes its boot   *)
(*    switch). Never a node m holds out (NodeProtocol::                    *)
(*    consider_readmission).                                               *)
(*  - TakeOver(n): the Master and every node ahead of n in Priority are    *)
(*    down; n, not out, takes over into the graph's configuration for them *)
(*    from its view, in an epoch above every epoch.                        *)
(*                                                                         *)
(* Properties, besides ConfigSwitch's NoDoubleActivationInv and            *)
(* ResumeLatestCheckpointInv:                                              *)
(*  - ValidUnderFailedInv: a Master's configuration places nothing         *)
(*    (observers, tasks) on a node it holds failed, and is of its own      *)
(*    (DrivesOwnConfigInv) and of the mission's phase (PhaseKeptInv);      *)
(*  - SafeOnlyByFailureInv: the cluster is in SAFE only when a node its    *)
(*    Master holds failed crashed: the ground takes no node out beyond the *)
(*    mission's tolerance;                                                 *)
(*  - SafeByFailuresInv (MCGroundWalk: every failure before the ground's   *)
(*    exclusions and known to the node deciding each): the cluster is in   *)
(*    SAFE only if the walk of its crashed nodes alone, without the        *)
(*    ground's holds, reaches SAFE: the walks count the failures under way;*)
(*  - NoReadmitHeldProp, NoHandOverHeldProp: a node a running Master holds *)
(*    out is never readmitted nor handed the mastership by it, until the   *)
(*    ground readmits it.                                                  *)
(*                                                                         *)
(* What TLC shows (MCGround.tla; one worker): every property holds with    *)
(* no precondition on what the ground sends. The rule the runtime had      *)
(* before, every node judging on its own view and x resigning on its own   *)
(* check, took the cluster into SAFE with no node crashed; it is kept as   *)
(* mutants: mutants/GroundExcludeAnyView.tla (a node in an older view      *)
(* accepts its own exclusion, which the Master refuses, and resigns: the   *)
(* Master excludes it on its word) and mutants/GroundReadmitPending.tla    *)
(* (a readmit lifts the hold of a node whose resignation is under way, so  *)
(* the next exclude's walk leaves it out). MCGroundWalk.tla, a mission in  *)
(* which a hold is safe alone but not with a crash, shows the walks needed:*)
(* without the Master's walk, or the Pending nodes in it or in the acting  *)
(* Master's check, a crash and the ground's hold take the cluster into     *)
(* SAFE where the crash alone does not (SafeByFailuresInv).                *)
(*                                                                         *)
(* Abstractions: failures are crashes (crashed nodes stay down); a node    *)
(* that resigns or that the view excludes stops at once (a Master's        *)
(* resignation flushes first: Lease.tla, LeaseStepDown.tla; an excluded    *)
(* node has stopped before the cluster decides against it: Lease.tla);     *)
(* a monitor declares a node that is down, at any time after it went down  *)
(* (declared); evidence, leases and the readmission's hearing are other    *)
(* specs' (Exclusion, Quorum, Lease, Rejoin), taken as one step; epochs    *)
(* are not owned (MasterElection).                                         *)
(***************************************************************************)
EXTENDS ConfigSwitch, TLC

CONSTANTS
    SafeIds,            \* the safe-mode configurations, one per phase and Master
    MasterOf(_),        \* MasterOf(c): the master configuration c names
    ObserversOf(_),     \* ObserversOf(c): the observers configuration c names
    PhaseOf(_),         \* PhaseOf(c): the phase configuration c belongs to
    RecoveryOf(_, _, _),\* RecoveryOf(c, r, F): where readmitting r in c with F failed leads
    MaxGround           \* at most this many accepted ground exclusions and readmissions

ASSUME GroundAssumption ==
    /\ SafeIds \subseteq ConfigIds
    /\ InitialConfig \notin SafeIds
    /\ \A c \in ConfigIds : MasterOf(c) \in Nodes /\ ObserversOf(c) \subseteq Nodes
    /\ MaxGround \in Nat

VARIABLES
    heldOut,  \* [Nodes -> SUBSET Nodes]: the nodes each node holds out (ground_exclude)
    out,      \* the nodes out on the ground's word (a Master that stepped down, a node
              \* the view excluded for the ground's hold), not yet readmitted: they know
              \* themselves out, run nothing, and are heard (Rejoin's `rebooted`)
    broken,   \* the nodes that crashed (real failures; they stay down)
    declared, \* [Nodes -> SUBSET Nodes]: the nodes each node's monitor declared failed
    views,    \* the switches started: <<epoch, seq, failed set>>
    phase,    \* the mission's phase (RequestPhase changes it)
    grounds,  \* the ground's commands accepted so far (a budget)
    hist      \* history, for the witnesses: what happened

groundVars == <<heldOut, out, broken, declared, views, phase, grounds, hist>>
allVars == <<vars, groundVars>>

(***************************************************************************)
(* Views and the graph                                                      *)
(***************************************************************************)

\* The failed set of the view node n adopted.
ViewFailed(n) ==
    LET w == {v \in views : v[1] = epoch[n] /\ v[2] = seq[n]}
    IN IF w = {} THEN {} ELSE (CHOOSE v \in w : TRUE)[3]

\* The nodes of S in Priority's order (the runtime's NodeSet order in the models).
InOrder(S) == SelectSeq(Priority, LAMBDA y : y \in S)

RECURSIVE Walk(_, _)
Walk(c, path) == IF path = <<>> THEN c ELSE Walk(OnFailure(c, Head(path)), Tail(path))

\* What configuration c uses: its master, observers and task hosts.
Uses(c) == {MasterOf(c)} \cup ObserversOf(c) \cup {Placement(c, t) : t \in Tasks}

NewEpoch == 1 + CHOOSE x \in {epoch[y] : y \in Nodes} \cup {msg.epoch : msg \in msgs} :
                    \A y \in Nodes : epoch[y] <= x /\ \A msg \in msgs : msg.epoch <= x

\* A switch of Master m to c with failed set F (ConfigSwitch's StartSwitch, recorded).
GStart(m, c, F) ==
    /\ StartSwitch(m, c)
    /\ views' = views \cup {<<epoch[m], masterSeq[m] + 1, F>>}

GTypeOK ==
    /\ TypeOK
    /\ heldOut \in [Nodes -> SUBSET Nodes]
    /\ out \subseteq Nodes
    /\ broken \subseteq Nodes
    /\ declared \in [Nodes -> SUBSET Nodes]
    /\ grounds \in 0..MaxGround

GInit ==
    /\ Init
    /\ heldOut = [n \in Nodes |-> {}]
    /\ out = {}
    /\ broken = {}
    /\ declared = [n \in Nodes |-> {}]
    /\ views = {<<1, 0, {}>>}
    /\ phase = PhaseOf(InitialConfig)
    /\ grounds = 0
    /\ hist = {}

(***************************************************************************)
(* The ground's commands                                                   *)
(***************************************************************************)

\* recover c at Master m: TraceConfigSwitch's GroundRecoveryAllowed.
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

GroundRecovery(m, c) ==
    /\ GroundRecoveryAllowed(m, c)
    /\ GStart(m, c, failed[m])
    /\ hist' = hist \cup {"recover"}
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted, heldOut, out, broken, declared, phase,
                   grounds>>

\* The runtime's reasons to refuse (NodeProtocol::request_recovery,
\* ReconfigurationManager::ground_recovery), in its order. A running node that is not
\* the Master (or a Master before its boot switch) refuses too.
RecoveryRefused(m, c) ==
    \/ ~IsMaster(m) \/ masterSeq[m] = 0
    \/ masterStage[m] # "Idle"
    \/ masterConfig[m] \notin SafeIds
    \/ c \notin ConfigIds \ SafeIds
    \/ PhaseOf(c) # PhaseOf(masterConfig[m])
    \/ MasterOf(c) # m
    \/ \E x \in ObserversOf(c) : x \in failed[m]
    \/ \E t \in Tasks : Placement(c, t) \in failed[m]

\* A refused recover: RefuseGroundCommand, nothing changes.
RefuseGroundCommand(m, c) ==
    /\ alive[m]
    /\ RecoveryRefused(m, c)
    /\ UNCHANGED allVars

\* The nodes n's monitor declared failed that its view has not excluded yet: a real failure
\* under way (a crashed node, a Master that stepped down, before the view excludes it).
Pending(n) == declared[n] \ ViewFailed(n)

\* What node n walks for an exclude of x: the nodes it holds out that its view has not
\* excluded, its Pending nodes, and x.
HeldPendingAnd(n, x) == (heldOut[n] \ ViewFailed(n)) \cup Pending(n) \cup {x}

\* The runtime's walk for a ground exclusion of x from configuration c
\* (NodeProtocol::ground_exclusion_reaches_safe): x first (the edge a Master's exclusion
\* takes), then the other nodes of S in the runtime's NodeSet order; and x's own edge
\* leads neither to SAFE nor, for a node other than c's Master, to a configuration of
\* another Master (which the Master's switch turns into SAFE).
GroundWalkOk(c, S, x) ==
    LET next == OnFailure(c, x)
    IN /\ Walk(c, <<x>> \o InOrder(S \ {x})) \notin SafeIds
       /\ next \notin SafeIds
       /\ x # MasterOf(c) => MasterOf(next) = MasterOf(c)

\* exclude x, as node n checks it (NodeProtocol::ground_exclude): SetOp gives the nodes
\* walked (a mutant passes another set).
ExcludeAcceptedBy(SetOp(_, _), n, x) ==
    \/ x \in ViewFailed(n)
    \/ config[n] \in SafeIds
    \/ GroundWalkOk(config[n], SetOp(n, x), x)

ExcludeAccepted(n, x) == ExcludeAcceptedBy(HeldPendingAnd, n, x)

\* The nodes that take the ground's commands: every running node, and those out on the
\* ground's word (their process runs).
Takers == {n \in Nodes : alive[n]} \cup out

\* x stops: it runs nothing (its tasks stop, what it had not flushed is lost), and knows
\* itself out (a crashed node stays what it is).
StopOut(x) ==
    /\ alive' = [alive EXCEPT ![x] = FALSE]
    /\ active' = [active EXCEPT ![x] = {}]
    /\ unflushed' = [unflushed EXCEPT ![x] = {}]
    /\ out' = IF x \in broken THEN out ELSE out \cup {x}

\* The ground's exclude of x at every node that takes it (AcceptOp its check); x steps down
\* when ResignOp(x) holds and it took it: the acting Master (a mutant: any node, the rule
\* before).
GroundExcludeBy(AcceptOp(_, _), ResignOp(_), x) ==
    LET takers == {n \in Takers : AcceptOp(n, x)}
        resigns == x \in takers /\ alive[x] /\ ResignOp(x)
    IN
    /\ grounds < MaxGround
    /\ takers # {}
    /\ grounds' = grounds + 1
    /\ heldOut' = [n \in Nodes |-> IF n \in takers THEN heldOut[n] \cup {x} ELSE heldOut[n]]
    \* x steps down: its own word; it stops (its tasks with it), and its successor takes
    \* over (a Master excludes it on its word).
    /\ IF resigns
       THEN StopOut(x)
       ELSE UNCHANGED <<alive, active, unflushed, out>>
    /\ hist' = hist \cup {"exclude"} \cup (IF resigns THEN {"resigned"} ELSE {})
    /\ UNCHANGED <<role, epoch, seq, config, stage, version, stored, masterStage,
                   masterConfig, masterSeq, failed, msgs, acks, crashes, phaseChanges,
                   unbooted, broken, declared, views, phase>>

\* Only the acting Master steps down on the ground's exclude of itself.
ActingMaster(x) == IsMaster(x)

GroundExclude(x) == GroundExcludeBy(ExcludeAccepted, ActingMaster, x)

\* An exclude every node refuses changes nothing (no trace line: the node's log says why).
RefuseExclude(x) ==
    /\ \A n \in Takers : ~ExcludeAccepted(n, x)
    /\ UNCHANGED allVars

\* The nodes Master m holds out that its view has not excluded (itself aside: it steps down
\* on the ground's exclude, and excludes no one for its own hold).
MasterHeld(m) == heldOut[m] \ (failed[m] \cup {m})

\* What the Master walks before it excludes a node it holds out: all of them and its
\* Pending nodes.
MasterWalkSet(m) == MasterHeld(m) \cup (declared[m] \ failed[m])

\* The Master's walk from its view for x stays out of SAFE (MCGroundWalk rejects mutants
\* without it and without the Pending nodes: SafeByFailuresInv); never from SAFE (the
\* ground's hold waits for a recovery).
MasterWalkOk(m, x) ==
    /\ masterConfig[m] \notin SafeIds
    /\ GroundWalkOk(masterConfig[m], MasterWalkSet(m), x)

\* The Master's ground exclusion (NodeProtocol, the ground's holds; trace line `Exclude`
\* with `ground`): Master m, between switches (IdleOp), excludes x, which it holds out
\* and its view has not excluded, when its walk stays out of SAFE (WalkOk): x, which the
\* view excludes, stops, and m switches along the graph's failure edge, also when it
\* keeps the configuration (the runtime's ExcludeSame).
GroundExcludeSwitchBy(WalkOk(_, _), IdleOp(_), m, x) ==
    /\ IsMaster(m)
    /\ masterSeq[m] > 0
    /\ IdleOp(m)
    /\ x \in MasterHeld(m)
    /\ WalkOk(m, x)
    /\ failed' = [failed EXCEPT ![m] = @ \cup {x}]
    /\ GStart(m, OnFailure(masterConfig[m], x), failed'[m])
    /\ IF alive[x] THEN StopOut(x) ELSE UNCHANGED <<alive, active, unflushed, out>>
    /\ hist' = hist \cup {"groundExcluded"}
    /\ UNCHANGED <<role, epoch, version, stored, acks, crashes, phaseChanges, unbooted,
                   heldOut, broken, declared, phase, grounds>>

Between(m) == masterStage[m] = "Idle"

GroundExcludeSwitch(m, x) == GroundExcludeSwitchBy(MasterWalkOk, Between, m, x)

GroundReadmit(x) ==
    LET takers == {n \in Takers : x \in heldOut[n]}
    IN
    /\ grounds < MaxGround
    /\ takers # {}
    /\ grounds' = grounds + 1
    /\ heldOut' = [n \in Nodes |-> IF n \in takers THEN heldOut[n] \ {x} ELSE heldOut[n]]
    /\ hist' = hist \cup {"readmit"} \cup (IF x \in out THEN {"readmitOut"} ELSE {})
    /\ UNCHANGED <<vars, out, broken, declared, views, phase>>

\* A readmit of a node no one holds out: refused everywhere, nothing changes.
RefuseReadmit(x) ==
    /\ \A n \in Takers : x \notin heldOut[n]
    /\ UNCHANGED allVars

(***************************************************************************)
(* The cluster                                                             *)
(***************************************************************************)

\* The boot switch, of the initial Master or of a Master handed the view once it adopted
\* it (TraceConfigSwitch's BootSwitch and HandedBootSwitch).
GBootSwitch(m) ==
    /\ IsMaster(m)
    /\ masterSeq[m] = 0
    /\ seq[m] = 0
    /\ config[m] = masterConfig[m]
    /\ \A msg \in msgs : msg.epoch <= epoch[m]
    /\ GStart(m, masterConfig[m], failed[m])
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, failed, acks,
                   crashes, phaseChanges, unbooted, heldOut, out, broken, declared, phase,
                   grounds, hist>>

\* The Master excludes f, which its monitor declared (crashed, or stepped down on the
\* ground's word): a switch to the graph's configuration, also when it is the same one (the
\* runtime's ExcludeSame).
GExclude(m, f) ==
    /\ IsMaster(m)
    /\ masterSeq[m] > 0
    /\ f \in declared[m]
    /\ f \notin failed[m]
    /\ failed' = [failed EXCEPT ![m] = @ \cup {f}]
    /\ GStart(m, OnFailure(masterConfig[m], f), failed'[m])
    /\ UNCHANGED <<alive, role, epoch, active, unflushed, version, stored, acks,
                   crashes, phaseChanges, unbooted, heldOut, out, broken, declared, phase,
                   grounds, hist>>

GRequestPhase(m, c) ==
    /\ RequestPhase(m, c)
    /\ views' = views \cup {<<epoch[m], masterSeq[m] + 1, failed[m]>>}
    /\ phase' = PhaseOf(c)
    /\ UNCHANGED <<heldOut, out, broken, declared, grounds, hist>>

\* The runtime's take-over: the Master and every node ahead of n are down; n, which does
\* not know itself out, takes over into the graph's configuration for them from its
\* view, in an epoch above every epoch.
TakeOver(n) ==
    LET ahead == {Priority[j] : j \in 1..(CHOOSE i \in 1..Len(Priority) : Priority[i] = n) - 1}
        F == ViewFailed(n) \cup ahead
        c == Walk(config[n], InOrder(ahead \ ViewFailed(n)))
        e == NewEpoch
    IN
    /\ alive[n]
    /\ n \notin out
    /\ \A x \in Nodes : role[x] = "Master" => ~alive[x]
    /\ \A x \in ahead : ~alive[x]
    /\ MasterOf(c) = n
    /\ role' = [x \in Nodes |-> IF x = n THEN "Master"
                               ELSE IF role[x] = "Master" THEN "Worker" ELSE role[x]]
    /\ epoch' = [epoch EXCEPT ![n] = e]
    /\ masterSeq' = [masterSeq EXCEPT ![n] = 1]
    /\ masterConfig' = [masterConfig EXCEPT ![n] = c]
    /\ masterStage' = [masterStage EXCEPT ![n] = "Preparing"]
    /\ failed' = [failed EXCEPT ![n] = F]
    /\ msgs' = msgs \cup {Command(e, 1, c)}
    /\ seq' = [seq EXCEPT ![n] = 1]
    /\ config' = [config EXCEPT ![n] = c]
    /\ stage' = [stage EXCEPT ![n] = "Deactivating"]
    /\ views' = views \cup {<<e, 1, F>>}
    /\ UNCHANGED <<alive, active, unflushed, version, stored, acks, crashes, phaseChanges,
                   unbooted, heldOut, out, broken, declared, phase, grounds, hist>>

\* r, back, runs again as a Worker awaiting its Command: nothing active, its view kept.
Back(r) ==
    /\ alive' = [alive EXCEPT ![r] = TRUE]
    /\ out' = out \ {r}
    /\ declared' = [n \in Nodes |-> declared[n] \ {r}]

\* The readmission's guards (NodeProtocol::consider_readmission), HeldOp saying which
\* nodes the Master may not take back (a mutant passes none).
MayReadmit(HeldOp(_), m, r, c) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Idle"
    /\ masterSeq[m] > 0
    /\ r \in out
    /\ r \in failed[m]
    /\ r \notin HeldOp(m)
    /\ c = RecoveryOf(masterConfig[m], r, failed[m] \ {r})
    /\ c \notin SafeIds
    /\ \A t \in Tasks : Placement(c, t) \notin failed[m] \ {r}

HeldBy(m) == heldOut[m]

\* Master m readmits r into c, its own configuration, in a new epoch (ReadmitSwitch).
ReadmitBy(HeldOp(_), m, r) ==
    LET c == RecoveryOf(masterConfig[m], r, failed[m] \ {r})
        e == NewEpoch
    IN
    /\ MayReadmit(HeldOp, m, r, c)
    /\ MasterOf(c) = m
    /\ Back(r)
    /\ role' = [role EXCEPT ![r] = "Worker"]
    /\ epoch' = [epoch EXCEPT ![m] = e]
    /\ failed' = [failed EXCEPT ![m] = @ \ {r}]
    /\ masterSeq' = [masterSeq EXCEPT ![m] = 1]
    /\ masterConfig' = [masterConfig EXCEPT ![m] = c]
    /\ masterStage' = [masterStage EXCEPT ![m] = "Preparing"]
    /\ msgs' = msgs \cup {Command(e, 1, c)}
    /\ seq' = [seq EXCEPT ![m] = 1]
    /\ config' = [config EXCEPT ![m] = c]
    /\ stage' = [stage EXCEPT ![m] = "Deactivating", ![r] = "Stable"]
    /\ views' = views \cup {<<e, 1, failed'[m]>>}
    /\ hist' = hist \cup {"readmitted"}
    /\ UNCHANGED <<active, unflushed, version, stored, acks, crashes, phaseChanges,
                   unbooted, heldOut, broken, phase, grounds>>

Readmit(m, r) == ReadmitBy(HeldBy, m, r)

\* Master m hands the view to r, the master of c, in a new epoch (HandOverSwitch): a
\* Command of that epoch at seq 0 every node adopts; r then makes its boot switch.
HandOverBy(HeldOp(_), m, r) ==
    LET c == RecoveryOf(masterConfig[m], r, failed[m] \ {r})
        e == NewEpoch
    IN
    /\ MayReadmit(HeldOp, m, r, c)
    /\ MasterOf(c) = r
    /\ Back(r)
    /\ msgs' = msgs \cup {Command(e, 0, c)}
    /\ role' = [role EXCEPT ![m] = "Worker", ![r] = "Master"]
    /\ masterSeq' = [masterSeq EXCEPT ![r] = 0]
    /\ masterConfig' = [masterConfig EXCEPT ![r] = c]
    /\ masterStage' = [masterStage EXCEPT ![r] = "Idle"]
    /\ failed' = [failed EXCEPT ![r] = failed[m] \ {r}]
    /\ stage' = [stage EXCEPT ![r] = "Stable"]
    /\ views' = views \cup {<<e, 0, failed[m] \ {r}>>}
    /\ hist' = hist \cup {"handedOver"}
    /\ UNCHANGED <<epoch, seq, config, active, unflushed, version, stored, acks, crashes,
                   phaseChanges, unbooted, heldOut, broken, phase, grounds>>

HandOver(m, r) == HandOverBy(HeldBy, m, r)

GCrash(n) ==
    /\ Crash(n)
    /\ broken' = broken \cup {n}
    /\ UNCHANGED <<heldOut, out, declared, views, phase, grounds, hist>>

\* n's monitor declares y, down, failed (Heartbeat: complete, and accurate within the loss
\* bound), at any time after y went down.
Declare(n, y) ==
    /\ alive[n]
    /\ ~alive[y]
    /\ y \notin declared[n] \cup ViewFailed(n)
    /\ declared' = [declared EXCEPT ![n] = @ \cup {y}]
    /\ UNCHANGED <<vars, heldOut, out, broken, views, phase, grounds, hist>>

\* ConfigSwitch's steps of the switch itself, unchanged.
SwitchSteps ==
    \/ \E m \in Nodes : BroadcastActivate(m)
    \/ \E m \in Nodes : CompleteSwitch(m)
    \/ \E n \in Nodes, msg \in msgs : ReceiveCommand(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Deactivate(n, t)
    \/ \E n \in Nodes, t \in Tasks : FlushCheckpoint(n, t)
    \/ \E n \in Nodes, k \in {"Prepared", "Activated"} : Ack(n, k)
    \/ \E n \in Nodes, msg \in msgs : ReceiveActivate(n, msg)
    \/ \E n \in Nodes, t \in Tasks : Activate(n, t)
    \/ \E n \in Nodes, t \in Tasks : Execute(n, t)

\* The next-state relation, with the ground's steps given (mutants pass others).
GNextWith(Recover(_, _), ExcludeCmd(_), ExcludeSwitch(_, _), ReadmitStep(_, _),
          HandOverStep(_, _)) ==
    \/ SwitchSteps /\ UNCHANGED groundVars
    \/ \E m \in Nodes : GBootSwitch(m)
    \/ \E m, f \in Nodes : GExclude(m, f)
    \/ \E m, x \in Nodes : ExcludeSwitch(m, x)
    \/ \E n, y \in Nodes : Declare(n, y)
    \/ \E m \in Nodes, c \in ConfigIds : GRequestPhase(m, c)
    \/ \E n \in Nodes : TakeOver(n)
    \/ \E n \in Nodes : GCrash(n)
    \/ \E m, r \in Nodes : ReadmitStep(m, r)
    \/ \E m, r \in Nodes : HandOverStep(m, r)
    \/ \E m \in Nodes, c \in ConfigIds : Recover(m, c)
    \/ \E m \in Nodes, c \in ConfigIds : RefuseGroundCommand(m, c)
    \/ \E x \in Nodes : ExcludeCmd(x)
    \/ \E x \in Nodes : RefuseExclude(x)
    \/ \E x \in Nodes : GroundReadmit(x)
    \/ \E x \in Nodes : RefuseReadmit(x)

GNext == GNextWith(GroundRecovery, GroundExclude, GroundExcludeSwitch, Readmit, HandOver)

GSpec == GInit /\ [][GNext]_allVars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* A running Master's configuration places nothing on a node it holds failed.
ValidUnderFailedInv ==
    \A m \in Nodes : IsMaster(m) /\ masterSeq[m] > 0 =>
        /\ \A x \in ObserversOf(masterConfig[m]) : x \notin failed[m]
        /\ \A t \in Tasks : Placement(masterConfig[m], t) \notin failed[m]

\* ... is one whose master it is ...
DrivesOwnConfigInv ==
    \A m \in Nodes : IsMaster(m) /\ masterSeq[m] > 0 => MasterOf(masterConfig[m]) = m

\* ... and is of the mission's phase.
PhaseKeptInv ==
    \A m \in Nodes : IsMaster(m) /\ masterSeq[m] > 0 => PhaseOf(masterConfig[m]) = phase

\* The cluster is in SAFE only when a node its Master holds failed crashed: no ground
\* exclusion takes it beyond the mission's tolerance.
SafeOnlyByFailureInv ==
    \A m \in Nodes : IsMaster(m) /\ masterConfig[m] \in SafeIds => failed[m] \cap broken # {}

\* What the walks are for: the cluster is in SAFE only if the walk of the failures alone
\* (the crashed nodes its Master's view excludes, in NodeSet order, without the ground's
\* holds) from the initial configuration reaches SAFE. It holds when every failure comes
\* before the ground's exclusions and is known (declared) to the node deciding each
\* (MCGroundWalk's MCWalkConstraint): a later or unseen failure may find the tolerance the
\* ground's exclusions spent, which no walk can foresee.
SafeByFailuresInv ==
    \A m \in Nodes : IsMaster(m) /\ masterConfig[m] \in SafeIds =>
        Walk(InitialConfig, InOrder(failed[m] \cap broken)) \in SafeIds

\* A node a running Master holds out and has excluded is not taken back into its view...
NoReadmitHeldProp ==
    [][\A m, r \in Nodes :
          (IsMaster(m) /\ r \in heldOut[m] /\ r \in failed[m] /\ IsMaster(m)')
          => r \in failed'[m]]_allVars

\* ... nor handed the mastership by it.
NoHandOverHeldProp ==
    [][\A m, r \in Nodes :
          (IsMaster(m) /\ r \in heldOut[m] /\ r \in failed[m] /\ ~IsMaster(r))
          => ~(IsMaster(r)')]_allVars
=============================================================================
