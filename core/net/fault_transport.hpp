// FaultTransport: a decorator that injects seeded network faults around any Transport, so
// protocol tests on real DDS (or on the loopback hub) see loss, delay, duplication and
// partitions without tc/netem.
//
// Faults act on what the wrapped node *receives*: every inbound envelope from node S to
// this node D is, in this order,
//   1. dropped if the shared FaultPlan blocks S -> D                 (fault_partitioned)
//   2. dropped with probability loss_probability                      (fault_lost)
//   3. doubled with probability duplicate_probability                 (fault_duplicated)
//   4. held for a delay drawn uniformly from [delay_min, delay_max]   (fault_delayed)
// and released by receive() once clock() reaches its release time (ties in arrival order).
// Malformed items pass through untouched so the Endpoint still counts them.
//
// Determinism: the same seed, configuration, clock readings and inbound order give the same
// deliveries. The random stream is a std::mt19937_64 and each inbound envelope consumes
// exactly three draws, whatever the configuration.
//
// A symmetric partition between groups A and B is plan->partition(A, B); a one-way one is
// plan->block(S, D). Wrap every node in a FaultTransport sharing one FaultPlan.
//
// Threading: as Transport; the FaultPlan is thread-safe (a fault schedule may change it
// from another thread).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <queue>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "core/net/transport.hpp"

namespace keel::net {

class FaultPlan {
public:
    // Blocks every direction between the two groups.
    void partition(const std::set<NodeAddress>& group_a, const std::set<NodeAddress>& group_b);
    // Blocks messages from `from` to `to` only.
    void block(NodeAddress from, NodeAddress to);
    void unblock(NodeAddress from, NodeAddress to);
    // Removes every block.
    void heal();
    bool blocked(NodeAddress from, NodeAddress to) const;

private:
    mutable std::mutex mutex_;
    std::set<std::pair<NodeAddress, NodeAddress>> blocked_;
};

using Clock = std::function<std::chrono::nanoseconds()>;
// std::chrono::steady_clock, as nanoseconds since its epoch.
Clock steady_clock_source();

struct FaultConfig {
    std::uint64_t seed = 1;
    double loss_probability = 0.0;
    double duplicate_probability = 0.0;
    std::chrono::nanoseconds delay_min{0};
    std::chrono::nanoseconds delay_max{0};
    std::size_t max_held = 65536;  // envelopes held for delay; beyond it they are lost
    std::shared_ptr<FaultPlan> plan{};  // optional; none = no partitions
    Clock clock{};                      // optional; none = steady clock
};

class FaultTransport final : public Transport {
public:
    FaultTransport(std::unique_ptr<Transport> inner, FaultConfig config);

    NodeAddress local_address() const override { return inner_->local_address(); }
    SendResult send(const Envelope& envelope) override { return inner_->send(envelope); }
    SendResult send_to_each(const Envelope& envelope,
                            std::span<const NodeAddress> destinations) override {
        return inner_->send_to_each(envelope, destinations);
    }
    std::size_t receive(std::vector<Inbound>& out, std::size_t max_items) override;
    bool wait(std::chrono::nanoseconds timeout) override;
    void wake() override { inner_->wake(); }
    void publish_node_state(const NodeState& state) override { inner_->publish_node_state(state); }
    TransportCounters counters() const override;

    // Changes loss, duplication and delay from now on (the random stream continues).
    void set_faults(double loss_probability, double duplicate_probability,
                    std::chrono::nanoseconds delay_min, std::chrono::nanoseconds delay_max);
    std::size_t held() const { return held_.size(); }

private:
    struct Held {
        std::chrono::nanoseconds release;
        std::uint64_t order;
        Inbound item;
    };
    struct Later {
        bool operator()(const Held& a, const Held& b) const {
            return a.release != b.release ? a.release > b.release : a.order > b.order;
        }
    };

    double draw_unit();
    void admit(Inbound&& item, std::chrono::nanoseconds now);
    void hold(Inbound&& item, std::chrono::nanoseconds release);

    std::unique_ptr<Transport> inner_;
    FaultConfig config_;
    std::mt19937_64 random_;
    std::priority_queue<Held, std::vector<Held>, Later> held_;
    std::uint64_t next_order_ = 0;
    std::vector<Inbound> scratch_;
    std::atomic<std::uint64_t> lost_{0};
    std::atomic<std::uint64_t> partitioned_{0};
    std::atomic<std::uint64_t> duplicated_{0};
    std::atomic<std::uint64_t> delayed_{0};
};

}  // namespace keel::net
