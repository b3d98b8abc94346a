----------------------------- MODULE ValueFault -----------------------------
(***************************************************************************)
(* Fault model 3: one value-faulty node (docs/fault-model.md, "Fault model *)
(* 3").                                                                    *)
(*                                                                         *)
(* One node, Liar, says something wrong. It may be any node: the first     *)
(* Master, an Observer, a Worker, the Storage node, an interface node. It  *)
(* sends any message its role's writers can carry, with any value the wire *)
(* admits and some it does not, at any time and to any node, but always    *)
(* under its own identity: the transport authenticates senders, so it can  *)
(* never speak as another node. Every other node is correct and applies    *)
(* the receiver rules below, which the runtime implements (core/fsm). The  *)
(* spec keeps what those rules are about and no more: views, epochs and    *)
(* their owners, Commands, Activates, "Prepared" and "Activated" acks,     *)
(* declarations, final checkpoint writes and their acknowledgements,       *)
(* restore replies, the lineages and counts of the states they carry, the  *)
(* epoch the Storage node adopted, the end of a hold, and a small decision *)
(* graph given as constants. It has no heartbeats, leases or crashes: the  *)
(* only faulty node is the liar, and a correct node declares a node failed *)
(* only on evidence, a Command of that node's it refused; every correct    *)
(* node sees what another declared (the runtime sends each declaration, an *)
(* ErrorNotification, to every node).                                      *)
(*                                                                         *)
(* A view, as a Command carries it, is its id <<epoch, seq>>, its          *)
(* configuration (one of the graph's, or Safe), its master and the         *)
(* processing nodes it excludes (`failed`). Epochs go round Priority as in *)
(* MasterElection: Owner(e) = Priority[((e - 1) % Len(Priority)) + 1] is   *)
(* the one node that may be Master in epoch e. A switch is ConfigSwitch's, *)
(* two phases: a node that adopts a newer view stops the tasks that view   *)
(* places elsewhere, sends their final checkpoints, and once the Storage   *)
(* node acknowledged them acks "Prepared" to every node, with the view it  *)
(* prepared; when every correct node the view does not exclude has, the    *)
(* Master sends Activate; a node takes it once it holds the "Prepared" of  *)
(* every other node the view does not exclude, starts the tasks placed on  *)
(* it from a restore reply and acks "Activated". A correct Master switches *)
(* along the graph for a node it declared (Exclude), for a planned         *)
(* phase change (RequestPhase), and a correct node takes over              *)
(* (BecomeMaster) once it declared the master of its view and every owner  *)
(* of the epochs before its next one, which it claims if the wire carries  *)
(* it. The cluster starts in the initial view, every task running on its   *)
(* host there.                                                             *)
(*                                                                         *)
(* The receiver rules (one operator each; NextBy takes them as parameters, *)
(* so that a mutant removes one):                                          *)
(*  - 1. Bounds (EpochInBounds, VersionInBounds). Every epoch is checked   *)
(*    against one wire width, MaxEpoch, every version against MaxVersion,  *)
(*    every configuration and task id against the mission's count, before  *)
(*    use; a message out of bounds is dropped (counted, no evidence).      *)
(*  - 2. Authority by role, decided by the receiver in its own view. A     *)
(*    Command's view is followed only from its master, the owner of its    *)
(*    epoch, not stale and at most one lap of the succession above the     *)
(*    receiver's epoch (MayCommand); an Activate only from the master of   *)
(*    the receiver's view, for that view's switch (MayActivate); a         *)
(*    checkpoint acknowledgement only from the Storage node (MayAck); a    *)
(*    restore reply only from the Storage node or a node the mission may   *)
(*    place the task on, MayHost(t) (MayReply); the Storage node stores a  *)
(*    write only from such a node (MayWrite). A message without authority  *)
(*    is dropped.                                                          *)
(*  - 3. Receivers check the Master (Checked). A Command's view must be    *)
(*    structurally valid (Valid): a configuration of the graph or Safe,    *)
(*    whose master out of Safe is the view's master, which the view does   *)
(*    not exclude, nor any task's host. When it is the next switch of the  *)
(*    receiver's own view from the same master (same epoch, seq + 1,       *)
(*    IsNextSwitch) it must also follow the graph: the edge for the nodes  *)
(*    it adds to the failed set (Walk, Topology::walk), or a phase edge    *)
(*    with the same failed set (OnEdge). Only of a view its master         *)
(*    commanded itself (seq 1 on) or of the initial one (epoch 1, seq 0):  *)
(*    a view at seq 0 of a later epoch is a hand-over's (IsHanded),        *)
(*    written by the Master before, and a lying one may have handed each   *)
(*    receiver a different copy, so the successor's first switch is held   *)
(*    to structural validity only, as one that skips a switch number is    *)
(*    (NodeProtocol::command_problem; HandedView.tla, seed 15049; here no  *)
(*    correct node follows a handed view). A Command that fails is refused *)
(*    and is evidence against its sender: the receiver declares it failed  *)
(*    for good, and no later message withdraws that.                       *)
(*  - 4. Peers' Prepared (PeersPrepared). A node takes the Activate of its *)
(*    view's switch only once it holds, from every node its view does not  *)
(*    exclude other than itself, a "Prepared" ack of exactly that view     *)
(*    (the same record: epoch, seq, configuration, master, failed set).    *)
(*    The Storage node and interface nodes take no part in switches here,  *)
(*    so the nodes it waits for are the correct processing nodes and the   *)
(*    liar, whose ack of any view is taken as sent. A Master's word is     *)
(*    then not enough to start a task: every node not excluded has adopted *)
(*    the same view and stopped what it places elsewhere.                  *)
(*  - 5. Backed exclusions (Backed). A node follows a Command whose view   *)
(*    excludes the node itself without this check: such a view only stops  *)
(*    what the node runs (Valid places no task on an excluded node, so it  *)
(*    starts nothing). Any other Command it follows only when each node    *)
(*    its view excludes beyond the node's `vetted` set, the failed set of  *)
(*    the last view it followed with this check, was declared failed by a  *)
(*    node other than the Command's sender, in a declaration the receiver  *)
(*    has seen (its own counts); or when another node vouches for the      *)
(*    view: its "Prepared" of exactly that view, from a node other than    *)
(*    the sender that the view does not exclude, says that node followed   *)
(*    the view, its exclusions backed where it checked them. A view that   *)
(*    excludes the node leaves `vetted` as it was, and so does a Master's  *)
(*    own switch (as in the runtime), so a Master cannot slip an exclusion *)
(*    in by first fencing a node and then readmitting it. A Command not    *)
(*    backed is not followed, and is no evidence: its backing may come     *)
(*    later, and the Master retransmits. Take-overs are Commands like any  *)
(*    other: the node taking over declared the old master and the owners   *)
(*    in between, and a receiver follows it on another node's declaration  *)
(*    of each, its own among them. A Master's word alone then stops the    *)
(*    node it excludes, but no other node acts on that exclusion.          *)
(*                                                                         *)
(* Lineages (Handoff.tla's). A task's state is its lineage, the switch id  *)
(* <<epoch, seq>> of the view that opened it (<<0, 0>> the initial one),   *)
(* and its count of steps, compared lineage first: the Storage node keeps  *)
(* the newest, and a checkpoint acknowledgement counts for every state     *)
(* below the one it carries. A liar that may host a task may claim a state *)
(* of a lineage of any epoch the wire carries, one no view has opened yet  *)
(* among them. Stored, such a state pins the task: nothing the cluster     *)
(* writes is newer until it opens a lineage of that epoch. And a host that *)
(* starts from it and runs on in it writes versions from the future, which *)
(* the Storage node refuses, so its final flush is never acknowledged and  *)
(* its switch waits for good (keel-sim --liar, prototype3 seeds 244, 1544  *)
(* and 12602). Three rules keep such a lineage out, one operator each      *)
(* (NextLineageBy takes them as parameters, NextBy passes the spec's):     *)
(*  - 2a. The Storage node's (WriteInEpoch; NodeProtocol::step,            *)
(*    CheckpointWrite). It drops a checkpoint write of a lineage of an     *)
(*    epoch newer than its writer's (refused as unauthorized) or newer     *)
(*    than its own adopted epoch (dropped as ahead, storeEpoch: an honest  *)
(*    host ahead of it repeats its flush until acknowledged). The liar     *)
(*    claims whatever writer epoch it likes, so only the second part binds *)
(*    it.                                                                  *)
(*  - 2b. The restore's (ReplyInEpoch; NodeProtocol::step,                 *)
(*    CheckpointReply). A reply from a node other than the Storage node    *)
(*    that holds a state of a lineage of an epoch above the request's, its *)
(*    receiver's, counts as holding nothing: the receiver takes another    *)
(*    reply. The Storage node's reply counts whatever its lineage.         *)
(*  - The start rule (RunLineage; ConfigSwitch::activate). A task that     *)
(*    starts from a state of a lineage of an epoch above its host's view   *)
(*    runs on in a lineage of that view, named by its switch id, so its    *)
(*    writes are of its own epoch. A state from the correct Storage node   *)
(*    may be of such a lineage: the Storage node may have followed a newer *)
(*    epoch than the host (StorageAdoptEpoch).                             *)
(*                                                                         *)
(* The Storage node's epoch is the newest of the Commands it followed      *)
(* (StorageAdoptEpoch): a correct Master's, or one of the liar's without a *)
(* defect. The Storage node takes no part in switches here, so nothing     *)
(* else of its view is modelled, and it follows those Commands unchecked   *)
(* by rules 3 to 5 (more epochs than the runtime's: more of the liar's     *)
(* writes pass 2a).                                                        *)
(*                                                                         *)
(* Counts (the protocol fuzzer's finding). A task's count goes up by one a *)
(* step; the wire and the Storage node carry any count up to the width,    *)
(* MaxVersion (the codec's 2^63 - 1). A liar that may host a task writes a *)
(* state at the width, and the correct Storage node keeps it (the newest   *)
(* wins). A correct host that adopts it, from the Storage node's restore   *)
(* reply, from a holder's, or resuming after a hold, and steps makes a     *)
(* count beyond the width: its later writes do not decode, its final flush *)
(* is never acknowledged, and its switch waits for good. A step here is    *)
(* bounded by the run's length alone, MaxSteps (a task's steps in the run, *)
(* on all its hosts together; in flight 2^62 - 1, 146,000 years at a       *)
(* million steps a second), not by the width. One rule, an operator        *)
(* NextLineageBy takes as a parameter too:                                 *)
(*  - The adoption rule (Adoptable; ConfigSwitch::adoptable). A correct    *)
(*    node adopts no state of a count above the adoption bound, AdoptBound *)
(*    = MaxVersion - MaxSteps (kMaxAdoptedCount, 2^62). No correct run     *)
(*    makes such a count (MaxSteps <= AdoptBound: a task started from no   *)
(*    state counts at most MaxSteps), and a state adopted at the bound     *)
(*    runs to at most the width. The Storage node's restore reply of a     *)
(*    state above it is taken as lost: the host starts the task from no    *)
(*    state in a new lineage named by its view's switch id, newer than the *)
(*    stored state unless that is of a lineage of a newer view, so that    *)
(*    its writes are taken (Activate;                                      *)
(*    ConfigSwitch::receive_checkpoint_reply). A holder's reply of one     *)
(*    counts as holding nothing, and the receiver takes another (Activate; *)
(*    the gathering). A node resuming after a hold keeps its own state     *)
(*    (Resume; ConfigSwitch::resume_released). The Storage node still      *)
(*    stores any count up to the width: a correct host that adopted a      *)
(*    state at the bound steps above it.                                   *)
(*                                                                         *)
(* The liar has no state: its messages are on the wire from the start      *)
(* (LiarCommands, LiarActivates, LiarCheckpointAcks, LiarWrites, a restore *)
(* reply with any version, the last three with a state of any lineage of   *)
(* LiarLineages, and, if it is a processing node, its declarations of      *)
(* every processing node, LiarDeclares: only a processing node's           *)
(* declaration has authority, and its request for its own exclusion backs  *)
(* that exclusion as a declaration does). A liar that waits to see what to *)
(* send adds no behaviour, since the channel may hold back, reorder and    *)
(* duplicate any message. Its Commands are the views with at most one      *)
(* defect: an epoch beyond the wire, an epoch it does not own, a master    *)
(* other than itself, or a view that is not valid; the invalid ones        *)
(* exclude at most one node, which leaves every way to be invalid among    *)
(* them (an unknown id, a master that is not the configuration's, an       *)
(* excluded master, an excluded host). The rules drop a message with two   *)
(* defects as they drop either alone, and refuse every invalid view alike, *)
(* so this leaves out no state of the spec; a mutant, which removes one    *)
(* rule, sees the messages that rule alone stopped. Its "Prepared" and     *)
(* "Activated" acks are taken as sent (a correct Master, and a node under  *)
(* rule 4, waits for no ack of the liar's). Its declarations back a        *)
(* Command, and its "Prepared" vouches for a view, only when it is not the *)
(* Command's sender (and, for the vouch, when the view does not exclude    *)
(* it): the liar backs or vouches only for a correct Master's Command.     *)
(*                                                                         *)
(* Properties, about the correct nodes:                                    *)
(*  - (a) OneMasterPerEpochInv: the correct nodes that follow views of one *)
(*    epoch agree on its master, so no two nodes run as Master in one      *)
(*    epoch or one view.                                                   *)
(*  - (b) NoDoubleActivationInv: no task runs on two correct nodes at      *)
(*    once.                                                                *)
(*  - (c) ValidConfigInv: every correct node follows a structurally valid  *)
(*    view of the graph (or Safe), and out of a switch's first phase runs  *)
(*    only the tasks that view places on it. NoHonestRefusalInv: the       *)
(*    checks cost a correct cluster nothing: no correct node refuses a     *)
(*    correct Master's Command, so none declares a correct node failed     *)
(*    (keel-sim's invariant of that name).                                 *)
(*  - (d) NoRegressionInv: no correct node runs a task below the newest    *)
(*    version a correct node wrote and the Storage node took as its        *)
(*    checkpoint; NoForeignStateInv: nor from a state the liar made. Both  *)
(*    for a correct Storage node and a task the mission may not place on   *)
(*    the liar: the Storage node's own store, and a task the liar may run, *)
(*    are within the liar's authority, which fault model 3 does not cover. *)
(*  - (e) EpochBoundInv: no correct node's epoch exceeds MaxEpoch;         *)
(*    VersionBoundInv: no version a correct node runs or has to flush, or  *)
(*    the correct Storage node holds, exceeds MaxVersion (a step being     *)
(*    bounded by MaxSteps, not the width, it binds the adoption rule).     *)
(*  - (f) Lineages. NoFutureLineageInv: no correct node runs a task, or    *)
(*    holds one to flush, in a lineage of an epoch above its view's, so    *)
(*    none writes a version from the future. With a correct Storage node:  *)
(*    StoredAdoptedInv, it holds no state of a lineage of an epoch it has  *)
(*    not adopted; NoFutureStateInv, no correct node runs a task started   *)
(*    from a state of a lineage of an epoch no correct node had adopted    *)
(*    (no view had opened it: the liar's claim); FlushLiveness, every      *)
(*    final flush of a correct node is acknowledged in the end (under      *)
(*    LineageFairness: the Storage node takes a flush it may take, and     *)
(*    follows a newer Command on the wire; no other step need happen).     *)
(*                                                                         *)
(* What TLC shows (MCValueFault.tla has the models; one worker):           *)
(*  - Every property holds against a liar of each kind, a lying Master     *)
(*    included, and each CI model checks every property that is not        *)
(*    vacuous in it. MCValueFault (PN1, the first Master, lies) checks     *)
(*    (a), (b), (c), (e): 11,532 states, 9 s. MCValueFaultRegression, the  *)
(*    same liar with a task t2 it may not host (Tasks = {t1, t2},          *)
(*    Essential = {t1}, MaxVersion = 2, a step of each task, MaxSeq = 1,   *)
(*    the liar's counts 0 or one beyond the width), checks (d) too: 9,184  *)
(*    states, 10 s. MCValueFaultObserver: 13,910 states, 7 s. By hand, no  *)
(*    property fails either in MCValueFaultRegression with MaxSeq = 2 (the *)
(*    liar may skip a switch number; 101,472 states, 1.8 min), in          *)
(*    MCValueFault with MaxSeq = 3 (it may fence and then readmit, see     *)
(*    below; 53,536 states, 1 min), with PN3 as the liar (MaxEpoch 3 and   *)
(*    4: 12,294 and 13,690 states), in MCValueFaultObserver with t2, a     *)
(*    step of each task (MaxVersion 2, the liar's counts as in             *)
(*    MCValueFaultRegression) and MaxEpoch 5 (PN2 owns epochs 2 and 5;     *)
(*    379,260 states, 7 min), nor, a smaller liar, when its request for    *)
(*    its own exclusion does not count as a declaration (MCValueFault      *)
(*    11,398, MCValueFaultObserver 11,906, MCValueFaultRegression 7,707    *)
(*    and, with MaxSeq = 2, 98,996).                                       *)
(*  - Each of rules 4 and 5 is needed against a lying Master. Without rule *)
(*    4 (ValueFaultNoPeerPrepared) PN1 sends PN2 the phase change (1, 1,   *)
(*    P2), which PN3 has not received, then its Activate; PN2 starts t1,   *)
(*    which PN3 still runs. Without rule 5 (ValueFaultUnbackedExclusion),  *)
(*    rule 4 does not stop it: PN1's (1, 1) that excludes PN3 is the       *)
(*    graph's edge for PN3's failure and passes rule 3, and PN2 waits for  *)
(*    no "Prepared" of an excluded node while PN3, which never received    *)
(*    that Command, runs t1. Both break NoDoubleActivationInv in           *)
(*    MCValueFault and NoRegressionInv in MCValueFaultRegression. Without  *)
(*    both, TLC finds (d) violated in 9 states of MCValueFaultRegression:  *)
(*    PN1 sends PN2 and PN3 two different next switches of (1, 0), PN3's   *)
(*    excluding PN2, and PN3 starts t2 from version 0 while PN2 still runs *)
(*    it to version 1. Rule 5 stops the exclusion, and two views with one  *)
(*    switch id never both activate under rule 4: each node waits for the  *)
(*    other's "Prepared" of its own view. Rule 3 binds the edge, rule 5    *)
(*    the evidence for an exclusion, rule 4 one view per switch.           *)
(*  - Rule 5's measure, vetted rather than the node's current view, binds. *)
(*    A correct node fenced by the liar follows its view unchecked         *)
(*    (WitnessFencedByLiarInv: PN1's next switch excluding PN2, which no   *)
(*    node declared) and stops its tasks. Measured against the failed set  *)
(*    of the view it follows instead (ValueFaultFencedThenUnchecked,       *)
(*    MCValueFault with MaxSeq = 3), PN1 fences PN2 and PN3 with (1, 1) to *)
(*    Safe, which PN2 follows unchecked, skips a switch number and         *)
(*    readmits PN2 alone with (1, 3), P1 without PN3, which places t1 on   *)
(*    PN2: it adds nothing to (1, 1)'s failed set, so PN2 follows it,      *)
(*    waits for no "Prepared" of PN3 and starts t1, which PN3, never       *)
(*    commanded, still runs (NoDoubleActivationInv). The liar needs a view *)
(*    that is not the next switch of the fencing one, a skipped number or  *)
(*    its next owned epoch (with MaxEpoch = 4 the mutant breaks            *)
(*    NoDoubleActivationInv too): the next switch of a view may only add   *)
(*    to its failed set (rule 3), so with MaxSeq = 2 the mutant breaks     *)
(*    nothing (11,532 states, as the spec).                                *)
(*  - A vouch binds nowhere in these models: without it MCValueFault,      *)
(*    MCValueFaultObserver and MCValueFaultRegression have the same states *)
(*    (a correct Master's Command adds only the liar, whose "Prepared"     *)
(*    then does not count, or nothing), and with it no property fails: the *)
(*    liar vouches only for a correct Master's Command. It is here because *)
(*    the runtime has it.                                                  *)
(*  - Rule 4 binds where the liar is the Master (WitnessActivateHeldInv: a *)
(*    node holds the liar's Activate while a peer's "Prepared" is          *)
(*    missing), and it implies rule 2's Activate authority: a node that    *)
(*    holds every peer's "Prepared" of its view holds all a correct Master *)
(*    waits for before its Activate, so an Activate from any node breaks   *)
(*    no property (by hand: MCValueFault 11,654 states,                    *)
(*    MCValueFaultObserver 14,805, MCValueFaultRegression 9,876). Rule 2's *)
(*    stale check is implied by adopting only newer views (a stale epoch   *)
(*    is never newer), and the one-lap bound never binds here (the liar's  *)
(*    next owned epoch is beyond MaxEpoch); none of the three has a        *)
(*    mutant. The Walk rule binds only the next switch of a receiver's     *)
(*    view: a liar Master that skips a switch number is held to structural *)
(*    validity only (WitnessLiarOffGraphInv: a correct node follows a view *)
(*    of the liar's whose configuration is not the graph's for its failed  *)
(*    set), and with Checked = Valid (no edge check at all) no property    *)
(*    fails (MCValueFault: 41,534 states; MCValueFaultRegression: 44,216). *)
(*  - The declaration on evidence is what lets a correct node take over    *)
(*    from a lying Master (WitnessLiarDeposedInv) and, under rule 5, what  *)
(*    lets the other correct nodes follow it: the node taking over cannot  *)
(*    back its own Command, so a second correct node must have refused a   *)
(*    Command of the liar's too (WitnessBackedTakeOverInv), unless the     *)
(*    liar asked for its own exclusion. A lying Observer still takes over  *)
(*    with a valid Command of the epoch it owns                            *)
(*    (WitnessMasterFollowsLiarInv: nothing here makes a node that still   *)
(*    hears its Master refuse a take-over, Raft's PreVote and CheckQuorum, *)
(*    not built); a Command of its that excludes the Master it deposes     *)
(*    fences that Master and no other node follows it, and it is then held *)
(*    to rules 4 and 5 like any lying Master.                              *)
(*  - Lineages. MCValueFaultLineage: PN2 lies, may host t2 (Tasks = {t2},  *)
(*    no essential task), sends only Commands without a defect, and its    *)
(*    checkpoint messages carry the initial lineage or one of its own      *)
(*    epoch 2 = MaxEpoch, which no correct node but the Storage node may   *)
(*    adopt; PN1 is the correct Master, with two phase changes (MaxSeq 1,  *)
(*    MaxVersion 0, no step). It checks (a), (b), (c), (e) and (f): 10,068 *)
(*    states. MCValueFaultLineageStorage, MCValueFaultStorage without the  *)
(*    step (MaxVersion 1, MaxSteps 0) whose lying ST1 replies with states  *)
(*    of a lineage of epoch 3 = MaxEpoch, which no node adopts, checks     *)
(*    (a), (b), (c), (e) and NoFutureLineageInv: 1,944 states. Without     *)
(*    2a's ahead part (ValueFaultStoresAhead) the liar's state of a        *)
(*    lineage of epoch 2 is stored while the Storage node is in epoch 1    *)
(*    (StoredAdoptedInv; by hand NoFutureStateInv fails too: PN3 restores  *)
(*    it at the phase change). Without 2b (ValueFaultFutureReply) PN3      *)
(*    starts t2 from the liar's reply of that lineage (NoFutureStateInv).  *)
(*    Without the start rule (ValueFaultFutureLineageKept) a host runs on  *)
(*    in the lying Storage node's lineage of epoch 3 (NoFutureLineageInv:  *)
(*    seed 12602), and with a correct Storage node too                     *)
(*    (ValueFaultFutureLineageStall): the Storage node follows PN2's       *)
(*    Command of epoch 2, which PN3 does not, and stores PN2's state of a  *)
(*    lineage of that epoch; PN3 restores t2 from it at the first phase    *)
(*    change (WitnessFutureStartInv) and deactivates it at the second, and *)
(*    its final flush, a version from the future, is refused for as long   *)
(*    as PN3 stays in epoch 1 (FlushLiveness). The start rule alone keeps  *)
(*    a correct host's writes in its epoch: without 2a's ahead part        *)
(*    (14,502 states) or without 2b (14,982), by hand, NoFutureLineageInv  *)
(*    and FlushLiveness hold; what 2a and 2b keep out is the liar's state  *)
(*    itself, a lineage no view opened, which would pin the task           *)
(*    (StoredAdoptedInv, NoFutureStateInv). The writer's-epoch part of 2a  *)
(*    binds no writer here (without it, 10,068 states, no violation): the  *)
(*    liar claims any writer epoch, and the start rule keeps a correct     *)
(*    writer's lineage within its epoch (without the start rule it is the  *)
(*    check that refuses PN3's flush); it has no mutant.                   *)
(*  - Counts. MCValueFaultWidth: PN3 lies (its epoch, 3, is beyond the     *)
(*    wire: MaxEpoch 2), may host t1, the one task, and writes it at the   *)
(*    width (MaxVersion 2, MaxSteps 1: AdoptBound 1); PN1 is the correct   *)
(*    Master, with two phase changes, which move t1 from PN3 to PN2 and    *)
(*    back. It checks (a), (b), (c), (e) and (f): 323 states, 2 s. PN2     *)
(*    restores t1 at the first phase change: from the Storage node's state *)
(*    at the width it starts from no state in lineage <<1, 1>>             *)
(*    (WitnessLostAboveBoundInv); from the liar's state at the bound it    *)
(*    steps to 2, and its final flush at the second phase change is stored *)
(*    (WitnessPastBoundInv). Without the adoption rule                     *)
(*    (ValueFaultAdoptsAtWidth) PN2 adopts the liar's 2 and steps to 3     *)
(*    (VersionBoundInv), and its final flush, dropped as out of bounds, is *)
(*    never acknowledged (ValueFaultAdoptsAtWidthStall: FlushLiveness, the *)
(*    protocol fuzzer's stall). Each adoption point binds alone: by hand,  *)
(*    with the rule removed at one of them only, VersionBoundInv fails in  *)
(*    MCValueFaultWidth, from the liar's reply, from the Storage node's,   *)
(*    or at a resumption; and without the rule it fails in                 *)
(*    MCValueFaultStorage, from the lying Storage node's reply at the      *)
(*    width. MaxSteps <= AdoptBound binds too: by hand, without that       *)
(*    assumption, with MaxVersion 1 and MaxSteps 1 in                      *)
(*    MCValueFaultInterface, a correct count of 1 is above the bound (0),  *)
(*    the next host takes it as lost, and the task restarts below what a   *)
(*    correct node wrote (NoRegressionInv).                                *)
(*                                                                         *)
(* Not covered (stated, not hidden):                                       *)
(*  - Combined faults: a liar together with a crash or a pause (fault      *)
(*    model 2). Here a correct node declares only on the evidence of a     *)
(*    refused Command, so a correct node's declaration is always true. In  *)
(*    the runtime a heartbeat monitor also declares a node it does not     *)
(*    hear: a paused correct node so declared backs a lying Master's       *)
(*    exclusion of it, the other nodes wait for no "Prepared" of its, and  *)
(*    it stops its tasks only when its lease lapses, which the liar's      *)
(*    heartbeat acks can keep from lapsing (Lease.tla assumes correct      *)
(*    ackers).                                                             *)
(*  - Backing that is the runtime's only (NodeProtocol::declared_to_me): a *)
(*    node's silence where its heartbeats come, for as long as a monitor   *)
(*    takes to declare it, and a restarted node's own word to the Storage  *)
(*    and interface nodes. Both are true of a node that is down, and both  *)
(*    are left out with the crashes and pauses above.                      *)
(*  - The last monitor's word. A receiver's own declaration backs an       *)
(*    exclusion, and when the receiver is the only node besides the sender *)
(*    that could declare, nobody checks that declaration. And the          *)
(*    runtime's exclusion_backed passes without any declaration when no    *)
(*    monitor of the receiver's view but the sender and the node excluded  *)
(*    is left (an exclusion then needs only the sender's word, fault model *)
(*    2): a lying last monitor may exclude a correct node on its own word. *)
(*    The spec has no monitors and does not model that clause.             *)
(*  - Liveness. Rule 5 makes a correct Master's exclusion, and a           *)
(*    take-over, wait until a second node declared the same node (or       *)
(*    vouched for the view); the liar can leave correct nodes in a switch  *)
(*    that never completes (two views with one switch id), and can fence a *)
(*    correct node, which nothing here readmits. The only liveness checked *)
(*    is FlushLiveness, (f).                                               *)
(*  - The runtime's other starts and writes. A start without the Storage   *)
(*    node, from holders' replies (a gathering, Handoff.tla), opens a      *)
(*    lineage of its view in the runtime whatever it starts from           *)
(*    (ConfigSwitch::finish_gathering); here a node starts from the first  *)
(*    reply it takes and keeps its lineage unless the start rule changes   *)
(*    it (more states in a lineage not opened by their view, not fewer). A *)
(*    hold (the lease, Lease.tla) is here only its end, Resume, which may  *)
(*    come at any time; the tasks a held node stops and restarts meanwhile *)
(*    are not modelled. Checkpoints between switches, the runtime's        *)
(*    host_wins (a host's periodic write replaces a foreign writer's pin)  *)
(*    and lineages beyond the wire's epoch width (dropped by rule 1 as any *)
(*    epoch is) are left out.                                              *)
(*  - Runs longer than MaxSteps. A task that ran more steps than           *)
(*    AdoptBound (in flight 2^62) would write a correct count above the    *)
(*    bound, which the next host takes as lost: it starts from no state,   *)
(*    below what the task ran to (NoRegressionInv, by hand, under Counts   *)
(*    above). The runtime counts each state it does not adopt              *)
(*    (ConfigSwitch::unadoptable_states); the spec has no counter.         *)
(*                                                                         *)
(* Where core/fsm differs, the spec is the stricter or the simpler: its    *)
(* view_problem counts an epoch that is not its master's, or one within a  *)
(* lap of the width, as evidence (here they are dropped, without evidence; *)
(* the properties do not depend on which); its edge_problem also takes the *)
(* same configuration again and a safe-mode exit (the spec's correct       *)
(* Masters send neither; HandedView.tla's HEdge takes the first, which a   *)
(* handed Master's boot switch is); its lap grows by one per heartbeat     *)
(* period since a node adopted its epoch (here one lap). Its "Prepared"    *)
(* ack carries a 64-bit digest of the view, where the spec's carries the   *)
(* view (a collision is not modelled), and a node keeps only a peer's      *)
(* newest "Prepared" of a view newer than its own (ConfigSwitch::vouched), *)
(* where the spec keeps every ack (more vouches, not fewer). The Storage   *)
(* node and interface nodes prepare too in the runtime and may vouch for a *)
(* view; here the liar, whatever its role, vouches, and no correct one of  *)
(* them does. A receiver ignores the declarations of a node its view       *)
(* excludes; here every declaration counts (more backing, not less). The   *)
(* runtime's declarations are ErrorNotifications that a receiver may not   *)
(* have yet; here every correct node sees one when it is made, which loses *)
(* nothing: a receiver that has not seen it yet just does not take the     *)
(* Command yet, and the channel may hold a Command back.                   *)
(*                                                                         *)
(* Abstractions: only processing nodes follow views (Followers: the        *)
(* correct ones); the Storage node and interface nodes take no part in     *)
(* switches, and views exclude processing nodes only (the Storage node's   *)
(* exclusion is Handoff.tla's). Commands carry no joint views              *)
(* (Quorum.tla), no correct Master readmits a node (the liar may: a view   *)
(* of its that skips a switch number may exclude fewer nodes), and there   *)
(* is no hand-over: a Command whose view names a master other than its     *)
(* sender is dropped (NodeProtocol::handle_command takes one from the      *)
(* Master of the receiver's view that hands the next epoch to the node it  *)
(* names; HandedView.tla adds the liar's hand-overs and the new Master's   *)
(* boot switch). A node starts a task from the first restore reply it      *)
(* takes (rule 2 allows the Storage node's or one from a node that may     *)
(* host the task, the adoption rule one of a count at most the bound, or   *)
(* the Storage node's as lost); the correct Storage node's reply carries   *)
(* what it holds when the node takes it, and its receipt of a final        *)
(* checkpoint and the acknowledgement are one step, as in Handoff.tla (a   *)
(* final write whose acknowledgement came from elsewhere is stored later,  *)
(* StoreCheckpoint). Checkpoints between switches are left out, as in      *)
(* ConfigSwitch. Node ids in the liar's views are nodes (the sender's is   *)
(* authenticated); phase ids travel inside configuration ids (no           *)
(* PhaseRequest).                                                          *)
(***************************************************************************)
EXTENDS Naturals, FiniteSets, Sequences, TLC

CONSTANTS
    Nodes,            \* every node: the processing nodes, the Storage node, interface nodes
    Priority,         \* the processing nodes in succession order; Priority[1] is the first
                      \*   Master, and Owner(e) the one node that may be Master in epoch e
    Storage,          \* the Storage node: keeps the checkpoints, owns no epoch
    Liar,             \* the value-faulty node (any node); every other node is correct
    Tasks,            \* the application tasks (all checkpointed)
    Essential,        \* the tasks safe mode runs, all on its view's master
    ConfigIds,        \* the configurations of the decision graph
    Safe,             \* the id of safe mode (not one of ConfigIds)
    BadConfig,        \* a configuration id beyond the mission's count (only on the wire)
    BadTask,          \* a task id beyond the mission's count (only on the wire)
    InitialConfig,    \* the configuration the cluster starts in
    ConfigMaster(_),  \* ConfigMaster(c): the master of configuration c
    Host(_, _),       \* Host(c, t): the node configuration c places task t on
    OnFailure(_, _),  \* OnFailure(c, f): the graph's edge from c when processing node f
                      \*   fails (a configuration, Safe, or c itself when f does not matter)
    OnPhase(_),       \* OnPhase(c): the configurations a planned phase change leads to
                      \*   from c (none from Safe)
    MaxEpoch,         \* the wire's epoch width: the largest epoch a message may carry
    MaxVersion,       \* the wire's version width: the largest checkpoint version
                      \*   (kMaxVersionCount, 2^63 - 1)
    MaxSteps,         \* the steps a task takes in a run, on all its hosts together: more
                      \*   than any run takes (kMaxVersionCount - kMaxAdoptedCount, 2^62 - 1)
    MaxSeq,           \* the liar's switch numbers are at most this (a bound on the model)
    MaxPhaseChanges   \* at most this many planned switches

ProcessingNodes == {Priority[i] : i \in 1..Len(Priority)}
N == Len(Priority)

\* Where a view places a task of no configuration (a task safe mode does not run).
Unplaced == "unplaced"

ASSUME NodesAssumption ==
    /\ Cardinality(ProcessingNodes) = N /\ N >= 1
    /\ ProcessingNodes \subseteq Nodes
    /\ Storage \in Nodes \ ProcessingNodes
    /\ Liar \in Nodes
ASSUME ConfigAssumption ==
    /\ InitialConfig \in ConfigIds
    /\ {Safe, BadConfig} \cap ConfigIds = {} /\ Safe # BadConfig
    /\ BadTask \notin Tasks
    /\ Essential \subseteq Tasks
    /\ \A c \in ConfigIds :
          /\ ConfigMaster(c) \in ProcessingNodes
          /\ \A t \in Tasks : Host(c, t) \in ProcessingNodes \cup {Unplaced}
          /\ OnPhase(c) \subseteq ConfigIds
          /\ \A d \in OnPhase(c) : ConfigMaster(d) = ConfigMaster(c)
          /\ \A f \in ProcessingNodes :
                /\ OnFailure(c, f) \in ConfigIds \cup {Safe}
                \* An edge for another node's failure keeps the master.
                /\ (f # ConfigMaster(c) /\ OnFailure(c, f) # Safe)
                      => ConfigMaster(OnFailure(c, f)) = ConfigMaster(c)
    /\ OnPhase(Safe) = {}
\* The adoption bound (kMaxAdoptedCount, 2^62): the largest count of a state a correct node
\* adopts. The steps of a run fit below it (a correct count is at most MaxSteps, so no state
\* a correct run made is ever refused), and above it (a state adopted at the bound runs at
\* most MaxSteps on, to at most the width).
AdoptBound == MaxVersion - MaxSteps
ASSUME BudgetAssumption ==
    /\ {MaxEpoch, MaxVersion, MaxSteps, MaxSeq, MaxPhaseChanges} \subseteq Nat
    /\ MaxEpoch >= 1
    /\ MaxSteps <= AdoptBound

(***************************************************************************)
(* Views, epochs and the decision graph                                    *)
(***************************************************************************)

\* The configuration ids the mission knows (the ids rule 1 lets through), Safe among them.
\* (TLCEval: the tables below are computed once, not at every state.)
KnownConfigs == TLCEval(ConfigIds \cup {Safe})

\* A view, as a Command carries it: its id <<epoch, seq>>, its configuration, its master
\* and the processing nodes it excludes.
Views == [epoch : Nat, seq : Nat, config : KnownConfigs, master : Nodes,
          failed : SUBSET ProcessingNodes]

\* The owner of epoch e >= 1, and a node's place in the succession.
Owner(e) == Priority[((e - 1) % N) + 1]
RankOf == TLCEval([n \in ProcessingNodes |-> CHOOSE i \in 1..N : Priority[i] = n])
Rank(n) == RankOf[n]

\* View v is newer than view w: the total order of switches.
Newer(v, w) == v.epoch > w.epoch \/ (v.epoch = w.epoch /\ v.seq > w.seq)

\* The node view v places task t on: safe mode runs the essential tasks on its master.
PlacedOn(v, t) ==
    IF v.config = Safe THEN IF t \in Essential THEN v.master ELSE Unplaced
    ELSE Host(v.config, t)
TasksOn(v, n) == {t \in Tasks : PlacedOn(v, t) = n}

\* The nodes the mission may ever place task t on: its host in any configuration and, for
\* an essential task, every node that may become Master (Topology::may_host).
MayHostOf ==
    TLCEval([t \in Tasks |->
                TLCEval(({Host(c, t) : c \in ConfigIds} \ {Unplaced})
                            \cup (IF t \in Essential THEN ProcessingNodes ELSE {}))])
MayHost(t) == MayHostOf[t]

\* The walk of the decision graph from c through the failed nodes F, in succession order,
\* one edge per failure (a failure that does not matter keeps the configuration); and the
\* configuration it ends in, or Safe when that one's master or a task's host is among
\* all, the view's failed nodes (Topology::walk).
RECURSIVE WalkFrom(_, _)
WalkFrom(c, F) ==
    IF F = {} \/ c = Safe THEN c
    ELSE LET f == CHOOSE x \in F : \A y \in F : Rank(x) <= Rank(y)
         IN  WalkFrom(OnFailure(c, f), F \ {f})
WalkOf ==
    TLCEval([c \in KnownConfigs |->
                TLCEval([F \in SUBSET ProcessingNodes |-> WalkFrom(c, F)])])
Target(c, F, all) ==
    LET w == WalkOf[c][F]
    IN  IF w = Safe \/ ConfigMaster(w) \in all \/ \E t \in Tasks : Host(w, t) \in all
        THEN Safe ELSE w

\* Rule 3's structural validity: a configuration of the graph or Safe, whose master (out
\* of Safe) is the view's master, which the view does not exclude, nor any task's host.
Valid(v) ==
    /\ v.config \in KnownConfigs
    /\ v.config # Safe => ConfigMaster(v.config) = v.master
    /\ v.master \notin v.failed
    /\ \A t \in Tasks : PlacedOn(v, t) \notin v.failed

(***************************************************************************)
(* Lineages (Handoff.tla): a task's state is its lineage, the switch id    *)
(* <<epoch, seq>> of the view that opened it, and its count of steps,      *)
(* compared lineage first.                                                 *)
(***************************************************************************)
Lineages == Nat \X Nat
InitialLineage == <<0, 0>>
\* The epoch whose view opened lineage l (the runtime's lineage_epoch).
LineageEpoch(l) == l[1]
\* State <<l, v>> (lineage l, count v) is at least as new as <<k, w>>, lineage first.
StateGeq(l, v, k, w) ==
    l[1] > k[1] \/ (l[1] = k[1] /\ (l[2] > k[2] \/ (l[2] = k[2] /\ v >= w)))
StateGt(l, v, k, w) == StateGeq(l, v, k, w) /\ <<l, v>> # <<k, w>>
\* The lineages the liar's checkpoint messages (writes, acknowledgements, restore replies)
\* carry. The initial one alone here: every state of the spec then stays in the initial
\* lineage and ValueFault's models are those of the spec without lineages.
\* MCValueFaultLineage.cfg and MCValueFaultLineageStorage.cfg replace it (MCLiarLineages),
\* TLC's override of a definition in the model's .cfg.
LiarLineages == {InitialLineage}

(***************************************************************************)
(* What the liar may send: on the wire from the start (see the header).    *)
(***************************************************************************)
\* The values the wire carries: one epoch and one version beyond the widths.
WireEpochs == 1..(MaxEpoch + 1)
WireVersions == 0..(MaxVersion + 1)
\* The counts the liar's checkpoint messages carry: every one the wire does, the width
\* (above the adoption bound) and one beyond it among them. A model may replace it, as it
\* may LiarLineages.
LiarVersions == WireVersions
WireViews == [epoch : WireEpochs, seq : 1..MaxSeq, config : ConfigIds \cup {Safe, BadConfig},
              master : Nodes, failed : SUBSET ProcessingNodes]
\* The liar's views: at most one defect of four, and an invalid one excluding at most one
\* node (each way to be invalid is among them: an unknown id, a master that is not the
\* configuration's, an excluded master, an excluded host).
Defects(v) ==
    (IF v.epoch <= MaxEpoch THEN 0 ELSE 1) + (IF Owner(v.epoch) = Liar THEN 0 ELSE 1)
        + (IF v.master = Liar THEN 0 ELSE 1) + (IF Valid(v) THEN 0 ELSE 1)
LiarCommands ==
    TLCEval({v \in WireViews :
                \/ Defects(v) = 0
                \/ Defects(v) = 1 /\ (Valid(v) \/ Cardinality(v.failed) <= 1)})
\* The same, by switch id <<epoch, seq>> (a receiver looks only at ids newer than its own).
LiarIds == TLCEval({<<v.epoch, v.seq>> : v \in LiarCommands})
LiarCommandsById ==
    TLCEval([id \in LiarIds |-> TLCEval({v \in LiarCommands : <<v.epoch, v.seq>> = id})])
\* Its Activates, checkpoint acknowledgements and checkpoint writes, the latter two with a
\* state of any of its lineages (a restore reply too: NextBy).
LiarActivates == TLCEval([epoch : WireEpochs, seq : 0..MaxSeq])
LiarCheckpointAcks ==
    TLCEval([task : Tasks \cup {BadTask}, version : LiarVersions, lineage : LiarLineages])
LiarWrites ==
    TLCEval([from : {Liar}, task : Tasks \cup {BadTask}, version : LiarVersions,
             lineage : LiarLineages])
\* Its declarations: a lying processing node declares every processing node failed, itself
\* included (only a processing node's declaration of another node has authority; a node's
\* request for its own exclusion is noted as a report too, NodeProtocol::note_report, so it
\* backs an exclusion of that node, though it is no evidence for a take-over).
LiarDeclares(f) == Liar \in ProcessingNodes /\ f \in ProcessingNodes

(***************************************************************************)
(* State                                                                   *)
(***************************************************************************)

\* The correct processing nodes: they follow views, run tasks, and may become Master.
Followers == ProcessingNodes \ {Liar}

VARIABLES
    view,          \* [Followers -> Views]: the view the node follows (the newest it adopted)
    stage,         \* [Followers -> Stages]: the node's progress in that view's switch
    active,        \* [Followers -> SUBSET Tasks]: tasks running on the node
    unflushed,     \* [Followers -> SUBSET Tasks]: stopped, final checkpoint not acknowledged
    version,       \* [Followers -> [Tasks -> WireVersions]]: the state of each task it holds
    lineage,       \* [Followers -> [Tasks -> Lineages]]: the lineage of that state
    fromLiar,      \* ghost [Followers -> [Tasks -> BOOLEAN]]: that state is the liar's
                   \*   (restored from its reply, or from a checkpoint it wrote)
    declared,      \* [Followers -> SUBSET Nodes]: nodes it declared failed on evidence (a
                   \*   Command it refused), for good; every correct node sees them
    vetted,        \* [Followers -> SUBSET ProcessingNodes]: the failed set of the last view
                   \*   the node followed with rule 5's check (a view not excluding it);
                   \*   rule 5 measures the exclusions a view adds against it
    masterStage,   \* [Followers -> MasterStages]: the switch the node drives as Master
    stored,        \* [Tasks -> WireVersions]: the Storage node's checkpoint (when correct)
    storedLineage, \* [Tasks -> Lineages]: the lineage of that checkpoint
    storeEpoch,    \* the epoch the Storage node adopted (when correct): the newest of the
                   \*   Commands it followed
    storedByLiar,  \* ghost [Tasks -> BOOLEAN]: that checkpoint is one the liar wrote
    honestStored,  \* ghost [Tasks -> WireVersions]: the newest version a correct node
                   \*   wrote that the Storage node took as its checkpoint
    startLineage,  \* ghost [Followers -> [Tasks -> Lineages]]: the lineage of the state
                   \*   the node started the task from (before the start rule)
    msgs,          \* env: the correct Masters' Commands and Activates
    acks,          \* env: the correct nodes' "Prepared" and "Activated" acks, each with the
                   \*   view it acks, to every node
    writes,        \* env: the correct nodes' final checkpoint writes
    phaseChanges,  \* planned switches so far
    steps          \* env [Tasks -> 0..MaxSteps]: the steps each task took so far, on any
                   \*   correct node (a bound on the model, not a check of any node's)

\* The lineages' variables: the steps that do not read them leave them alone.
lineageVars == <<lineage, storedLineage, storeEpoch, startLineage>>
vars == <<view, stage, active, unflushed, version, fromLiar, declared, vetted, masterStage,
          stored, storedByLiar, honestStored, msgs, acks, writes, phaseChanges, steps,
          lineageVars>>

Stages == {"Stable", "Deactivating", "Prepared", "Activating"}
MasterStages == {"Idle", "Preparing", "Activating"}

InitialView == [epoch |-> 1, seq |-> 0, config |-> InitialConfig, master |-> Priority[1],
                failed |-> {}]

IsMaster(n) == view[n].master = n

CommandMsg(m, v) == [kind |-> "Command", from |-> m, view |-> v]
ActivateMsg(m, v) == [kind |-> "Activate", from |-> m, epoch |-> v.epoch, seq |-> v.seq]
\* An ack carries the whole view it acks (in the runtime, a digest of it).
AckMsg(k, n, v) == [kind |-> k, from |-> n, view |-> v]

TypeOK ==
    /\ view \in [Followers -> Views]
    /\ stage \in [Followers -> Stages]
    /\ active \in [Followers -> SUBSET Tasks]
    /\ unflushed \in [Followers -> SUBSET Tasks]
    /\ version \in [Followers -> [Tasks -> WireVersions]]
    /\ lineage \in [Followers -> [Tasks -> Lineages]]
    /\ fromLiar \in [Followers -> [Tasks -> BOOLEAN]]
    /\ declared \in [Followers -> SUBSET Nodes]
    /\ vetted \in [Followers -> SUBSET ProcessingNodes]
    /\ masterStage \in [Followers -> MasterStages]
    /\ stored \in [Tasks -> WireVersions]
    /\ storedByLiar \in [Tasks -> BOOLEAN]
    /\ honestStored \in [Tasks -> WireVersions]
    /\ storedLineage \in [Tasks -> Lineages]
    /\ storeEpoch \in 1..MaxEpoch
    /\ startLineage \in [Followers -> [Tasks -> Lineages]]
    /\ writes \subseteq [from : Followers, task : Tasks, version : WireVersions,
                         lineage : Lineages]
    /\ phaseChanges \in 0..MaxPhaseChanges
    /\ steps \in [Tasks -> 0..MaxSteps]

\* The cluster runs the initial configuration: every node follows the initial view, each
\* task runs on its host there from version 0 of the initial lineage.
Init ==
    /\ view = [n \in Followers |-> InitialView]
    /\ stage = [n \in Followers |-> "Stable"]
    /\ active = [n \in Followers |-> TasksOn(InitialView, n)]
    /\ unflushed = [n \in Followers |-> {}]
    /\ version = [n \in Followers |-> [t \in Tasks |-> 0]]
    /\ lineage = [n \in Followers |-> [t \in Tasks |-> InitialLineage]]
    /\ fromLiar = [n \in Followers |-> [t \in Tasks |-> FALSE]]
    /\ declared = [n \in Followers |-> {}]
    /\ vetted = [n \in Followers |-> InitialView.failed]
    /\ masterStage = [n \in Followers |-> "Idle"]
    /\ stored = [t \in Tasks |-> 0]
    /\ storedByLiar = [t \in Tasks |-> FALSE]
    /\ honestStored = [t \in Tasks |-> 0]
    /\ storedLineage = [t \in Tasks |-> InitialLineage]
    /\ storeEpoch = InitialView.epoch
    /\ startLineage = [n \in Followers |-> [t \in Tasks |-> InitialLineage]]
    /\ msgs = {}
    /\ acks = {}
    /\ writes = {}
    /\ phaseChanges = 0
    /\ steps = [t \in Tasks |-> 0]

(***************************************************************************)
(* The receiver rules, one operator each, so that a mutant removes one     *)
(* (NextBy takes them as parameters).                                      *)
(***************************************************************************)

\* Rule 1, bounds: an epoch the wire's width carries, a version within its width. (Ids are
\* checked too, by the actions: a configuration or task id beyond the mission's count is
\* dropped; without that check a receiver would index past its tables.)
EpochInBounds(e) == e \in 1..MaxEpoch
VersionInBounds(v) == v \in 0..MaxVersion

\* Rule 2, authority by role, decided in the receiver's own view:
\* a Command's view comes from its master, the owner of its epoch, which is not stale and
\* at most one lap of the succession above the receiver's epoch;
MayCommand(n, s, v) ==
    /\ s = v.master
    /\ Owner(v.epoch) = s
    /\ view[n].epoch <= v.epoch
    /\ v.epoch <= view[n].epoch + N
\* an Activate comes from the master of the receiver's view;
MayActivate(n, s) == s = view[n].master
\* a checkpoint acknowledgement from the Storage node;
MayAck(s) == s = Storage
\* a restore reply from the Storage node or a node the mission may place the task on;
MayReply(s, t) == s = Storage \/ s \in MayHost(t)
\* the Storage node stores a write only from a node the mission may place the task on.
MayWrite(s, t) == s \in MayHost(t)

\* Rules 2a and 2b, authority over lineages (the runtime's authority table, CheckpointWrite
\* and CheckpointReply): the Storage node takes a checkpoint write only when the epoch of
\* its state's lineage is no newer than its writer's epoch e (else it is refused as
\* unauthorized: no view of that epoch opened it at the writer) nor than the Storage node's
\* own adopted epoch (else it is dropped as ahead: no view of that epoch reached the Storage
\* node yet; an honest host ahead of it repeats its flush until acknowledged, so that one is
\* taken later);
WriteInEpoch(l, e) == LineageEpoch(l) <= e /\ LineageEpoch(l) <= storeEpoch
\* a restore reply from a node other than the Storage node counts only with a state of a
\* lineage no newer than the request's epoch, its receiver's: otherwise it answers as
\* holding nothing. The Storage node's reply counts whatever its lineage (the correct one
\* holds none of an epoch it has not adopted).
ReplyInEpoch(n, s, l) == s = Storage \/ LineageEpoch(l) <= view[n].epoch

\* The start rule (not a receiver check: the host's own): a task that starts from a state
\* of a lineage of an epoch above its host's view runs on in a lineage of that view (its
\* switch id), so that its writes are of its own epoch, which the Storage node takes.
ViewLineage(n) == <<view[n].epoch, view[n].seq>>
RunLineage(n, l) == IF LineageEpoch(l) > view[n].epoch THEN ViewLineage(n) ELSE l

\* The adoption rule (ConfigSwitch::adoptable, wherever a node takes a state): a correct
\* node adopts no state of a count above the adoption bound, AdoptBound = MaxVersion -
\* MaxSteps, though the wire and the Storage node carry any count up to the width. No
\* correct run makes such a count (a task takes at most MaxSteps steps, and MaxSteps <=
\* AdoptBound), and one adopted at the bound still runs to at most the width: a correct
\* node never steps past what the codec carries, whatever count the liar wrote. Where a
\* state above the bound arrives, Activate and Resume say what the node does instead.
Adoptable(v) == v <= AdoptBound

\* A view at seq 0 of an epoch after the first is a hand-over's, written by the Master
\* before it (HandedView.tla); its own Master has yet to make its boot switch. (Here no
\* correct node follows one: a take-over opens its epoch at seq 1.)
IsHanded(v) == v.seq = 0 /\ v.epoch # 1

\* Rule 3, receivers check the Master: the view is structurally valid, and the next switch
\* of the receiver's own view from the same master follows the graph's edge for the nodes
\* it adds to the failed set (Walk), or a phase edge with the same failed set. Only of a
\* view that master commanded itself (seq 1 on) or the initial one (epoch 1, seq 0): a
\* handed view (IsHanded) is written by the Master before, so the next switch of one is
\* held to structural validity only, as one that skips a switch number is
\* (NodeProtocol::command_problem; HandedView.tla, seed 15049).
IsNextSwitch(n, v) ==
    /\ v.epoch = view[n].epoch /\ v.master = view[n].master /\ v.seq = view[n].seq + 1
    /\ ~IsHanded(view[n])
\* The graph's edge from view w to view v (edge_problem): the walk for the nodes v adds to
\* w's failed set, or a phase edge with the same failed set.
Edge(w, v) ==
    \/ /\ w.failed \subseteq v.failed /\ w.failed # v.failed
       /\ v.config = Target(w.config, v.failed \ w.failed, v.failed)
    \/ /\ v.failed = w.failed
       /\ v.config \in OnPhase(w.config)
OnEdge(n, v) == IsNextSwitch(n, v) => Edge(view[n], v)
Checked(n, v) == Valid(v) /\ OnEdge(n, v)

\* Rule 4, peers' Prepared: node n takes the Activate of its view's switch only once it
\* holds, from every node its view does not exclude other than itself, a "Prepared" ack of
\* exactly that view. The followers are the correct ones; the liar's ack, for any view, is
\* taken as sent.
PeersPrepared(n) ==
    \A p \in Followers \ (view[n].failed \cup {n}) : AckMsg("Prepared", p, view[n]) \in acks

\* Rule 5, backed exclusions: node n follows a Command from s whose view v excludes n
\* itself unchecked (it only stops what n runs: an excluded node runs and starts nothing).
\* Any other it follows only when every node v excludes beyond vetted[n], the failed set of
\* the last view n followed with this check, was declared failed by a node other than s,
\* in a declaration n has seen: a correct node's on evidence (n's own among them), or the
\* liar's; or when a node other than s and n that v does not exclude vouches for v: its
\* "Prepared" of exactly v says it followed v, so v's exclusions were backed where it
\* checked them. The liar's "Prepared", of any view, is taken as sent.
Declarers(f) ==
    {p \in Followers : f \in declared[p]} \cup (IF LiarDeclares(f) THEN {Liar} ELSE {})
Vouched(n, s, v) ==
    \/ \E p \in Followers \ (v.failed \cup {s, n}) : AckMsg("Prepared", p, v) \in acks
    \/ Liar \notin v.failed \cup {s}
BackedSince(F, n, s, v) ==
    \/ n \in v.failed
    \/ \A f \in v.failed \ F : Declarers(f) \ {s} # {}
    \/ Vouched(n, s, v)
Backed(n, s, v) == BackedSince(vetted[n], n, s, v)

(***************************************************************************)
(* Receivers                                                               *)
(***************************************************************************)

\* Node n takes a Command from s whose view v is newer than its own, in bounds and sent
\* with authority. If v passes the checks, n adopts it (a Master of an older view steps
\* down) and starts the switch, once the exclusions it adds are backed (at once if v
\* excludes n), and, unless v excludes n, v's failed set is what n has vetted; if not, n
\* refuses it and declares s failed, for good: the refused Command is evidence against its
\* sender, and no later message withdraws it. (A Command that is not newer, out of bounds
\* or without authority is dropped, and one not yet backed is not followed, without
\* evidence: its backing may come later, and the Master retransmits. Both are stuttering
\* steps, left out.)
ReceiveCommand(EpochOk(_), MayCommandOp(_, _, _), CheckedOp(_, _), BackedOp(_, _, _),
               n, s, v) ==
    /\ Newer(v, view[n])
    /\ EpochOk(v.epoch) /\ v.config \in KnownConfigs
    /\ MayCommandOp(n, s, v)
    /\ IF CheckedOp(n, v)
       THEN /\ BackedOp(n, s, v)
            /\ view' = [view EXCEPT ![n] = v]
            /\ stage' = [stage EXCEPT ![n] = "Deactivating"]
            /\ masterStage' = [masterStage EXCEPT ![n] = "Idle"]
            /\ vetted' = IF n \in v.failed THEN vetted ELSE [vetted EXCEPT ![n] = v.failed]
            /\ UNCHANGED declared
       ELSE /\ s \notin declared[n]
            /\ declared' = [declared EXCEPT ![n] = @ \cup {s}]
            /\ UNCHANGED <<view, stage, masterStage, vetted>>
    /\ UNCHANGED <<active, unflushed, version, fromLiar, stored, storedByLiar, honestStored,
                   msgs, acks, writes, phaseChanges, steps, lineageVars>>

\* Node n's checkpoint write of t: its state, lineage and count.
WriteOf(n, t) ==
    [from |-> n, task |-> t, version |-> version[n][t], lineage |-> lineage[n][t]]

\* Node n stops task t, which its view places elsewhere, and sends its final checkpoint.
Deactivate(n, t) ==
    /\ stage[n] = "Deactivating"
    /\ t \in active[n]
    /\ PlacedOn(view[n], t) # n
    /\ active' = [active EXCEPT ![n] = @ \ {t}]
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \cup {t}]
    /\ writes' = writes \cup {WriteOf(n, t)}
    /\ UNCHANGED <<view, stage, version, fromLiar, declared, vetted, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, phaseChanges, steps,
                   lineageVars>>

\* The Storage node takes write w, sent in its writer's epoch e, as its checkpoint when it
\* is in bounds, from a writer with authority, of a lineage in epoch (WriteInEpoch), and
\* newer than the one it holds, lineage first (the newest is kept).
StoreWrite(VersionOk(_), MayWriteOp(_, _), WriteInEpochOp(_, _), w, e) ==
    /\ Storage # Liar
    /\ w.task \in Tasks
    /\ VersionOk(w.version)
    /\ MayWriteOp(w.from, w.task)
    /\ WriteInEpochOp(w.lineage, e)
    /\ IF StateGt(w.lineage, w.version, storedLineage[w.task], stored[w.task])
       THEN /\ stored' = [stored EXCEPT ![w.task] = w.version]
            /\ storedLineage' = [storedLineage EXCEPT ![w.task] = w.lineage]
            /\ storedByLiar' = [storedByLiar EXCEPT ![w.task] = (w.from = Liar)]
            /\ honestStored' = IF w.from = Liar THEN honestStored
                               ELSE [honestStored EXCEPT ![w.task] = w.version]
       ELSE UNCHANGED <<stored, storedLineage, storedByLiar, honestStored>>
    /\ UNCHANGED <<lineage, storeEpoch, startLineage, steps>>

\* The correct Storage node receives n's final checkpoint of t, sent in n's epoch, and
\* acknowledges it (one step: the acknowledgement carries the state it holds, at least
\* n's). A write it drops is not acknowledged: n repeats it (the channel may hold it
\* back), and this step waits until the Storage node takes it.
FlushCheckpoint(VersionOk(_), MayWriteOp(_, _), WriteInEpochOp(_, _), n, t) ==
    /\ t \in unflushed[n]
    /\ StoreWrite(VersionOk, MayWriteOp, WriteInEpochOp, WriteOf(n, t), view[n].epoch)
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \ {t}]
    /\ UNCHANGED <<view, stage, active, version, fromLiar, declared, vetted, masterStage,
                   msgs, acks, writes, phaseChanges>>

\* The Storage node receives a write again (the channel duplicates), or one whose
\* acknowledgement its writer took from elsewhere, or one of the liar's, sent in epoch e.
StoreCheckpoint(VersionOk(_), MayWriteOp(_, _), WriteInEpochOp(_, _), w, e) ==
    /\ StoreWrite(VersionOk, MayWriteOp, WriteInEpochOp, w, e)
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, declared, vetted,
                   masterStage, msgs, acks, writes, phaseChanges>>

\* Node n takes an acknowledgement from s of its final checkpoint of t, for the state of
\* lineage l and count v (an acknowledgement below n's state is one of an older write).
ReceiveCheckpointAck(VersionOk(_), MayAckOp(_), n, s, t, l, v) ==
    /\ t \in Tasks
    /\ VersionOk(v)
    /\ MayAckOp(s)
    /\ t \in unflushed[n]
    /\ StateGeq(l, v, lineage[n][t], version[n][t])
    /\ unflushed' = [unflushed EXCEPT ![n] = @ \ {t}]
    /\ UNCHANGED <<view, stage, active, version, fromLiar, declared, vetted, masterStage,
                   stored, storedByLiar, honestStored, msgs, acks, writes, phaseChanges,
                   steps, lineageVars>>

\* Every task leaving n is stopped and acknowledged (phase 1 done), or every task placed
\* on n runs (phase 2 done): n acks.
ReadyToAck(n, kind) ==
    IF kind = "Prepared"
    THEN /\ stage[n] = "Deactivating"
         /\ \A t \in active[n] : PlacedOn(view[n], t) = n
         /\ unflushed[n] = {}
    ELSE /\ stage[n] = "Activating"
         /\ TasksOn(view[n], n) \subseteq active[n]

Ack(n, kind) ==
    /\ ReadyToAck(n, kind)
    /\ stage' = [stage EXCEPT ![n] = IF kind = "Prepared" THEN "Prepared" ELSE "Stable"]
    /\ acks' = acks \cup {AckMsg(kind, n, view[n])}
    /\ UNCHANGED <<view, active, unflushed, version, fromLiar, declared, vetted,
                   masterStage, stored, storedByLiar, honestStored, msgs, writes,
                   phaseChanges, steps, lineageVars>>

\* Node n takes the Activate of its view's switch from s, once its peers prepared that
\* view (until then it holds it: the channel may hold any message back).
ReceiveActivate(EpochOk(_), MayActivateOp(_, _), PeersPreparedOp(_), n, s, e, q) ==
    /\ stage[n] = "Prepared"
    /\ EpochOk(e)
    /\ MayActivateOp(n, s)
    /\ e = view[n].epoch /\ q = view[n].seq
    /\ PeersPreparedOp(n)
    /\ stage' = [stage EXCEPT ![n] = "Activating"]
    /\ UNCHANGED <<view, active, unflushed, version, fromLiar, declared, vetted,
                   masterStage, stored, storedByLiar, honestStored, msgs, acks, writes,
                   phaseChanges, steps, lineageVars>>

\* Node n starts task t, which its view places on it, from s's restore reply for its
\* view's switch, carrying the state of lineage l and count v. A state it may adopt
\* (AdoptableOp) it runs on in the lineage the start rule gives (RunLineageOp). One above
\* the adoption bound it does not adopt: from a node other than the Storage node (a holder,
\* ConfigSwitch::receive_checkpoint_reply while gathering), the reply counts as holding
\* nothing, and n takes another; from the Storage node, the state is lost: n starts the
\* task from no state, count 0, in a new lineage named by its view's switch id
\* (ConfigSwitch::receive_checkpoint_reply), newer than the stored state when that is of
\* a lineage no newer than n's view, so that n's writes are taken.
Activate(VersionOk(_), MayReplyOp(_, _), ReplyInEpochOp(_, _, _), RunLineageOp(_, _),
         AdoptableOp(_), n, t, s, l, v) ==
    /\ stage[n] = "Activating"
    /\ PlacedOn(view[n], t) = n
    /\ t \notin active[n]
    /\ VersionOk(v)
    /\ MayReplyOp(s, t)
    /\ ReplyInEpochOp(n, s, l)
    /\ s = Storage \/ AdoptableOp(v)
    /\ active' = [active EXCEPT ![n] = @ \cup {t}]
    /\ IF AdoptableOp(v)
       THEN /\ version' = [version EXCEPT ![n][t] = v]
            /\ lineage' = [lineage EXCEPT ![n][t] = RunLineageOp(n, l)]
            /\ startLineage' = [startLineage EXCEPT ![n][t] = l]
            /\ fromLiar' = [fromLiar EXCEPT ![n][t] =
                               IF s = Liar THEN TRUE ELSE storedByLiar[t]]
       ELSE /\ version' = [version EXCEPT ![n][t] = 0]
            /\ lineage' = [lineage EXCEPT ![n][t] = ViewLineage(n)]
            /\ startLineage' = [startLineage EXCEPT ![n][t] = ViewLineage(n)]
            /\ fromLiar' = [fromLiar EXCEPT ![n][t] = FALSE]
    /\ UNCHANGED <<view, stage, unflushed, declared, vetted, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, writes, phaseChanges, steps,
                   storedLineage, storeEpoch>>

\* Node n resumes task t, which it runs, after a hold (Lease.tla: the spec has no leases,
\* and since the channel may hold back any message a correct node's hold may end at any
\* time): it asks the Storage node s, whose reply carries the state of lineage l and count
\* v, and takes that state when it is newer than its own, compared as it will run (the
\* start rule), and it may adopt it; otherwise it resumes from its own, which is no step
\* (ConfigSwitch::resume_released). An excluded node resumes nothing.
Resume(VersionOk(_), RunLineageOp(_, _), AdoptableOp(_), n, t, s, l, v) ==
    /\ t \in active[n]
    /\ n \notin view[n].failed
    /\ VersionOk(v)
    /\ AdoptableOp(v)
    /\ StateGt(RunLineageOp(n, l), v, lineage[n][t], version[n][t])
    /\ version' = [version EXCEPT ![n][t] = v]
    /\ lineage' = [lineage EXCEPT ![n][t] = RunLineageOp(n, l)]
    /\ startLineage' = [startLineage EXCEPT ![n][t] = l]
    /\ fromLiar' = [fromLiar EXCEPT ![n][t] = IF s = Liar THEN TRUE ELSE storedByLiar[t]]
    /\ UNCHANGED <<view, stage, active, unflushed, declared, vetted, masterStage, stored,
                   storedByLiar, honestStored, msgs, acks, writes, phaseChanges, steps,
                   storedLineage, storeEpoch>>

\* The epochs of the liar's Commands that have authority somewhere: its own, on the wire.
LiarOwnEpochs == TLCEval({v.epoch : v \in {w \in LiarCommands : Defects(w) = 0}})

\* The correct Storage node follows a Command of epoch e, newer than its own, in bounds and
\* at most one lap of the succession above its epoch (MayCommand): a correct Master's, or
\* one of the liar's without a defect. Only its epoch is modelled (the Storage node takes
\* no part in switches here), and it follows any such Command, unchecked by rules 3 to 5:
\* more epochs than the runtime's, so more of the liar's writes pass WriteInEpoch.
StorageAdoptEpoch(EpochOk(_), e) ==
    /\ Storage # Liar
    /\ EpochOk(e)
    /\ storeEpoch < e /\ e <= storeEpoch + N
    /\ storeEpoch' = e
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, declared, vetted,
                   masterStage, stored, storedByLiar, honestStored, msgs, acks, writes,
                   phaseChanges, steps, lineage, storedLineage, startLineage>>

(***************************************************************************)
(* Masters (correct ones)                                                  *)
(***************************************************************************)

\* Master m starts the switch to view v: it broadcasts the Command and applies it at once.
StartSwitch(m, v) ==
    /\ view' = [view EXCEPT ![m] = v]
    /\ stage' = [stage EXCEPT ![m] = "Deactivating"]
    /\ masterStage' = [masterStage EXCEPT ![m] = "Preparing"]
    /\ msgs' = msgs \cup {CommandMsg(m, v)}

\* Master m declared f failed on evidence: it switches along the graph's edge. (A Master
\* handed its view makes its boot switch first: HandedView.tla's BootSwitch.)
Exclude(m, f) ==
    /\ IsMaster(m)
    /\ ~IsHanded(view[m])
    /\ f \in declared[m] \ view[m].failed
    /\ f \in ProcessingNodes
    /\ LET F == view[m].failed \cup {f}
       IN  StartSwitch(m, [epoch |-> view[m].epoch, seq |-> view[m].seq + 1,
                           config |-> Target(view[m].config, {f}, F), master |-> m,
                           failed |-> F])
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, vetted, stored,
                   storedByLiar, honestStored, acks, writes, phaseChanges, steps,
                   lineageVars>>

\* Master m starts a planned switch to c (a mission-phase change), between switches; not
\* to a configuration that places a task on a node its view excludes (refused, as
\* ReconfigurationManager::on_phase does).
RequestPhase(m, c) ==
    /\ IsMaster(m)
    /\ ~IsHanded(view[m])
    /\ masterStage[m] = "Idle"
    /\ phaseChanges < MaxPhaseChanges
    /\ c \in OnPhase(view[m].config)
    /\ \A t \in Tasks : Host(c, t) \notin view[m].failed
    /\ phaseChanges' = phaseChanges + 1
    /\ StartSwitch(m, [view[m] EXCEPT !.seq = @ + 1, !.config = c])
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, vetted, stored,
                   storedByLiar, honestStored, acks, writes, steps, lineageVars>>

\* Every correct node the view does not exclude acked kind for m's switch (the liar, if
\* the view does not exclude it, may ack anything at any time: its acks are taken as sent).
AllAcked(m, kind) ==
    \A n \in Followers \ view[m].failed : AckMsg(kind, n, view[m]) \in acks

BroadcastActivate(m) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Preparing"
    /\ AllAcked(m, "Prepared")
    /\ masterStage' = [masterStage EXCEPT ![m] = "Activating"]
    /\ msgs' = msgs \cup {ActivateMsg(m, view[m])}
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, declared, vetted,
                   stored, storedByLiar, honestStored, acks, writes, phaseChanges,
                   steps, lineageVars>>

CompleteSwitch(m) ==
    /\ IsMaster(m)
    /\ masterStage[m] = "Activating"
    /\ AllAcked(m, "Activated")
    /\ masterStage' = [masterStage EXCEPT ![m] = "Idle"]
    /\ UNCHANGED <<view, stage, active, unflushed, version, fromLiar, declared, vetted,
                   stored, storedByLiar, honestStored, msgs, acks, writes, phaseChanges,
                   steps, lineageVars>>

\* The first epoch after n's that n owns, and the owners of the epochs in between.
NextEpoch(n) ==
    LET e == view[n].epoch IN e + 1 + ((Rank(n) - ((e % N) + 1)) % N)
Ahead(n) == {Owner(e) : e \in (view[n].epoch + 1)..(NextEpoch(n) - 1)} \ {n}

\* Node n takes over (MasterElection's BecomeMaster): it declared the master of its view
\* and every owner of the epochs before its next one. It claims that epoch, if the wire
\* carries it, and switches to the graph's configuration without them (Safe if that one's
\* master is another node).
BecomeMaster(n) ==
    /\ ~IsMaster(n)
    /\ n \notin view[n].failed
    /\ view[n].master \in declared[n]
    /\ Ahead(n) \subseteq declared[n]
    /\ NextEpoch(n) <= MaxEpoch
    /\ LET F == view[n].failed \cup {view[n].master} \cup Ahead(n)
           w == Target(view[n].config, F \ view[n].failed, F)
       IN  StartSwitch(n, [epoch |-> NextEpoch(n), seq |-> 1,
                           config |-> IF w # Safe /\ ConfigMaster(w) = n THEN w ELSE Safe,
                           master |-> n, failed |-> F])
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, vetted, stored,
                   storedByLiar, honestStored, acks, writes, phaseChanges, steps,
                   lineageVars>>

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* Task t runs one step on n, one of the MaxSteps it takes in the run. Only the run's length
\* bounds a step, not the width: that no correct node steps past the width is
\* VersionBoundInv's, which the adoption rule keeps.
Execute(n, t) ==
    /\ t \in active[n]
    /\ steps[t] < MaxSteps
    /\ version' = [version EXCEPT ![n][t] = @ + 1]
    /\ steps' = [steps EXCEPT ![t] = @ + 1]
    /\ UNCHANGED <<view, stage, active, unflushed, fromLiar, declared, vetted, masterStage,
                   stored, storedByLiar, honestStored, msgs, acks, writes, phaseChanges,
                   lineageVars>>

(***************************************************************************)
(* Next-state relation                                                     *)
(***************************************************************************)

\* The epochs of the Commands on the wire that the Storage node may follow.
WireCommandEpochs ==
    {msg.view.epoch : msg \in {m \in msgs : m.kind = "Command"}} \cup LiarOwnEpochs

\* The next-state relation with the given receiver rules and start rule (a mutant passes
\* one broken). The liar takes no step: its messages are on the wire from the start; its
\* checkpoint writes claim any writer epoch (here the widest, so that the writer's epoch
\* never binds them: the Storage node's own does).
NextLineageBy(EpochOk(_), VersionOk(_), MayCommandOp(_, _, _), CheckedOp(_, _),
              MayActivateOp(_, _), MayAckOp(_), MayReplyOp(_, _), MayWriteOp(_, _),
              PeersPreparedOp(_), BackedOp(_, _, _), WriteInEpochOp(_, _),
              ReplyInEpochOp(_, _, _), RunLineageOp(_, _), AdoptableOp(_)) ==
    \* Receivers
    \/ \E n \in Followers :
          \/ \E msg \in msgs :
                /\ msg.kind = "Command"
                /\ ReceiveCommand(EpochOk, MayCommandOp, CheckedOp, BackedOp, n, msg.from,
                                  msg.view)
          \/ \E id \in LiarIds :
                /\ Newer([epoch |-> id[1], seq |-> id[2]], view[n])
                /\ \E v \in LiarCommandsById[id] :
                      ReceiveCommand(EpochOk, MayCommandOp, CheckedOp, BackedOp, n, Liar, v)
    \/ \E n \in Followers :
          \/ \E msg \in msgs :
                /\ msg.kind = "Activate"
                /\ ReceiveActivate(EpochOk, MayActivateOp, PeersPreparedOp, n, msg.from,
                                   msg.epoch, msg.seq)
          \/ \E a \in LiarActivates :
                ReceiveActivate(EpochOk, MayActivateOp, PeersPreparedOp, n, Liar, a.epoch,
                                a.seq)
    \/ \E n \in Followers, t \in Tasks : Deactivate(n, t)
    \/ \E n \in Followers, t \in Tasks :
          FlushCheckpoint(VersionOk, MayWriteOp, WriteInEpochOp, n, t)
    \/ \E w \in writes :
          StoreCheckpoint(VersionOk, MayWriteOp, WriteInEpochOp, w, view[w.from].epoch)
    \/ \E w \in LiarWrites :
          StoreCheckpoint(VersionOk, MayWriteOp, WriteInEpochOp, w, MaxEpoch)
    \/ \E e \in WireCommandEpochs : StorageAdoptEpoch(EpochOk, e)
    \/ \E n \in Followers, a \in LiarCheckpointAcks :
          ReceiveCheckpointAck(VersionOk, MayAckOp, n, Liar, a.task, a.lineage, a.version)
    \/ \E n \in Followers, k \in {"Prepared", "Activated"} : Ack(n, k)
    \/ \E n \in Followers, t \in Tasks :
          \/ /\ Storage # Liar
             /\ Activate(VersionOk, MayReplyOp, ReplyInEpochOp, RunLineageOp, AdoptableOp,
                         n, t, Storage, storedLineage[t], stored[t])
          \/ \E v \in LiarVersions, l \in LiarLineages :
                Activate(VersionOk, MayReplyOp, ReplyInEpochOp, RunLineageOp, AdoptableOp,
                         n, t, Liar, l, v)
    \/ \E n \in Followers, t \in Tasks :
          \/ /\ Storage # Liar
             /\ Resume(VersionOk, RunLineageOp, AdoptableOp, n, t, Storage,
                       storedLineage[t], stored[t])
          \/ /\ Storage = Liar
             /\ \E v \in LiarVersions, l \in LiarLineages :
                   Resume(VersionOk, RunLineageOp, AdoptableOp, n, t, Liar, l, v)
    \* Correct Masters
    \/ \E m \in Followers, f \in Nodes : Exclude(m, f)
    \/ \E m \in Followers, c \in ConfigIds : RequestPhase(m, c)
    \/ \E m \in Followers : BroadcastActivate(m)
    \/ \E m \in Followers : CompleteSwitch(m)
    \/ \E n \in Followers : BecomeMaster(n)
    \* Environment
    \/ \E n \in Followers, t \in Tasks : Execute(n, t)

\* The same with the lineage rules and the adoption rule of the spec (the mutants of the
\* other rules pass those).
NextBy(EpochOk(_), VersionOk(_), MayCommandOp(_, _, _), CheckedOp(_, _),
       MayActivateOp(_, _), MayAckOp(_), MayReplyOp(_, _), MayWriteOp(_, _),
       PeersPreparedOp(_), BackedOp(_, _, _)) ==
    NextLineageBy(EpochOk, VersionOk, MayCommandOp, CheckedOp, MayActivateOp, MayAckOp,
                  MayReplyOp, MayWriteOp, PeersPreparedOp, BackedOp, WriteInEpoch,
                  ReplyInEpoch, RunLineage, Adoptable)

Next == NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked, MayActivate, MayAck,
               MayReply, MayWrite, PeersPrepared, Backed)

Spec == Init /\ [][Next]_vars

\* For the liveness of flushes (FlushLiveness): the correct Storage node takes a
\* correct node's final checkpoint that it may take, and follows a Command of a newer epoch
\* on the wire. No other step need happen: a switch may stall (ValueFault checks no other
\* liveness), and no node need adopt a newer view.
LineageFairness ==
    /\ \A n \in Followers, t \in Tasks :
          WF_vars(FlushCheckpoint(VersionInBounds, MayWrite, WriteInEpoch, n, t))
    /\ WF_vars(\E e \in WireCommandEpochs : StorageAdoptEpoch(EpochInBounds, e))

LineageSpec == Spec /\ LineageFairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* (a) The correct nodes that follow views of one epoch agree on its master: no two nodes
\* run as Master in one epoch, nor in one view.
OneMasterPerEpochInv ==
    \A n, m \in Followers : view[n].epoch = view[m].epoch => view[n].master = view[m].master

\* (b) No task runs on two correct nodes at once.
NoDoubleActivationInv ==
    \A t \in Tasks, n, m \in Followers : (t \in active[n] /\ t \in active[m]) => n = m

\* (c) Every correct node follows a structurally valid view of the graph (or Safe), and
\* out of a switch's first phase runs only the tasks that view places on it.
ValidConfigInv ==
    \A n \in Followers :
        /\ Valid(view[n])
        /\ stage[n] # "Deactivating" => active[n] \subseteq TasksOn(view[n], n)

\* (d) With a correct Storage node, no correct node runs a task below the newest version a
\* correct node wrote and the Storage node took (no regression) ... (Counts, compared alone:
\* the models that check it keep every state in the initial lineage. In the models with
\* lineages the liar is the Storage node or may host every task: it says nothing there.)
NoRegressionInv ==
    Storage # Liar =>
        \A n \in Followers, t \in Tasks :
            (t \in active[n] /\ Liar \notin MayHost(t)) => version[n][t] >= honestStored[t]

\* ... nor from a state the liar made, unless the mission may place the task on the liar
\* (a state within its own authority, which fault model 3 does not cover).
NoForeignStateInv ==
    Storage # Liar =>
        \A n \in Followers, t \in Tasks :
            (t \in active[n] /\ fromLiar[n][t]) => Liar \in MayHost(t)

\* The checks cost a correct cluster nothing: no correct node refuses a correct Master's
\* Command, so none declares a correct node failed (keel-sim's NoHonestRefusalInv, here for
\* refusals as no Master's; no correct message is dropped in these models either).
NoHonestRefusalInv == \A n \in Followers : declared[n] \subseteq {Liar}

\* (e) No correct node's epoch exceeds the wire's width; nor does the version of a task a
\* correct node runs or has to flush, or of a checkpoint the correct Storage node holds. A
\* step is bounded by the run's length alone (MaxSteps), so a node that adopted a state too
\* close to the width would step past it, and its writes would not decode.
EpochBoundInv == \A n \in Followers : view[n].epoch <= MaxEpoch
VersionBoundInv ==
    /\ \A n \in Followers, t \in Tasks :
          t \in active[n] \cup unflushed[n] => version[n][t] <= MaxVersion
    /\ Storage # Liar => \A t \in Tasks : stored[t] <= MaxVersion

\* (f) Lineages. No correct node runs a task, or holds one to flush, in a lineage of an
\* epoch above its view's: no write of a correct node is from the future, which the Storage
\* node would refuse (keel-sim --liar, prototype3 seed 12602).
NoFutureLineageInv ==
    \A n \in Followers, t \in Tasks :
        t \in active[n] \cup unflushed[n] => LineageEpoch(lineage[n][t]) <= view[n].epoch

\* The highest epoch a correct node adopted: a processing node's view's, or the Storage
\* node's.
AdoptedEpoch ==
    LET es == {view[n].epoch : n \in Followers} \cup {storeEpoch}
    IN  CHOOSE e \in es : \A x \in es : x <= e

\* With a correct Storage node: it holds no state of a lineage of an epoch it has not
\* adopted (keel-sim --liar, prototype3 seeds 244 and 1544) ...
StoredAdoptedInv ==
    Storage # Liar => \A t \in Tasks : LineageEpoch(storedLineage[t]) <= storeEpoch

\* ... and no correct node runs a task it started from a state of a lineage of an epoch no
\* correct node had adopted: a lineage no view opened yet, so the liar's claim. (With a
\* lying Storage node its store is within the liar's authority, as in (d).)
NoFutureStateInv ==
    Storage # Liar =>
        \A n \in Followers, t \in Tasks :
            t \in active[n] => LineageEpoch(startLineage[n][t]) <= AdoptedEpoch

\* With a correct Storage node, every final flush of a correct node is acknowledged in the
\* end (under LineageFairness): none waits for good (the seed-12602 stall).
FlushLiveness ==
    Storage # Liar =>
        \A n \in Followers, t \in Tasks : t \in unflushed[n] ~> t \notin unflushed[n]

=============================================================================
