// NodeProtocol: one node's protocol state machines, composed, behind one step/tick API in
// the shape of etcd raft's Node (events in, actions out; no IO, no clock, no threads).
//
// It owns the node's HeartbeatMonitor, Election, ReconfigurationManager, ConfigSwitch and,
// on the Storage node, the CheckpointStore. The node runtime (keel-node, over DDS) and the
// deterministic simulator (keel-sim) drive the same class.
//
// The contract, in the order the caller must honour it:
//  1. Construct at boot with the current time. First boot (no PersistentState): every node
//     holds the initial view (the first phase's initial configuration, epoch 1, seq 0,
//     Stable) and runs nothing — no node activates anything by itself, since real
//     processes do not start at the same instant. The initial Master (the view's master)
//     boots as Master and at once starts an ordinary two-phase switch to the same
//     configuration at seq 1 (the boot switch): Command, every live node acks Prepared,
//     Activate, nodes start their tasks (checkpointed ones from the Storage node), acks
//     Activated, CompleteSwitch. The Master retransmits every period, so a node that
//     boots late joins the boot switch; a node declared failed before it booted is fenced
//     by the Master's Command and never activates. Should the Master die first, the
//     Observers' take-over walks the graph from the initial view as after any failure.
//     After a crash, construct with the PersistentState the previous incarnation left
//     (persistent_state(), which the caller saves after every call): the node boots as
//     a Worker running nothing and waits to be commanded.
//  2. Feed events, each with the current time, never decreasing:
//       step(message, now)      a message arrived (decode it with codec.hpp first; drop
//                               what fails to decode)
//       tick(now)               when now >= next_tick_ns(); calling it earlier is harmless
//       task_stepped(t, s, now) the application executed task t once; s is its new state
//       request_phase(p, now)   the ground or the mission timeline asks for phase p (only
//                               the Master acts on it; a PhaseRequest from another node
//                               is unauthorized)
//       ground_exclude(n, now), ground_readmit(n, now)  the ground holds node n out of the
//                               cluster, or lets it back (core/node/ground.hpp)
//       request_recovery(c, now) the ground names configuration c to leave safe mode for
//                               (only the Master acts on it)
//       resign(now)             the node asks the cluster to treat it as failed (a task
//                               keeps failing here after its local restarts, and the
//                               decision graph, keyed by node, relocates what it hosts)
//  3. After each call, take_ready() and carry out the actions in the order given
//     (actions.hpp says what each means). Sends to the node itself never appear: they are
//     delivered internally, in order, before the call returns. The state machines have
//     already moved on; a lost Send is the channel's business (the protocols retransmit).
//  4. Fault model 2 (spec/Exclusion.tla): the Master excludes a node only on evidence a
//     single faulty monitor cannot fabricate: two current declarations among the monitors
//     still in the cluster (its own and the Observers' ErrorNotifications), or one when it
//     is the last monitor; a node's own word (a restart, `excluded` in its heartbeat, a
//     resign request) needs nothing more. A take-over is the Master's exclusion, on the
//     same evidence: an Observer reports a declared monitor to the other Observers too,
//     and takes over only with two monitors' declarations on every node ahead of it (its
//     own and another's), or its own alone when it is the last monitor. A Master that
//     hears no other node for miss_limit - 1 periods is cut off: it steps down as resign()
//     does, before the Observers, which declare it after miss_limit periods, take over.
//     So does a Master whose own period boundary is more than miss_limit - 1 periods
//     overdue when it next gets to run (paused, starved): its lease ran out, and it stops
//     before it acts on what arrived meanwhile.
//     The lease (spec/Lease.tla): every monitor's heartbeat acknowledges the last
//     heartbeat it heard from each node, and a node runs only while fewer of its voters
//     (the monitors of its view but itself) may hold it failed than an exclusion of it
//     needs: a voter may once miss_limit periods have passed since the send time of the
//     node's last heartbeat it acknowledged (less a quarter period of margin). A Master
//     whose lease lapses steps down as resign() does, before the Observers can take over
//     (a Master acknowledged only from a newer epoch holds no lease); the initial Master
//     starts the boot switch only once it holds its lease. Any other node holds its tasks
//     (they stop, and stay placed here) until its acknowledgements come back, before the
//     Master can move them. An Observer whose lease lapsed does not take over.
//     Reintegration (spec/Rejoin.tla): an excluded node that this Master hears for
//     kRejoinPeriods periods in a row, saying it knows itself excluded from this epoch on
//     (it adopted this Master's fencing Command, so it hears the Master too), is
//     readmitted: the cluster moves to Topology::recovery_target, the mission's
//     on_recovery edge or else the configuration of the smaller failed set (from safe
//     mode too). Every node that adopts the view
//     forgets what it counted and declared of the readmitted node, which forgets what
//     it declared itself, and runs again only with its lease. When that configuration is
//     another node's, this Master hands the view over (ReconfigurationManager::hand_over):
//     a Command for that node's next epoch at seq 0, which this Master adopts itself (it
//     stops driving at once) and repeats to the new Master until that one commands; the
//     new Master starts driving, as the initial Master boots, once it holds its lease.
//  5. Stale messages (an epoch below the node's) are rejected in step(), in one place,
//     before any role-specific handling; heartbeats and phase requests carry no epoch.
//
// Limits: one call delivers at most kMaxInternalDeliveries self-addressed messages.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/fsm/actions.hpp"
#include "core/fsm/admission.hpp"
#include "core/fsm/checkpoint_store.hpp"
#include "core/fsm/config_switch.hpp"
#include "core/fsm/election.hpp"
#include "core/fsm/heartbeat_monitor.hpp"
#include "core/fsm/mutants.hpp"
#include "core/fsm/reconfiguration_manager.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

inline constexpr int kMaxInternalDeliveries = 4096;
// Periods, per miss limit, a Master must hear an excluded node without a gap before it
// readmits it (a node that flaps is not readmitted each time it is heard once).
inline constexpr int kRejoinPeriodsPerMissLimit = 2;

struct NodeOptions {
    // Emit act::Trace actions (NDJSON trace lines); off, the machines skip building them.
    bool tracing = false;
    // Offset of this node's heartbeat period boundaries from time zero, in [0, period).
    TimeNs phase_offset_ns = 0;
    Mutant mutant = Mutant::none;  // tests only (mutants.hpp)
    // First boot of the Storage node whose durable checkpoint store outlived a
    // whole-cluster power cycle: the checkpoints it kept, so the boot switch's activations
    // resume from them. Ignored on other nodes and on a restart (PersistentState carries
    // the checkpoints there).
    std::vector<StoredCheckpoint> kept_checkpoints;
    // This boot's identifier, drawn at random at each boot (keel-node reads the OS's
    // random source; keel-sim makes one per boot of each node) and sent in every
    // heartbeat: monitors see a restart by it even when the saved incarnation went back
    // (HeartbeatMonitor). 0 (the default, as in unit tests) is an identifier like any: an
    // embedder that never sets it loses restart detection by boot.
    std::uint32_t boot = 0;
    // The boot before this one (the one the saved state was written by; also kept by a
    // --cold-start, which discards the rest); 0: none, or take PersistentState::boot.
    std::uint32_t previous_boot = 0;
    // The first 64 bits of the SHA-256 of the mission image this node flies (keel-node:
    // the verified image's hash); 0: not compared. A node whose heartbeats name another
    // image takes no part here: everything it sends is dropped (counted, foreign_image)
    // until a heartbeat names this node's image.
    std::uint64_t image = 0;
};

// What survives a crash: the spec's persisted `epoch`, the last view accepted, the boot
// counter, and on the Storage node its checkpoints.
struct PersistentState {
    Epoch epoch = 0;
    View view;
    std::uint32_t incarnation = 0;
    std::uint32_t boot = 0;  // the boot that saved it (NodeOptions::boot)
    std::vector<StoredCheckpoint> checkpoints;
    // The nodes the ground holds out of the cluster (ground_exclude): no Master readmits
    // them until the ground readmits them.
    NodeSet held_out;
    // The tasks the ground paused (ground_pause): they stay paused across the restart.
    TaskSet paused;
};

// Counters for benchmarks and logs.
struct NodeStats {
    std::uint64_t stale_rejected = 0;
    std::uint64_t switches_started = 0;
    std::uint64_t switches_completed = 0;
    // Times the Master considered a declaration or report and did not act on it for lack
    // of a second monitor's evidence (it reconsiders each period and on each report). A
    // reliability counter: a single deaf or starved monitor shows up here instead of in an
    // exclusion.
    std::uint64_t exclusions_withheld = 0;
    // Ticks at which the acting Master, idle, left the nodes the ground holds out not
    // excluded, because the graph's edges from its view for them (with the failures
    // pending and the other nodes held out) lead to safe mode (docs/operations.md,
    // `exclude`). In the status line as `ground_withheld`.
    std::uint64_t ground_exclusions_withheld = 0;
    // This node stepped down as Master because it heard no other node (cut off).
    std::uint64_t cut_off_step_downs = 0;
    // This node stepped down as Master because its own loop stalled past its lease.
    std::uint64_t stall_step_downs = 0;
    // This node stepped down as Master because its lease lapsed (too few monitors
    // acknowledged its heartbeats: cut off, mute, or on the wrong side of a partition).
    std::uint64_t lease_step_downs = 0;
    // Times this node held its tasks for want of a lease, and released them again.
    std::uint64_t lease_holds = 0;
    std::uint64_t lease_releases = 0;
    // Reintegration (spec/Rejoin.tla): nodes this Master readmitted, and of those the
    // readmissions it handed over to another Master (the configuration returned to is
    // another node's).
    std::uint64_t readmissions = 0;
    std::uint64_t hand_overs = 0;
    // This node was handed a view but never got every voter's acknowledgement to drive it
    // (2 * miss_limit periods), and gave it up.
    std::uint64_t hand_overs_given_up = 0;
    // Hand-overs this node refused because they named a boot of it that ended (it restarted
    // within the repeats of a hand-over meant for its previous boot).
    std::uint64_t hand_overs_stale = 0;
    // This node declared its view's Master for leaving the view: its heartbeats said, for 3
    // miss_limit periods, that it follows a newer epoch whose Commands never came here (a
    // value-faulty Master's doing, or a Master of that epoch that failed at once).
    std::uint64_t masters_left = 0;
    // Fault model 3 (admission.hpp, docs/fault-model.md "Authority"), per message kind (the
    // Message variant's index, named by kind_name): messages dropped for an id the mission
    // does not have (malformed), and for a sender whose role may not send them, or an epoch
    // it may not open, in this node's view (unauthorized).
    std::array<std::uint64_t, std::variant_size_v<Message>> malformed{};
    std::array<std::uint64_t, std::variant_size_v<Message>> unauthorized{};
    // Commands this node refused as no Master's: their view is none the decision graph
    // places, or the next switch of this node's view follows no edge of it. Each holds its
    // sender failed for good (HeartbeatMonitor::declare_wrong).
    std::uint64_t commands_refused = 0;
    // Messages of an epoch beyond adoptable_epoch(), dropped unread: this node has not
    // adopted that epoch, acts on nothing of it before its Command, and adopts it by a
    // Command only once its bound has grown a lap per period. An honest node far ahead
    // (the other side of a partition that healed) sends them too, so this is no refusal.
    std::uint64_t ahead_dropped = 0;
    // Commands not followed (yet) because an exclusion they add is backed by no
    // declaration of a node other than their sender that this node has seen, nor vouched
    // for by another member's Prepared (rule 5). The backing may arrive after the Command
    // (the Master retransmits), so this is no refusal either.
    std::uint64_t commands_unbacked = 0;
    // Heartbeats of a boot whose sender this node has since heard boot again (a stale
    // heartbeat overtaken on the way by the next boot's), dropped unread.
    std::uint64_t retired_boot_heartbeats = 0;
    // This node took over after a whole-cluster power cycle (WarmBoot), or would have but
    // no adoptable epoch was left above the ones the nodes saved.
    std::uint64_t warm_boots = 0;
    std::uint64_t warm_boots_refused = 0;
    // A take-over, or a Master's move past a newer epoch, that did not happen because the
    // epoch it would open is beyond the width of fault model 3's bound (kMaxEpoch less a
    // lap): every other node would refuse it as proof. Only --cold-start helps then.
    std::uint64_t take_overs_refused = 0;
    // Readmissions (or hand-overs) not made for the same reason: the epoch they would open
    // is beyond that width. The node stays out.
    std::uint64_t readmissions_refused = 0;
    // Messages dropped because their sender flies another mission image (its heartbeats
    // say so: NodeOptions::image).
    std::uint64_t foreign_image = 0;
    // Prepared acknowledgements for this node's own view (its epoch and switch number)
    // that name another view: two views under one id, which only a value-faulty Master
    // issues (a copy changed on its way out), or a lying sender. This node's view and
    // the sender's differ in who succeeds whom, so no take-over waits for that sender
    // (NodeProtocol::diverged). An honest cluster never has one (keel-sim's
    // NoHonestRefusalInv).
    std::uint64_t prepared_diverged = 0;
    // Members this node passed over in the succession when it took over (diverged()):
    // each went by another view than this node's, one it prepared under this view's id, an
    // older epoch, or a newer switch of this view's epoch that never reached this node (a
    // copy lost when its Master died). No refusal: an honest cluster may need one.
    std::uint64_t passed_over = 0;
};

class NodeProtocol {
public:
    NodeProtocol(const Topology& topology, NodeId self, TimeNs now, const NodeOptions& options);
    NodeProtocol(const Topology& topology, NodeId self, TimeNs now, const NodeOptions& options,
                 const PersistentState& restart);

    void step(const Message& message, TimeNs now);
    // A caller that reads several messages at once (its queue, after its loop was starved)
    // may hand over the heartbeats' acknowledgements first, so that the lease is judged on
    // everything that arrived; the heartbeats are stepped in their turn all the same.
    // Bounded as step() bounds it (admission.hpp); a refused heartbeat is counted by step().
    void note_acks(const Message& message) {
        const auto* heartbeat = std::get_if<Heartbeat>(&message);
        if (heartbeat != nullptr && !out_of_mission(message, *topology_)) monitor_.take_acks(*heartbeat);
    }
    void tick(TimeNs now);
    void task_stepped(TaskId task, std::vector<std::uint8_t> state, TimeNs now);
    void request_phase(PhaseId phase, TimeNs now);
    // A ground command naming a configuration to leave safe mode for (fault model 2, item
    // 3; ReconfigurationManager::ground_recovery says which targets are accepted). Only the
    // Master acts on it, when no switch is under way. Returns an empty string when the
    // switch started, else why the command was refused (also traced as
    // switch.RefuseGroundCommand).
    std::string request_recovery(ConfigId target, TimeNs now);
    // Ground commands (core/node/ground.hpp checked the operator's signature): the ground
    // holds node n out of the cluster. Every node keeps n in held_out(), and a Master never
    // readmits a node held out. The acting Master excludes n by a switch of its own (the
    // graph's edge, traced `Exclude` with `ground`), when no switch of its is under way and
    // its own walk of the graph from its view passes (exclude_held_out); when n is the
    // acting Master, it steps down (resign()). Refused, with the reason (nothing changes),
    // when the decision graph's edges from this node's view, for the failures its monitor
    // declared that the view has not excluded yet, the nodes held out already that the
    // view has not excluded, and n, lead to safe mode: the ground does not take the cluster
    // beyond its tolerance (spec/Ground.tla; a node's own view may be behind the Master's,
    // which is why only the Master's walk excludes). A node already excluded is held out as
    // it is; in safe mode (beyond the tolerance already) the check does not apply, and the
    // Master excludes no one for the ground until a recovery leaves safe mode.
    std::string ground_exclude(NodeId node, TimeNs now);
    // The ground lets node n back: it is readmitted as any node that comes back (Rejoin).
    std::string ground_readmit(NodeId node, TimeNs now);
    const NodeSet& held_out() const { return held_out_; }
    // The ground pauses task t (or lets it run again): every node keeps t in paused(), and
    // the node that runs it stops it, keeping it placed, its state and version, until the
    // ground resumes it (ConfigSwitch::pause). Refused, with the reason (nothing changes),
    // for an essential task (it always runs, in every phase and in safe mode), a task
    // paused already, or (resume) one that is not.
    // The ground's vote (spec/Designate.tla, rule 3; docs/operations.md, `designate`): the
    // mission sets heartbeat.tie_grace, and the ground designates `node` to take over a
    // cluster left headless by a tie. The vote is for `node` from `wait_periods` periods
    // after this node admits it until `span_periods` periods after `node` sent its
    // heartbeat `echo` (this boot's; the ground echoes the latest it saw, so a late command
    // only shortens the vote). Every node keeps the latest designation it admitted: one of
    // another node ends this node's own vote (a designee steps down). Refused, with the
    // reason (nothing changes), when the mission has no tie_grace, `node` is no monitor of
    // this node's view, or (on the designee) `echo` is no heartbeat of this boot it still
    // knows the send time of.
    std::string ground_designate(NodeId node, int wait_periods, int span_periods, std::uint32_t echo,
                                 TimeNs now);
    // This node holds the ground's vote now (rule 3).
    bool holds_vote() const { return vote_for(self_); }
    // The designation this node admitted last, as it counts it: the designee, and the
    // window [from, until) of its vote in this node's time (until: the vote's end bounded
    // from below; for another node, by what that node's heartbeats said of it).
    struct Designation {
        NodeId node = kNoNode;
        TimeNs from = 0;
        TimeNs until = 0;
    };
    const Designation& designation() const { return designation_; }
    // Rule 5: this node's lease lapsed in a tie; it runs again only once it follows a
    // newer Command, holds the vote, or is acknowledged by every voter of every view it
    // goes by, none going by a newer epoch.
    bool stood_down() const { return stood_down_; }
    std::string ground_pause(TaskId task, TimeNs now);
    std::string ground_resume(TaskId task, TimeNs now);
    const TaskSet& paused() const { return switch_.paused(); }
    // Asks the cluster to treat this node as failed. A node that is not the acting Master
    // sends ErrorNotification{self, epoch, self} to the Master of its view, again every
    // period until a view that excludes it arrives, and its heartbeats say `excluded` from
    // now on, so every monitor declares it at once (should the Master die meanwhile, the
    // next Observer in the succession does not wait for this one). The acting Master cannot exclude
    // itself through its own ReconfigurationManager, so it steps down: it stops driving,
    // deactivates its tasks and flushes their final checkpoints to the Storage node
    // (retransmitted every period until acked, or given up after miss_limit periods);
    // then its heartbeats say `excluded`, every monitor declares it failed at once and the
    // first Observer takes over along the graph's master-failure edge. A node that has
    // resigned never takes over or drives again, and adopts only Commands that exclude it,
    // until it restarts. Calling it again is harmless.
    void resign(TimeNs now);

    // The next period boundary, or the lease's expiry if that comes first.
    TimeNs next_tick_ns() const;
    bool has_ready() const { return !out_.actions().empty(); }
    std::vector<Action> take_ready();
    // Swaps the pending actions into `into` (cleared first): no allocation in steady state.
    void take_ready(std::vector<Action>& into);

    PersistentState persistent_state() const;

    // Read-only state, for the simulator's checkers, tests and status displays.
    NodeId self() const { return self_; }
    const Topology& topology() const { return *topology_; }
    const HeartbeatMonitor& monitor() const { return monitor_; }
    const Election& election() const { return election_; }
    const ReconfigurationManager& manager() const { return manager_; }
    const ConfigSwitch& config_switch() const { return switch_; }
    const CheckpointStore* store() const { return store_ ? &*store_ : nullptr; }
    // Checkpoint requests this node left unanswered: from a node never placed on the task
    // (refused), or beyond the requester's budget (limited); as the Storage node, or as a
    // node holding hand-offs (request_budget.hpp).
    const RequestBudget& request_budget() const {
        return store_ ? store_->request_budget() : switch_.request_budget();
    }
    Role role() const { return election_.role(); }
    Epoch epoch() const { return election_.epoch(); }
    const View& view() const { return switch_.view(); }
    bool is_master() const { return election_.role() == Role::Master && manager_.active(); }
    // Where resign() stands: none, asked (a non-Master told its Master; its heartbeats say
    // excluded), flushing (a
    // Master stepping down waits for its final checkpoints' acks), done (its heartbeats
    // say excluded).
    enum class Resign : std::uint8_t { none, asked, flushing, done };
    Resign resign_state() const { return resign_; }
    // Booted from its saved state and not commanded since (its heartbeats say `waiting`).
    bool waiting() const { return restarted_ && !commanded_; }
    // The image `node`'s heartbeats name when it is not this node's (0: the same, or not
    // heard, or not known).
    std::uint64_t foreign_image(NodeId node) const { return node < foreign_image_.size() ? foreign_image_[node] : 0; }
    const NodeStats& stats() const { return stats_; }
    // Why the last message this node refused (malformed, unauthorized or a Command it
    // refused) was refused, naming the message's kind and sender; empty before any.
    const std::string& last_refusal() const { return last_refusal_; }
    // This Master holds `node` failed but lacks a second monitor's evidence to exclude it
    // (both of the other monitors went down at once, e.g.: beyond the tolerance).
    bool awaiting_evidence(NodeId node) const;
    // The lease (contract point 4): when it ends, as things stand (kNever: not held;
    // kForever: no voter is left that could exclude this node).
    static constexpr TimeNs kForever = std::numeric_limits<TimeNs>::max();
    TimeNs lease_expiry_ns() const;
    bool holds_lease() const { return now_ < lease_expiry_ns(); }
    // The lease rests on fresh acknowledgements: a period of it is left at least (a
    // Master's boot switch waits for it, enforce_lease).
    bool lease_fresh() const;
    // This node's tasks are held for want of a lease.
    bool holding() const { return switch_.holding(); }
    // This Observer suspects every node ahead of it in the succession but lacks a second
    // monitor's evidence to take over (the other monitors went down with the Master, e.g.:
    // beyond the tolerance).
    bool awaiting_takeover_evidence() const;
    // This Observer has the evidence to take over but not the lease (spec/Lease.tla): a
    // monitor behind it, which it cannot hear, may be alive and could succeed it at once
    // (two monitors gone together with the Master, e.g.: beyond the tolerance).
    bool awaiting_takeover_lease() const;
    // The members that prepared another view under the id of this node's view: the
    // succession of this node's view is not theirs, and no take-over waits for them.
    NodeSet diverged() const;

private:
    NodeProtocol(const Topology& topology, NodeId self, TimeNs now, const NodeOptions& options,
                 const PersistentState* restart);
    void handle(const Message& message);
    // Fault model 3: counts a refused message in `counter` (by kind) and keeps why.
    void refuse(std::uint64_t& counter, const Message& message, const std::string& why);
    void refuse(std::uint64_t& counter, std::string_view kind, NodeId from, const std::string& why);
    // The receiver's rules for a Command it would adopt (admission.hpp): why it is refused,
    // or nothing; `proof` is set when the refusal proves its sender faulty.
    // Why this node does not follow `command` now, and how sure it is: `proof` (no honest
    // Master sends it), `unbacked` (rule 5: it may be followed once the backing arrives),
    // `ahead` (an epoch beyond adoptable_epoch(): an honest node far ahead sends it too,
    // and this node adopts it once its bound has grown), or neither.
    enum class Verdict : std::uint8_t { unauthorized, proof, unbacked, ahead };
    // What backs one exclusion a Command adds (rule 5), as its trace line names it:
    // "reported" by a node (this node's own monitor, or another's declaration), "word"
    // (the node asked for its own exclusion), "silent" (unheard here for miss_limit
    // periods), "last" (the sender is the last monitor) or "vouched" by a member's Prepared.
    struct Backing {
        NodeId node = kNoNode;
        const char* kind = "";
        NodeId by = kNoNode;
    };
    std::optional<std::string> command_problem(const Command& command, Verdict* verdict,
                                               std::vector<Backing>* backing = nullptr) const;
    std::optional<Backing> backing_of(NodeId node, NodeId sender, const View& target) const;
    bool silent_here(NodeId node) const;
    // Rule 5: a node `target` adds to this node's failed set is backed when this node
    // declared it itself (or has its own word), or heard nothing from it for miss_limit
    // periods though it would have (its heartbeats come here), or when a node other than the sender
    // declared it to this node (a current report: declared_to_me); or when the sender is
    // the last monitor, whose own declaration is then the whole evidence an exclusion needs
    // (no monitor of this node's view is left but the sender and the node, once those the
    // view excludes and those `target` excludes with backing are taken out). While this
    // node is out of the cluster, "its view" is the last one it checked (vetted_): the
    // view that excluded it was not checked, and neither are its exclusions. Only this
    // node's own declarations count, not the failed sets it adopted from views.
    bool declared_to_me(NodeId node, NodeId sender) const;
    bool exclusion_backed(NodeId node, NodeId sender, const View& target) const;
    // A node asking for its own exclusion (resign) says so to every node: its word backs
    // the exclusion wherever it is checked.
    void announce_own_exclusion();
    // Whether the graph's edges from `view`, for `node`, then the failures this node's
    // monitor declared and the nodes held out that `view` has not excluded (an acting
    // Master leaves itself out), reach safe mode, or `node`'s own edge reaches safe mode or
    // a configuration of another Master.
    bool ground_exclusion_reaches_safe(const View& view, NodeId node) const;
    // The acting Master, idle, holding its lease, out of safe mode: the first node held
    // out that its view has not excluded and whose exclusion passes its walk is excluded
    // by a switch (ground_exclude).
    void exclude_held_out();
    void announce_restart();
    // The largest epoch this node adopts now (fault model 3): a lap of the succession
    // above the epoch it anchored its bound at, plus a lap per heartbeat period since, and
    // never within a lap of kMaxEpoch. An epoch it adopts or opens re-anchors the bound
    // only where that lowers it (note_epoch): a run of Commands moves it no faster than a
    // lap a period.
    Epoch adoptable_epoch() const;
    void note_epoch();
    // Whether this node knows the cluster's epoch: it adopted a Command since it booted, or
    // opened an epoch itself.
    bool knows_epoch() const;
    // The largest epoch a node that knows none follows in a Command from `sender`: a lap
    // above what the other nodes' heartbeats reported, plus a lap per period since each
    // was heard (or its own saved epoch, plus a lap per period since boot).
    Epoch corroborated_bound(NodeId sender) const;
    void handle_command(const Command& command);
    void handle_declared(NodeId node);
    // Evidence before exclusion (spec/Exclusion.tla, rule 2), on the acting Master.
    void note_report(NodeId reporter, NodeId node);
    void consider_exclusion(NodeId node);
    bool evidence_suffices(NodeId node, const View& driving) const;
    bool evidence_suffices_in(NodeId node, const View& view) const;
    // The evidence for excluding `node` in `view` (evidence_suffices_in decides on it).
    Evidence evidence_in(NodeId node, const View& view) const;
    // The members of `view` whose declarations count (spec/Quorum.tla, rule 1).
    NodeSet members_of(const View& view) const;
    int exclusion_quorum(int members, int voters) const;
    bool no_joint_views() const {
        return mutant_on(options_.mutant, Mutant::no_joint_views) || mutant_on(options_.mutant, Mutant::quorum_before_fix);
    }
    bool takeover_evidence() const;
    void note_divergence(const Ack& ack);
    NodeSet diverged_members() const;
    void time_pass_over();
    bool may_act() const;
    void report_declared(NodeId node);
    void take_over();
    bool hears_others() const;
    void start_switch(const View& target);
    void start_queued_phase();
    void update_watch();
    void deliver_internal(std::size_t from_index);
    void advance_resign();
    void step_down_if_cut_off();
    // WarmBoot (spec/MasterElection.tla): see consider_warm_boot in the .cpp.
    void consider_warm_boot();
    void step_down_if_stalled();
    void enforce_lease();
    void consider_readmission();
    void repeat_hand_over();
    Command hand_over_command(const View& handed, std::vector<View> joint) const;
    // The view's Master left it (its heartbeats say it follows a newer epoch whose
    // Commands never reached this node): see note_master_left.
    void note_master_left(const Heartbeat& heartbeat);
    void declare_master_left();
    // The lease with the voters in `without` left out (a decider's, on them), by the view
    // this node goes by, or by `view`.
    TimeNs lease_expiry_ns(NodeSet without) const;
    // `joint`: a joint view, where the ground's vote for this node's Master counts too.
    TimeNs lease_expiry_ns(const View& view, NodeSet without, bool joint) const;
    // spec/Designate.tla. Rule 1: the ground is a member of a view with `members` monitors
    // when the mission sets tie_grace and the count is even.
    bool ground_member(int members) const { return topology_->tie_grace() > 0 && members % 2 == 0; }
    // Rule 3: the vote is for `node` now, as this node counts it.
    bool vote_for(NodeId node) const;
    // Rule 2: when the ground counts against this node in a view whose tie began at
    // `tie` (its grace then runs out, unless the vote is for it: `for_self`, or for the
    // view's Master, `for_master`).
    TimeNs ground_against_from(TimeNs tie, bool for_self, bool for_master) const;
    // Rule 5: whether the node may resume (see stood_down()).
    void consider_stand_down(bool lapsed_in_tie);
    void end_stand_down(const char* why);
    // What this node's heartbeats say of its vote (Heartbeat::vote_left_ms), and what its
    // Master's say (master_vote_until_).
    void note_vote_left();
    void note_master_vote(const Heartbeat& heartbeat);
    // Keeps declared_at_ and report_since_ (rule 4) with the declarations and reports.
    void note_declarations();
    // lease_expiry_ns without the ground's count (lease_ends_in_tie).
    mutable bool cluster_only_ = false;
    bool tie_over() const;
    // Whether the lease, as things stand, ends by the ground's count (a tie's grace).
    bool lease_ends_in_tie() const;
    // Rule 4: the ground's vote counted in a decision on `node` in `view` (this node holds
    // the vote, and its own declaration of `node`, and each report it counts, has stood
    // tie_grace periods).
    bool vote_counts_against(NodeId node, const View& view) const;
    // Of `declared` (this node and reporters), those whose declaration of `node` has stood
    // tie_grace periods.
    int stood_declarations(NodeId node, const NodeSet& declared) const;
    bool vote_completes(NodeId node, const View& view, const Evidence& evidence, int needed) const;
    // Rule 1: the ground is a member of `view` (its monitors not excluded are even).
    bool view_has_ground(const View& view) const;
    // Whether the ground counts in `view` where this node counts `members` members: by the
    // view's parity or by that count's (the vote, though, only by the view's).
    bool ground_counts(const View& view, int members) const;
    // The ground's vote completed the evidence for excluding `node` in `view` (traced).
    bool vote_needed(NodeId node, const View& view) const;
    // The view a decision counted the ground's vote in (rule 4's joint view): every view
    // of this lineage keeps it joint until the tie is over (tie_over()).
    std::optional<View> tie_view_;
    void keep_tie_view();
    void adopt_tie_view(const std::vector<View>& joint);
    bool in_tie(const View& view) const;
    Designation designation_;
    std::uint32_t designation_echo_ = 0;
    // The vote's end for this node's Master, as its heartbeats said it: counted from this
    // node's own heartbeat that the Master acknowledged (Heartbeat::vote_left_ms).
    TimeNs master_vote_until_ = 0;
    NodeId master_vote_node_ = kNoNode;
    bool stood_down_ = false;
    Epoch stood_down_epoch_ = 0;
    // When this node's own monitor declared each node (-1: not declared), and since when
    // each reporter's current report of it has stood (rule 4: the declarations stood
    // tie_grace periods).
    std::array<TimeNs, kMaxNodes> declared_at_ = [] {
        std::array<TimeNs, kMaxNodes> none{};
        none.fill(-1);
        return none;
    }();
    std::vector<std::array<TimeNs, kMaxNodes>> report_since_;
    // Whether this node's heartbeats say `excluded`: its view excludes it, it asked to be
    // excluded, or it resigned as Master and has flushed (or given up flushing).
    bool left_cluster() const {
        return switch_.excluded() || resign_ == Resign::asked || resign_ == Resign::done;
    }

    const Topology* topology_;
    NodeId self_;
    NodeOptions options_;
    Outbox out_;
    HeartbeatMonitor monitor_;
    Election election_;
    ReconfigurationManager manager_;
    ConfigSwitch switch_;
    std::optional<CheckpointStore> store_;
    std::optional<PhaseId> queued_phase_;
    NodeSet held_out_;  // held out by the ground (ground_exclude)
    NodeStats stats_;
    std::string last_refusal_;
    TimeNs now_ = 0;
    TimeNs booted_ns_ = 0;
    // This node adopted a Command since it booted (see may_act).
    bool commanded_ = false;
    // This node took over since it booted: it knows the cluster's epoch (adoptable_epoch).
    bool mastered_ = false;
    // Rule 5: the last view this node followed with its exclusions checked (a view
    // excluding this node is followed unchecked: what it excludes besides is checked when
    // a view readmits this node, against this view).
    View vetted_;
    // The members whose Prepared named another view under this node's view's id
    // (NodeStats::prepared_diverged), and that id.
    NodeSet diverged_;
    Epoch diverged_epoch_ = 0;
    Seq diverged_seq_ = 0;
    TimeNs pass_over_since_ = -1;  // since when only they stand before a take-over
    Epoch pass_over_epoch_ = 0;    // and the view (epoch, switch) that wait is for
    Seq pass_over_seq_ = 0;
    // Per node, the epoch its latest heartbeat said (0: none heard): a member below this
    // node's view's epoch never took that view (diverged_members).
    std::array<Epoch, kMaxNodes> latest_epoch_{};
    // Per node, what its heartbeats last acknowledged of the Master of this node's view
    // (every processing node acknowledges the nodes it watches, a Worker too) and since
    // when that acknowledgement stands unchanged: a member that still hears that Master
    // (in the incarnation it was first heard in: one restarted is a Worker waiting to be
    // commanded) is not passed over for a newer switch of its epoch (diverged_members).
    struct MasterHeard {
        NodeId master = kNoNode;  // the Master of the view (its epoch below) it is about
        Epoch epoch = 0;
        std::uint32_t incarnation = 0;
        std::uint32_t seq = 0;
        TimeNs changed_at = -1;  // -1: never heard acknowledged
        bool restarted = false;  // acknowledged in a later incarnation: no Master now
    };
    std::array<MasterHeard, kMaxNodes> master_heard_{};
    void note_master_heard(const Heartbeat& heartbeat);
    bool hears_master(NodeId node) const;
    bool never_prepared(NodeId node) const;
    bool restarted_ = false;  // booted from a PersistentState
    // WarmBoot: what each node's last heartbeat said of `waiting`, the epoch its last
    // heartbeat saying it waits carried (the one it saved), and the periods in a row in
    // which every processing node was heard waiting.
    std::array<std::uint64_t, kMaxNodes> foreign_image_{};  // see foreign_image()
    std::array<bool, kMaxNodes> heard_waiting_{};
    std::array<Epoch, kMaxNodes> waiting_epoch_{};
    int warm_periods_ = 0;
    Resign resign_ = Resign::none;
    // Reintegration: per excluded node, since when and until when this Master heard it
    // without a gap, saying it knows itself excluded; the epoch of the view this node
    // handed over (0: none).
    std::array<TimeNs, kMaxNodes> rejoin_since_{};
    std::array<TimeNs, kMaxNodes> rejoin_last_{};
    Epoch handed_over_epoch_ = 0;
    // The view (epoch, seq) whose Master has been heard since left_since_ (-1: not) saying
    // it follows the newer epoch left_epoch_ (note_master_left); left_declared_: this node
    // declared it so, and a take-over opens an epoch above left_epoch_.
    Epoch left_view_epoch_ = 0;
    Seq left_view_seq_ = 0;
    TimeNs left_since_ = -1;
    Epoch left_epoch_ = 0;
    bool left_declared_ = false;
    std::uint32_t handed_over_boot_ = 0;  // the boot of the node it was handed to
    // Readmitted by this Master in the switch under way (see lease_expiry_ns).
    NodeSet joining_;
    // Joint views (spec/Quorum.tla): the views this Master left since its last switch
    // completed, by which a node that has not adopted the newer one yet may still decide.
    std::vector<View> pending_;
    // Handed a view over: every voter must acknowledge this Master until its first switch
    // completes (see lease_expiry_ns); since when it waits to start driving.
    bool strict_lease_ = false;
    TimeNs boot_pending_since_ = 0;
    TimeNs resign_deadline_ns_ = 0;
    // The initial Master's boot switch waits for its lease.
    bool boot_pending_ = false;
    // This node went miss_limit periods without hearing anyone (cut off); once it hears
    // again it does not take over for rejoin_hold_ more periods (see tick()).
    bool isolated_ = false;
    int rejoin_hold_ = 0;
    // A newer epoch, seen in heartbeats, whose owner this Master holds failed, and since
    // when. Moved past (reclaim) only once its owner stayed unheard for miss_limit periods
    // after that: the declaration may date from this Master's own isolation, and a live
    // owner fences this Master within a period of hearing it.
    Epoch newer_epoch_ = 0;
    TimeNs newer_epoch_since_ = 0;
    std::array<TimeNs, kMaxNodes> last_heard_{};
    // Per node, the highest epoch its heartbeats reported since this node booted (-1: none
    // heard), and when it was first heard, for corroborated_bound.
    std::array<TimeNs, kMaxNodes> heard_epoch_at_{};
    std::array<std::int64_t, kMaxNodes> heard_epoch_ = [] {
        std::array<std::int64_t, kMaxNodes> none{};
        none.fill(-1);
        return none;
    }();
    // When each node's last message (of any kind) arrived (rule 5: its silence).
    std::array<TimeNs, kMaxNodes> last_message_{};
    // Fault model 3 (adoptable_epoch): the epoch this node's bound is anchored at, and
    // since when; whether it was anchored once the node knew its epoch.
    Epoch anchor_epoch_ = 0;
    TimeNs anchor_at_ = 0;
    bool anchor_known_ = false;
    Epoch noted_epoch_ = 0;
    // The Observers' current reports, by reported node: who reported it in the period under
    // way and in the one before. Observers repeat a report every period while they hold
    // it, so a report missing from both generations has been withdrawn (its sender heard
    // the node again) or its sender is gone.
    // Consecutive periods in which this Master heard no other node (once it has heard one
    // since it booted): at miss_limit - 1 it is cut off and steps down.
    int cut_off_periods_ = 0;
    // Per node of the mission (Topology::node_count entries).
    std::vector<NodeSet> reports_now_;
    std::vector<NodeSet> reports_before_;
};

}  // namespace keel::fsm
