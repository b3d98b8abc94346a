// The fuzzer's cluster: every node of a mission as a NodeProtocol, an honest network between
// them, one clock, and the invariants (invariants.hpp) checked after every call.
//
// The network carries every Send as the runtime does, encoded and decoded again (codec.hpp),
// and delivers it kDeliveryDelayNs later, in the order sent, unless the fuzz input reorders
// or drops it. run_until() delivers what is due and ticks each node at its own period
// boundaries (next_tick_ns), stepping each task the node runs once per tick first, as
// keel-sim's driver does. A node that crashed is neither ticked nor delivered to until it
// restarts from the PersistentState it left.
//
// Every call into a NodeProtocol goes through this class, honest or forged: it takes the
// node's actions, checks them and the node's state, carries them out (Sends into the
// network, Activate and Deactivate into the node's running tasks), and aborts the process
// naming the invariant when one breaks. A Cluster is a value: the honest prefixes are
// computed once and copied into each run (prefix.hpp).
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <vector>

#include "core/fsm/node_protocol.hpp"
#include "tests/fuzz/invariants.hpp"

namespace keel::fuzz {

using fsm::NodeId;
using fsm::TaskId;
using fsm::TimeNs;

// One hop of the honest network (a period is 100 ms in both shipped missions).
inline constexpr TimeNs kDeliveryDelayNs = 1'000'000;
// Limits: messages in flight (more are lost, as a full queue loses them), and events one
// run_until() handles (honest traffic is a few dozen messages a period; a storm far beyond
// it is a finding, EventBoundInv).
inline constexpr std::size_t kMaxInFlight = 4096;
inline constexpr int kMaxEventsPerRun = 200'000;

struct InFlight {
    TimeNs at_ns = 0;
    NodeId from = fsm::kNoNode;
    NodeId to = fsm::kNoNode;
    fsm::Message message;
};

class Cluster {
  public:
    // First boot at time zero of the nodes in `booted` (the others boot later, by restart()).
    // With `tracing`, the nodes build their trace lines too (act::Trace, dropped here).
    Cluster(const fsm::Topology& topology, fsm::NodeSet booted, bool tracing);

    const fsm::Topology& topology() const { return *topology_; }
    TimeNs now() const { return now_; }
    int node_count() const { return topology_->node_count(); }
    bool up(NodeId node) const { return nodes_[node].has_value(); }
    const fsm::NodeProtocol& node(NodeId node) const { return *nodes_[node]; }
    const fsm::TaskSet& running(NodeId node) const { return running_[node]; }
    const std::deque<InFlight>& in_flight() const { return in_flight_; }
    // Honest messages delivered lately, for replays (a duplicate or a late copy).
    const std::deque<InFlight>& delivered() const { return delivered_; }

    // Time: the network and every node's boundaries until `until`; or the clock jumps, as
    // if every node's loop had stalled meanwhile (they tick late, at the next run_until).
    void run_until(TimeNs until);
    void stall(TimeNs duration) { now_ += duration; }

    // The network: a message in flight delivered now, out of order, or lost.
    void deliver_in_flight(std::size_t index);
    void drop_in_flight(std::size_t index);
    // Any message to `to`, now, as a receiver's runtime hands it over: nothing for a node
    // that is down, and nothing that names `to` itself as its sender (the runtime drops a
    // message whose sender is not its authenticated source, and no node receives its own).
    void step(NodeId to, const fsm::Message& message);

    // A node's other events (node_protocol.hpp, contract point 2), now. task_stepped only
    // for a task the node runs, as its application would.
    void tick(NodeId node);
    void task_stepped(NodeId node, TaskId task, std::vector<std::uint8_t> state);
    void request_phase(NodeId node, fsm::PhaseId phase);
    void request_recovery(NodeId node, fsm::ConfigId config);
    void resign(NodeId node);
    void crash(NodeId node);
    // A node that is down boots: from the state it left, or for the first time if it never
    // ran. A node that is up crashes first.
    void restart(NodeId node);

  private:
    fsm::NodeOptions options(NodeId node) const;
    // After every call into `node`: its actions checked and carried out, its state checked.
    void after_call(NodeId node, const char* call);
    void send(NodeId from, const fsm::act::Send& send);
    void deliver(const InFlight& message);

    const fsm::Topology* topology_;
    bool tracing_;
    TimeNs now_ = 0;
    std::vector<std::optional<fsm::NodeProtocol>> nodes_;
    std::vector<std::optional<fsm::PersistentState>> persisted_;
    std::vector<fsm::TaskSet> running_;
    // Each node's next_tick_ns() as of its last call (it changes only with a call): the
    // event loop asks for it once per event and node, and computing it is the lease's work.
    std::vector<TimeNs> next_tick_ns_;
    std::uint64_t steps_ = 0;  // the applications' states: a counter, as keel-sim's
    std::deque<InFlight> in_flight_;
    std::deque<InFlight> delivered_;
    Invariants invariants_;
    std::vector<fsm::Action> ready_;
    std::vector<std::uint8_t> bytes_;
};

}  // namespace keel::fuzz
