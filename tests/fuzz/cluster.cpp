#include "tests/fuzz/cluster.hpp"

#include <cassert>
#include <limits>

#include "core/fsm/codec.hpp"

namespace keel::fuzz {

namespace {

// Delivered messages kept for replays.
constexpr std::size_t kMaxDelivered = 64;

// The test build keel-protocol-fuzz-mutant runs every node with a mutant (CMakeLists.txt).
#ifdef KEEL_FUZZ_MUTANT
constexpr fsm::Mutant kMutant = fsm::Mutant::KEEL_FUZZ_MUTANT;
static_assert(fsm::kMutantsCompiled, "a mutant needs the test library, keel_fsm_mutants");
#else
constexpr fsm::Mutant kMutant = fsm::Mutant::none;
#endif

std::vector<std::uint8_t> counter_state(std::uint64_t counter) {
    std::vector<std::uint8_t> state(8);
    for (std::size_t i = 0; i < state.size(); ++i) {
        state[i] = static_cast<std::uint8_t>(counter >> (8 * i));
    }
    return state;
}

}  // namespace

Cluster::Cluster(const fsm::Topology& topology, fsm::NodeSet booted, bool tracing)
    : topology_(&topology),
      tracing_(tracing),
      nodes_(static_cast<std::size_t>(topology.node_count())),
      persisted_(static_cast<std::size_t>(topology.node_count())),
      running_(static_cast<std::size_t>(topology.node_count())),
      next_tick_ns_(static_cast<std::size_t>(topology.node_count())),
      invariants_(topology) {
    booted.for_each([&](NodeId node) {
        nodes_[node].emplace(topology, node, now_, options(node));
        after_call(node, "boot");
    });
}

fsm::NodeOptions Cluster::options(NodeId node) const {
    fsm::NodeOptions options;
    // Boundaries spread over the period, the same in every run.
    const TimeNs period = topology_->heartbeat_period_ns();
    options.phase_offset_ns = period * (2 * node + 1) / (2 * topology_->node_count() + 1);
    options.mutant = kMutant;
    options.tracing = tracing_;
    return options;
}

void Cluster::after_call(NodeId node, const char* call) {
    fsm::NodeProtocol& protocol = *nodes_[node];
    invariants_.set_call(call, now_);
    protocol.take_ready(ready_);
    invariants_.check_actions(protocol, ready_, running_[node]);
    for (const fsm::Action& action : ready_) {
        if (const auto* sent = std::get_if<fsm::act::Send>(&action)) {
            send(node, *sent);
        } else if (const auto* activate = std::get_if<fsm::act::Activate>(&action)) {
            running_[node].insert(activate->task);
        } else if (const auto* deactivate = std::get_if<fsm::act::Deactivate>(&action)) {
            running_[node].erase(deactivate->task);
        }
    }
    invariants_.check_node(protocol, running_[node]);
    next_tick_ns_[node] = protocol.next_tick_ns();
}

void Cluster::send(NodeId from, const fsm::act::Send& sent) {
    // As the runtime carries it: encoded, and decoded by the receiver.
    bytes_.clear();
    fsm::encode_into(sent.message, bytes_);
    fsm::DecodedMessage decoded = fsm::decode(bytes_);
    if (!decoded.ok() || !(*decoded.message == sent.message)) {
        broken("CodecRoundTripInv",
               topology_->node_name(from) + " sent a " + std::string(fsm::kind_name(sent.message)) +
                   " that " + (decoded.ok() ? "decodes to another message" : "does not decode: ") +
                   decoded.detail);
    }
    if (in_flight_.size() >= kMaxInFlight) return;  // lost
    in_flight_.push_back(
        InFlight{now_ + kDeliveryDelayNs, from, sent.to, std::move(*decoded.message)});
}

void Cluster::deliver(const InFlight& message) {
    if (!up(message.to)) return;
    if (delivered_.size() >= kMaxDelivered) delivered_.pop_front();
    delivered_.push_back(message);
    nodes_[message.to]->step(message.message, now_);
    after_call(message.to, "step");
}

void Cluster::run_until(TimeNs until) {
    for (int events = 0;; ++events) {
        if (events > kMaxEventsPerRun) {
            broken("EventBoundInv", std::to_string(events) + " events before " +
                                        std::to_string(until) + " ns of " +
                                        std::string(topology_->mission_name()) + ", " +
                                        std::to_string(in_flight_.size()) + " messages in flight");
        }
        // The earliest event: a delivery first on a tie, then nodes in id order.
        TimeNs next = std::numeric_limits<TimeNs>::max();
        NodeId ticking = fsm::kNoNode;
        if (!in_flight_.empty()) next = in_flight_.front().at_ns;
        for (NodeId n = 0; n < node_count(); ++n) {
            if (up(n) && next_tick_ns_[n] < next) {
                next = next_tick_ns_[n];
                ticking = n;
            }
        }
        if (next > until) break;
        now_ = std::max(now_, next);
        if (ticking == fsm::kNoNode) {
            const InFlight message = std::move(in_flight_.front());
            in_flight_.pop_front();
            deliver(message);
        } else {
            tick(ticking);
        }
    }
    now_ = std::max(now_, until);
}

void Cluster::deliver_in_flight(std::size_t index) {
    assert(index < in_flight_.size());
    const InFlight message = std::move(in_flight_[index]);
    in_flight_.erase(in_flight_.begin() + static_cast<std::ptrdiff_t>(index));
    deliver(message);
}

void Cluster::drop_in_flight(std::size_t index) {
    assert(index < in_flight_.size());
    in_flight_.erase(in_flight_.begin() + static_cast<std::ptrdiff_t>(index));
}

void Cluster::step(NodeId to, const fsm::Message& message) {
    if (!up(to) || fsm::sender_of(message) == to) return;
    nodes_[to]->step(message, now_);
    after_call(to, "step");
}

void Cluster::tick(NodeId node) {
    if (!up(node)) return;
    // The application ran each task once in the period that ends.
    const fsm::TaskSet running = running_[node];
    running.for_each([&](TaskId task) {
        if (!running_[node].contains(task)) return;  // stopped by a step before it
        nodes_[node]->task_stepped(task, counter_state(++steps_), now_);
        after_call(node, "task_stepped");
    });
    nodes_[node]->tick(now_);
    after_call(node, "tick");
    invariants_.check_tick(*nodes_[node], next_tick_ns_[node], now_);
}

void Cluster::task_stepped(NodeId node, TaskId task, std::vector<std::uint8_t> state) {
    if (!up(node) || !running_[node].contains(task)) return;
    nodes_[node]->task_stepped(task, std::move(state), now_);
    after_call(node, "task_stepped");
}

void Cluster::request_phase(NodeId node, fsm::PhaseId phase) {
    if (!up(node)) return;
    nodes_[node]->request_phase(phase, now_);
    after_call(node, "request_phase");
}

void Cluster::request_recovery(NodeId node, fsm::ConfigId config) {
    if (!up(node)) return;
    (void)nodes_[node]->request_recovery(config, now_);
    after_call(node, "request_recovery");
}

void Cluster::resign(NodeId node) {
    if (!up(node)) return;
    nodes_[node]->resign(now_);
    after_call(node, "resign");
}

void Cluster::crash(NodeId node) {
    if (!up(node)) return;
    persisted_[node] = nodes_[node]->persistent_state();
    nodes_[node].reset();
    running_[node] = fsm::TaskSet{};
}

void Cluster::restart(NodeId node) {
    crash(node);
    if (persisted_[node]) {
        nodes_[node].emplace(*topology_, node, now_, options(node), *persisted_[node]);
    } else {
        nodes_[node].emplace(*topology_, node, now_, options(node));
    }
    after_call(node, "boot");
}

}  // namespace keel::fuzz
