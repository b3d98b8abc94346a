// NodeProtocol: one node's protocol state machines, composed, behind one step/tick API in
// the shape of etcd raft's Node (events in, actions out; no IO, no clock, no threads).
//
// It owns the node's HeartbeatMonitor, Election, ReconfigurationManager, ConfigSwitch and,
// on the Storage node, the CheckpointStore. The node runtime (keel-node, over DDS) and the
// deterministic simulator (keel-sim) drive the same class.
//
// The contract, in the order the caller must honour it:
//  1. Construct at boot with the current time (first boot: every node starts in the first
//     phase's initial configuration, epoch 1, its tasks active). After a crash, construct
//     with the PersistentState the previous incarnation left (persistent_state(), which
//     the caller saves after every call).
//  2. Feed events, each with the current time, never decreasing:
//       step(message, now)      a message arrived (decode it with codec.hpp first; drop
//                               what fails to decode)
//       tick(now)               when now >= next_tick_ns(); calling it earlier is harmless
//       task_stepped(t, s, now) the application executed task t once; s is its new state
//       request_phase(p, now)   an operator or the mission timeline asks for phase p (only
//                               the Master acts on it; others forward it to their Master)
//  3. After each call, take_ready() and carry out the actions in the order given
//     (actions.hpp says what each means). Sends to the node itself never appear: they are
//     delivered internally, in order, before the call returns. The state machines have
//     already moved on; a lost Send is the channel's business (the protocols retransmit).
//  4. Stale messages (an epoch below the node's) are rejected in step(), in one place,
//     before any role-specific handling; heartbeats and phase requests carry no epoch.
//
// Limits: one call delivers at most kMaxInternalDeliveries self-addressed messages.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/fsm/actions.hpp"
#include "core/fsm/checkpoint_store.hpp"
#include "core/fsm/config_switch.hpp"
#include "core/fsm/election.hpp"
#include "core/fsm/heartbeat_monitor.hpp"
#include "core/fsm/mutants.hpp"
#include "core/fsm/reconfiguration_manager.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

inline constexpr int kMaxInternalDeliveries = 4096;

struct NodeOptions {
    // Emit act::Trace actions (NDJSON trace lines); off, the machines skip building them.
    bool tracing = false;
    // Offset of this node's heartbeat period boundaries from time zero, in [0, period).
    TimeNs phase_offset_ns = 0;
    Mutant mutant = Mutant::none;  // tests only (mutants.hpp)
};

// What survives a crash: the spec's persisted `epoch`, the last view accepted, the boot
// counter, and on the Storage node its checkpoints.
struct PersistentState {
    Epoch epoch = 0;
    View view;
    std::uint32_t incarnation = 0;
    std::vector<StoredCheckpoint> checkpoints;
};

// Counters for benchmarks and logs.
struct NodeStats {
    std::uint64_t stale_rejected = 0;
    std::uint64_t switches_started = 0;
    std::uint64_t switches_completed = 0;
};

class NodeProtocol {
public:
    NodeProtocol(const Topology& topology, NodeId self, TimeNs now, const NodeOptions& options);
    NodeProtocol(const Topology& topology, NodeId self, TimeNs now, const NodeOptions& options,
                 const PersistentState& restart);

    void step(const Message& message, TimeNs now);
    void tick(TimeNs now);
    void task_stepped(TaskId task, std::vector<std::uint8_t> state, TimeNs now);
    void request_phase(PhaseId phase, TimeNs now);

    TimeNs next_tick_ns() const { return monitor_.next_boundary_ns(); }
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
    Role role() const { return election_.role(); }
    Epoch epoch() const { return election_.epoch(); }
    const View& view() const { return switch_.view(); }
    bool is_master() const { return election_.role() == Role::Master && manager_.active(); }
    const NodeStats& stats() const { return stats_; }

private:
    NodeProtocol(const Topology& topology, NodeId self, TimeNs now, const NodeOptions& options,
                 const PersistentState* restart);
    void handle(const Message& message);
    void handle_command(const Command& command);
    void handle_declared(NodeId node);
    void take_over();
    bool hears_others() const;
    void start_switch(const View& target);
    void start_queued_phase();
    void update_watch();
    void deliver_internal(std::size_t from_index);

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
    NodeStats stats_;
    TimeNs now_ = 0;
};

}  // namespace keel::fsm
