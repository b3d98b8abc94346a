// A deterministic cluster simulation: every node of a mission runs its NodeProtocol over a
// seeded network model (loss, duplication, delay and so reordering, partitions symmetric
// and one-way), with a virtual clock and injectable crashes, restarts and phase changes.
// One seed fixes everything: the same seed replays the same run, event for event.
//
// The simulation owns the ground truth the protocols cannot see (who is really alive,
// which heartbeats the network dropped, what each fake task's state is) and runs every
// checker (checkers.hpp) after every step: one message delivery, or one node's period
// boundary. Application tasks are fake: a counter that grows by one per period and is
// checkpointed, so checkpoint continuity can be checked exactly.
//
// Each node's actions become effects through keel-node's own driver (core/node/driver.hpp):
// the node's state is saved to a simulated disk before the messages of a step leave, the
// Storage node's acknowledgements and restore replies wait until its checkpoint write is
// durable, and a disk failure is fail-stop. The simulated disk (SimDisk) writes each
// checkpoint after a drawn latency, one write at a time; a crash loses what it had not
// written, and a restart boots from what it had. Disk faults: every write failing from an
// instant (worn out, full) until the node restarts, and a power loss at the next write.
#pragma once

#include <array>
#include <cassert>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <queue>
#include <string>
#include <vector>

#include "core/fsm/node_protocol.hpp"
#include "core/node/driver.hpp"
#include "nodes/sim/src/liar.hpp"
#include "nodes/sim/src/rng.hpp"

namespace keel::sim {

using fsm::NodeId;
using fsm::NodeSet;
using fsm::TaskId;
using fsm::TimeNs;

inline constexpr TimeNs kMs = fsm::kNanosecondsPerMillisecond;

struct NetworkModel {
    double loss = 0;       // probability a message is dropped
    double duplicate = 0;  // probability a delivered message arrives twice
    TimeNs delay_min_ns = kMs / 2;
    TimeNs delay_max_ns = 5 * kMs;  // kept below half a heartbeat period
};

// The simulated disk: a checkpoint write takes between these (SQLite with
// synchronous=FULL on flash: about a millisecond); the node's own state is written on its
// loop, before the step's messages leave, and takes no simulated time.
struct DiskModel {
    TimeNs write_min_ns = kMs / 5;
    TimeNs write_max_ns = 2 * kMs;
};

struct SimOptions {
    std::uint64_t seed = 1;
    fsm::Mutant mutant = fsm::Mutant::none;
    bool tracing = false;  // build trace actions (trace files, scenario output)
    NetworkModel network;
    DiskModel disk;
    // Each node's own clock, by node id (missing entries: the simulation's): a node's
    // protocol reads local = t + offset + t * drift_ppm / 10^6 at simulated time t, as a
    // board's monotonic clock starts at its own zero and its crystal runs fast or slow.
    struct Clock {
        TimeNs offset_ns = 0;
        std::int64_t drift_ppm = 0;  // above -10^6 (a clock that runs)
    };
    std::vector<Clock> clocks;
    // When each node's process starts (its first boot), by node id; missing entries and
    // an empty vector mean time zero. Real processes do not start at the same instant: a
    // node that boots late is down until then (never crashed), and boots with no
    // PersistentState.
    std::vector<TimeNs> boot_ns;
};

struct Violation {
    std::string invariant;  // the TLA+ invariant the checker is named after
    std::string message;
    TimeNs t_ns = 0;
};

class Checker;

// Milestones of one injected fault, for latency measurement.
struct FaultRecord {
    std::string kind;  // "crash", "phase"
    NodeId node = fsm::kNoNode;
    fsm::PhaseId phase = 0;
    TimeNs injected_ns = 0;
    std::optional<TimeNs> detected_ns;      // first DeclareFailed of the node
    std::optional<TimeNs> reconfigured_ns;  // first completed switch that reflects it
};

class Simulation {
public:
    // `setup` runs before any node boots (so that on_action and on_environment see the
    // boot actions, e.g. the initial Master's boot switch).
    Simulation(const fsm::Topology& topology, const SimOptions& options,
               const std::function<void(Simulation&)>& setup = {});
    ~Simulation();

    const fsm::Topology& topology() const { return *topology_; }
    const SimOptions& options() const { return options_; }
    TimeNs now() const { return now_; }

    // Runs every event up to and including `until`; stops early at the first violation
    // when stop_on_violation is set (the default).
    void run_until(TimeNs until);
    void run_for(TimeNs duration) { run_until(now_ + duration); }
    bool stop_on_violation = true;

    // --- the environment ---
    // A crash before the node's first boot cancels that boot: it stays down until a
    // restart, which is then its first boot.
    void crash(NodeId node);
    // `rolled_back`: the node's saved protocol state went back to what it was before its
    // last boot saved its incarnation (a lost write, a restored file): its epoch, view and
    // incarnation are those of its previous boot, one lower; a Storage node keeps its
    // checkpoints (they are a store of their own). The new boot is told apart only by its
    // boot identifier.
    void restart(NodeId node, bool rolled_back = false);
    // The node asks the cluster to treat it as failed (NodeProtocol::resign), as the
    // runtime does when a task keeps failing there.
    void resign(NodeId node);
    void block(NodeId from, NodeId to);  // one-way: from -> to drops
    void partition(NodeSet side_a, NodeSet side_b);  // symmetric
    void heal();
    // Receive omission: nothing sent to the node arrives (it still sends) until heal().
    void deaf(NodeId node);
    // The node's process is stopped (SIGSTOP, a long stall) for `duration`: it takes no
    // step; what arrives meanwhile waits in its queue, and its period boundary comes late.
    void pause(NodeId node, TimeNs duration);
    // Whether the node ever had an omission fault of its own (deaf, paused, a blocked link
    // to or from it, resigned): ground truth for NoFalseExclusionInv.
    bool omission_faulty(NodeId node) const { return omission_faulty_.contains(node); }
    bool paused(NodeId node) const { return nodes_[node].paused_until_ns > now_; }
    // Since when the node is deaf (receives nothing), if it is.
    std::optional<TimeNs> deaf_since(NodeId node) const { return nodes_[node].deaf_since_ns; }
    // Receive omission from some nodes only (a starved or partly deaf node): what `from`
    // sends to `node` is lost until heal().
    void deaf_to(NodeId node, NodeSet from);
    // When the node's last pause ends (0: never paused).
    TimeNs paused_until(NodeId node) const { return nodes_[node].paused_until_ns; }
    void set_network(const NetworkModel& network) { network_ = network; }
    void set_disk(const DiskModel& disk) { disk_model_ = disk; }
    // A disk fault: from now every write of the node's disk fails (worn out, full), until
    // the node restarts (the disk is replaced). The driver makes the node leave at its
    // first failed write (fail-stop), which ends its process here.
    void fail_disk(NodeId node);
    // Power is lost at the node's next disk write (its state, or a checkpoint it stores;
    // `checkpoint`: its next checkpoint write): the write is lost and the node is down from
    // that instant, in the middle of its step.
    void power_loss_at_write(NodeId node, bool checkpoint = false);
    // The node's disk is full: from now every checkpoint write fails (a state grows the
    // database), while the node's small state, rewritten in place, is still saved; until
    // the node restarts (space freed).
    void fill_disk(NodeId node);
    // The highest version of each task the Storage node acknowledged or sent in a restore
    // reply, over all its boots and its liar's lies excepted: what it promised is durable.
    std::optional<fsm::Version> storage_said(TaskId task) const { return storage_said_[task]; }
    // The highest view (epoch, seq) the node's own Acks named, the highest epoch its
    // Commands named, and the highest incarnation its heartbeats carried, since its last
    // rolled-back restart (what its saved state must be no lower than when it restarts:
    // DurableStateInv).
    std::pair<fsm::Epoch, fsm::Seq> said_view(NodeId node) const { return nodes_[node].said_view; }
    fsm::Epoch said_epoch(NodeId node) const { return nodes_[node].said_epoch; }
    std::uint32_t said_incarnation(NodeId node) const { return nodes_[node].said_incarnation; }
    // How many times the node's process started, and whether its last start found a state
    // that went back (restart(node, true)).
    std::uint32_t boots(NodeId node) const { return nodes_[node].boots; }
    bool rolled_back(NodeId node) const { return nodes_[node].rolled_back; }
    // The node's driver (valid once it booted).
    const node::NodeDriver& driver(NodeId node) const { return *nodes_[node].driver; }
    const NetworkModel& network() const { return network_; }
    // A phase request from the ground, delivered to the acting Master (or, without one, to
    // the first alive processing node: the initial Master waiting for its lease keeps it).
    void request_phase(fsm::PhaseId phase);
    // A ground command to the acting Master: leave safe mode for `config`. Returns why it
    // was refused, or an empty string.
    std::string request_recovery(fsm::ConfigId config);
    // Fault model 3: the node is value-faulty for `duration` (liar.hpp): its honest
    // messages go out with wrong values or not at all, and it forges more. One liar per
    // run. The node stays value-faulty in the ground truth after it stops lying (what it
    // said may still act), and checkers judge only the correct nodes.
    void lie(NodeId node, TimeNs duration);
    // Value-faulty now: the liar, in the boot that lied (after its restart it runs a fresh,
    // correct NodeProtocol, and the checkers judge it again).
    bool value_faulty(NodeId node) const {
        return liar_ != nullptr && liar_->node() == node &&
               (lying(node) || (lied_ && nodes_[node].boots == liar_boot_));
    }
    // Value-faulty at some time of the run: what it said may still act (a state it wrote,
    // a node it fenced, an exclusion it caused).
    bool ever_value_faulty(NodeId node) const { return value_faulty_.contains(node); }
    bool any_value_faulty() const { return !value_faulty_.empty(); }
    // Whether the message the step being checked delivered was sent while its sender lied.
    bool delivered_lie() const { return delivered_lie_; }
    // The message the step being checked delivered, if it was a delivery.
    const fsm::Message* delivered() const { return delivered_; }
    bool lying(NodeId node) const {
        return liar_ != nullptr && liar_->node() == node && now_ < lie_until_ns_ && nodes_[node].alive;
    }
    // Correct nodes that followed a value-faulty Master's view excluding them (fenced: a
    // view excluding its receiver is followed unchecked, docs/fault-model.md "Not
    // covered"): they stop their tasks and say they are excluded, which a correct Master
    // then takes at their word.
    bool fenced_by_liar(NodeId node) const { return fenced_by_liar_.contains(node); }
    // No acting Master after a value-faulty Master fenced correct nodes, and a processing
    // node alive that neither waits nor knows itself excluded, so that no warm boot can
    // come: the limit docs/fault-model.md states (headless, not a violation).
    bool headless_by_fencing() const;
    // Whether a value-faulty node may speak for the task's state within its own authority
    // (the Storage node, or a node the mission may place the task on): what it wrote or
    // answered may be restored, which fault model 3 does not cover (docs/fault-model.md).
    bool state_at_liars_word(TaskId task) const {
        bool may = false;
        value_faulty_.for_each([&](NodeId n) {
            may = may || n == topology_->storage_node() || topology_->may_host(task).contains(n);
        });
        return may;
    }
    // The ground's `exclude NODE` (exclude) or `readmit NODE` taken by every running node
    // (NodeProtocol::ground_exclude, ground_readmit); the last refusal's reason, or empty.
    std::string ground_hold(NodeId node, bool exclude);
    // The ground's `pause-task TASK` (pause) or `resume-task TASK` taken by every running
    // node (NodeProtocol::ground_pause, ground_resume); the last refusal's reason, or empty.
    std::string ground_pause(TaskId task, bool pause);
    // The ground's `designate NODE` (spec/Designate.tla) taken by every running node
    // (NodeProtocol::ground_designate): `wait` and `span` in periods, the echo the
    // designee's latest heartbeat (the ground saw it just now); the last refusal's reason,
    // or empty.
    // `reached`: the nodes the uplink reaches (empty: every running node).
    std::string ground_designate(NodeId node, int wait, int span, NodeSet reached = NodeSet{});
    // The same as the ground computes it (docs/operations.md, `designate`): the wait outlasts
    // every span it gave another node (each ending, as far as the ground can tell, `span`
    // periods after it read the designee's heartbeat, plus a period for the clocks' drift),
    // and the span is the wait plus kVoteSpanPeriods.
    std::string ground_designate(NodeId node, NodeSet reached = NodeSet{});
    static constexpr int kVoteSpanPeriods = 20;
    // A ground command taken by every running node (`command` at that node and its local
    // time); the last refusal's reason, or empty.
    std::string uplink(const std::function<std::string(fsm::NodeProtocol&, TimeNs)>& command,
                       NodeSet reached = NodeSet{});
    // The ground's designations so far: the designee and when its vote ends at the latest,
    // in the simulation's time (ground_designate).
    std::vector<std::pair<NodeId, TimeNs>> ground_votes_;

    // --- ground truth, for checkers and reports ---
    bool alive(NodeId node) const { return nodes_[node].alive; }
    bool ever_crashed(NodeId node) const { return nodes_[node].crashes > 0; }
    // Whether the node's process has started at least once (node() is only valid then).
    bool booted(NodeId node) const { return nodes_[node].protocol != nullptr; }
    // When the node first booted, if it has.
    std::optional<TimeNs> booted_at(NodeId node) const;
    // Down: crashed, or not booted yet (then down since time zero).
    std::optional<TimeNs> down_since(NodeId node) const;
    const fsm::NodeProtocol& node(NodeId node) const {
        assert(nodes_[node].protocol != nullptr);
        return *nodes_[node].protocol;
    }
    const fsm::TaskSet& running(NodeId node) const { return nodes_[node].running; }
    std::uint64_t counter(NodeId node, TaskId task) const { return nodes_[node].counter[task]; }
    int heartbeat_drops_in_row(NodeId from, NodeId to) const { return drops_in_row_[link(from, to)]; }
    // The longest run of heartbeats lost in a row on the link that is still going, or that a
    // delivery ended at most `within` ago: a monitor's declaration rests on a run that a
    // heartbeat delivered after it (before the Master decides) ends.
    int heartbeat_drops_in_row_within(NodeId from, NodeId to, TimeNs within) const {
        const std::size_t at = link(from, to);
        const bool recent = last_run_end_[at] >= 0 && now_ - last_run_end_[at] <= within;
        return std::max(drops_in_row_[at], recent ? last_run_[at] : 0);
    }
    bool blocked(NodeId from, NodeId to) const { return blocked_[link(from, to)] != 0; }
    // The alive node acting as Master in the highest epoch, if any.
    std::optional<NodeId> acting_master() const;
    // No acting Master, and an alive Observer has the evidence to take over but not the
    // lease (NodeProtocol::awaiting_takeover_lease).
    bool lease_stalled() const;

    // Checks SwitchConverges now (the caller decides that faults have stopped long enough).
    bool agreement(std::string* why) const;
    // Heals the network, then runs until agreement holds or `limit` passes; records a
    // violation of SwitchConverges when it never does. Returns the time agreement took.
    std::optional<TimeNs> stabilize(TimeNs limit);

    const std::vector<Violation>& violations() const { return violations_; }
    void report(std::string invariant, std::string message);
    const std::vector<FaultRecord>& faults() const { return faults_; }
    std::uint64_t steps() const { return steps_; }
    // Fault model 2's overlap measures (ground truth, not checkers: the protocol does not
    // yet guarantee them zero in every case; docs/fault-model.md). Simulated time during
    // which two nodes both ran as Master (alive, unpaused, acting as Master, not stepped
    // down), across epochs; and during which one task ran on two alive, unpaused nodes,
    // whatever their views.
    TimeNs two_masters_ns() const { return two_masters_ns_; }
    TimeNs double_run_ns() const { return double_run_ns_; }
    std::uint64_t messages_sent() const { return messages_sent_; }
    std::uint64_t messages_dropped() const { return messages_dropped_; }

    // Observers: every effect of a node (with the time: activations, deactivations,
    // declarations, safe mode and trace lines, in the order its driver carries them out, a
    // held trace line when it is released), and environment events as (action, args
    // JSON), e.g. ("Crash", {"n":"PN2"}).
    std::function<void(TimeNs, NodeId, const fsm::Action&)> on_action;
    std::function<void(TimeNs, const char*, const std::string&)> on_environment;

private:
    class Host;
    struct PendingWrite {
        TaskId task = 0;
        std::uint64_t ticket = 0;
        fsm::Version version;
        std::vector<std::uint8_t> state;
        bool replaces = false;
        TimeNs start_ns = 0;
        TimeNs done_ns = 0;
    };
    // What a node's disk holds (durable) and is writing.
    struct SimDisk {
        fsm::PersistentState durable;  // the node's state and (the Storage node) checkpoints
        // In the order queued (one writer); as keel-node's CheckpointPersister, a write not
        // yet started is replaced by a newer one of its task (which then stands for both).
        std::vector<PendingWrite> writing;
        std::uint64_t tickets = 0;
        bool failing = false;
        bool full = false;  // checkpoint writes fail
        bool power_loss_armed = false;     // at the next write
        bool power_loss_checkpoint = false;  // at the next checkpoint write
    };
    struct SimNode {
        std::unique_ptr<fsm::NodeProtocol> protocol;
        std::unique_ptr<Host> host;
        std::unique_ptr<node::NodeDriver> driver;  // after host and protocol: destroyed first
        SimDisk disk;
        std::pair<fsm::Epoch, fsm::Seq> said_view{0, 0};
        fsm::Epoch said_epoch = 0;
        std::uint32_t said_incarnation = 0;
        TimeNs tick_local_ns = -1;  // next_tick's cache: the protocol's due time ...
        TimeNs tick_global_ns = 0;  // ... in simulated time
        bool rolled_back = false;
        bool alive = true;
        int crashes = 0;
        TimeNs down_since_ns = 0;
        fsm::PersistentState persisted;
        fsm::PersistentState booted_with;  // the state saved at the last boot
        std::uint32_t boots = 0;
        fsm::TaskSet running;
        std::vector<std::uint64_t> counter;  // per task of the mission
        TimeNs phase_offset_ns = 0;
        std::optional<TimeNs> pending_boot_ns;  // the first boot, until it happens
        std::optional<TimeNs> booted_at_ns;
        TimeNs paused_until_ns = 0;
        std::optional<TimeNs> deaf_since_ns;
    };
    // Messages in flight live in slots; the heap orders small keys, so heap operations
    // never move a message.
    struct Delivery {
        NodeId from = fsm::kNoNode;
        NodeId to = fsm::kNoNode;
        fsm::Message message;
        bool lie = false;  // sent while its sender lied
    };
    struct Key {
        TimeNs t_ns;
        std::uint64_t order;
        std::uint32_t slot;
    };
    struct Later {
        bool operator()(const Key& a, const Key& b) const {
            return a.t_ns != b.t_ns ? a.t_ns > b.t_ns : a.order > b.order;
        }
    };
    void enqueue(TimeNs t_ns, NodeId from, NodeId to, fsm::Message message, bool lie = false);

    fsm::NodeOptions node_options(NodeId node) const;
    // The node's clock at simulated time t, and the first simulated time its clock reads
    // at least `local` (SimOptions::clocks).
    TimeNs local(NodeId node, TimeNs t) const;
    TimeNs global(NodeId node, TimeNs local_ns) const;
    TimeNs local_now(NodeId node) const { return local(node, now_); }
    // When the node's next period boundary comes, in simulated time (cached per node).
    TimeNs next_tick(NodeId node);
    void boot(NodeId node);
    // A new NodeProtocol for the node's boot (from its disk when `restart`), with its driver.
    void start_process(NodeId node, bool restart);
    // The node's disk finished its oldest write.
    void finish_write(NodeId node);
    // Lost power in the middle of a step: down at once (crash()), the write lost.
    void lose_power(NodeId node);
    void process(NodeId node);
    void send(NodeId from, NodeId to, fsm::Message message);
    void forge(NodeId node);  // the liar's forged message of a period boundary, if any
    void after_step(NodeId node);
    void environment(const char* action, const std::string& args);
    void note_completion(NodeId node);

    const fsm::Topology* topology_;
    SimOptions options_;
    NetworkModel network_;
    DiskModel disk_model_;
    Rng rng_;
    Rng disk_rng_;  // its own stream: disk latencies do not shift the network's draws
    std::vector<std::optional<fsm::Version>> storage_said_;  // per task
    TimeNs now_ = 0;
    std::vector<SimNode> nodes_;
    std::vector<Key> queue_;  // a binary heap ordered by Later
    std::vector<Delivery> slots_;
    std::vector<std::uint32_t> free_slots_;
    std::uint64_t order_ = 0;
    // Per directed link from -> to (link(from, to)), node_count squared entries: sized for
    // the mission, not for the capacity.
    std::size_t link(NodeId from, NodeId to) const { return from * nodes_.size() + to; }
    std::vector<std::uint8_t> blocked_;
    std::vector<int> drops_in_row_;
    std::vector<int> last_run_;          // the run a delivery ended last, per link
    std::vector<TimeNs> last_run_end_;   // when (-1: none yet)
    std::vector<TimeNs> run_start_;      // when the run under way began, per link
    NodeSet omission_faulty_;
    void measure_overlaps();
    TimeNs measured_until_ns_ = 0;
    bool two_masters_now_ = false;
    bool double_run_now_ = false;
    TimeNs two_masters_ns_ = 0;
    TimeNs double_run_ns_ = 0;
    std::vector<fsm::Action> step_actions_;
    std::vector<std::unique_ptr<Checker>> checkers_;
    std::unique_ptr<Liar> liar_;
    TimeNs lie_until_ns_ = 0;
    NodeSet value_faulty_;  // ever value-faulty
    std::uint32_t liar_boot_ = 0;  // the liar's last boot that sent a lie (SimNode::boots)
    bool lied_ = false;
    bool delivered_lie_ = false;
    const fsm::Message* delivered_ = nullptr;
    NodeSet fenced_by_liar_;
    std::vector<Violation> violations_;
    std::vector<FaultRecord> faults_;
    std::vector<std::uint64_t> completed_;  // per node
    std::uint64_t steps_ = 0;
    std::uint64_t messages_sent_ = 0;
    std::uint64_t messages_dropped_ = 0;

public:
    // The actions of the step being checked (checkers read them).
    const std::vector<fsm::Action>& step_actions() const { return step_actions_; }
};

// The fake task's state: its counter, eight bytes big-endian.
std::vector<std::uint8_t> encode_counter(std::uint64_t counter);
std::optional<std::uint64_t> decode_counter(const std::vector<std::uint8_t>& state);

}  // namespace keel::sim
