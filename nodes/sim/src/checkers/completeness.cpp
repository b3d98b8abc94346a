// CompletenessInv (spec/Heartbeat.tla): a crashed node is declared failed by every running
// monitor within DetectionBound = (miss_limit + 2) periods plus the largest network delay,
// counted from the crash or from when the monitor began monitoring, whichever is later. A
// node the monitor has never heard since it booted (a node that has not booted yet, or
// crashed before its first heartbeat reached the monitor) is given the start-up grace:
// (startup_grace_periods + 2) periods plus the delay. Each period the monitor did not count
// because it suspected itself (it heard no one, or ran late) adds a period to the bound.
// A view the monitor adopts that no longer excludes the node (a readmission, or the view
// of a Master that took over without having learnt of the exclusion) makes it count
// afresh, as Heartbeat.tla's Readmit does: the bound runs from then.
#include <algorithm>

#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class Completeness final : public Checker {
public:
    const char* invariant() const override { return "CompletenessInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        const auto& topology = sim.topology();
        const int count = topology.node_count();
        if (since_.empty()) {
            const auto nodes = static_cast<std::size_t>(count);
            since_.assign(nodes, -1);
            incarnation_.assign(nodes, 0);
            suspected_base_.assign(nodes, 0);
            excluded_.assign(nodes, fsm::NodeSet{});
            readmitted_at_.assign(nodes * nodes, 0);
        }
        // Track when each live node began monitoring (a restart starts afresh).
        for (NodeId m = 0; m < count; ++m) {
            if (!sim.booted(m)) {
                since_[m] = -1;
                continue;
            }
            const bool monitoring = sim.alive(m) && sim.node(m).monitor().monitoring();
            const std::uint32_t incarnation = sim.node(m).monitor().incarnation();
            if (!monitoring || incarnation != incarnation_[m]) {
                since_[m] = -1;
                incarnation_[m] = incarnation;
            }
            if (monitoring && since_[m] < 0) {
                since_[m] = sim.now();
                suspected_base_[m] = sim.node(m).monitor().self_suspected_periods();
            }
        }
        (void)node;
        for (NodeId m = 0; m < count; ++m) {
            static const fsm::NodeSet none;
            const fsm::NodeSet& excluded = sim.booted(m) ? sim.node(m).view().failed : none;
            excluded_[m].minus(excluded).for_each([&](NodeId n) { readmitted_at(m, n) = sim.now(); });
            excluded_[m] = excluded;
        }
        const TimeNs period = topology.heartbeat_period_ns();
        const TimeNs heard_bound = (topology.miss_limit() + 2) * period + sim.network().delay_max_ns;
        const TimeNs grace_bound =
            (topology.startup_grace_periods() + 2) * period + sim.network().delay_max_ns;
        for (NodeId n = 0; n < count; ++n) {
            const auto down = sim.down_since(n);
            if (!down) continue;
            for (NodeId m = 0; m < count; ++m) {
                if (m == n || since_[m] < 0 || sim.value_faulty(m)) continue;  // correct monitors
                const auto& monitor = sim.node(m).monitor();
                if (monitor.failed().contains(n) || sim.node(m).view().failed.contains(n)) continue;
                // A paused monitor takes no step: counting restarts when it resumes.
                const TimeNs from = std::max({*down, since_[m], sim.paused_until(m), readmitted_at(m, n)});
                // Periods the monitor did not count because it heard no one or ran late
                // (self-suspicion) delay its declarations by as many periods.
                const auto suspected = static_cast<TimeNs>(monitor.self_suspected_periods() -
                                                           suspected_base_[m]);
                const TimeNs bound = (monitor.heard_once().contains(n) ? heard_bound : grace_bound) +
                                     suspected * period;
                if (sim.now() - from > bound) {
                    sim.report(invariant(), topology.node_name(n) + " crashed " +
                                                std::to_string((sim.now() - *down) / kMs) +
                                                " ms ago and monitor " + topology.node_name(m) +
                                                " has not declared it (bound " +
                                                std::to_string(bound / kMs) + " ms)");
                    return;
                }
            }
        }
    }

private:
    TimeNs& readmitted_at(NodeId monitor, NodeId node) {
        return readmitted_at_[monitor * excluded_.size() + node];
    }

    // Per node of the mission (sized at the first step).
    std::vector<TimeNs> since_;
    std::vector<std::uint32_t> incarnation_;
    std::vector<std::uint64_t> suspected_base_;
    // Per monitor, the nodes its view excluded after the last step, and when its view
    // last stopped excluding each node (monitor-major, node_count squared).
    std::vector<fsm::NodeSet> excluded_;
    std::vector<TimeNs> readmitted_at_;
};

}  // namespace

std::unique_ptr<Checker> make_completeness() { return std::make_unique<Completeness>(); }

}  // namespace keel::sim
