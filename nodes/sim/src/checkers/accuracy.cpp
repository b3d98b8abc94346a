// AccuracyInv (spec/Heartbeat.tla): with fewer than miss_limit heartbeats lost in a row,
// no running node is declared failed. The simulator knows every heartbeat the network
// dropped on each link, so a declaration of a node that is running and never crashed
// must follow at least miss_limit - 1 drops in a row on that link (network delay stays
// below half a period, so one empty period is all jitter alone can cause). A node with an
// omission fault of its own (paused, deaf, behind a blocked link) is exempt: it may rightly
// be declared. Self-suspicion clause: a monitor that has been deaf (receiving nothing) for
// two periods declares no running node at all.
//
// Start-up clause (the start-up grace): a node the monitor has never heard since it booted
// is declared for missed heartbeats only after the monitor has been monitoring for at
// least startup_grace_periods - 1 periods, whatever the node's state (it may not have
// booted yet: real processes start late). The drop count above applies once it was heard.
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class Accuracy final : public Checker {
public:
    const char* invariant() const override { return "AccuracyInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        const auto& topology = sim.topology();
        // Monitoring as it stood before this step: a monitor that declares and stops
        // monitoring in one step (it takes over and resigns at once) was monitoring.
        check_declarations(sim, node, topology);
        track_monitoring(sim);
    }

private:
    void check_declarations(Simulation& sim, NodeId node, const fsm::Topology& topology) {
        if (since_.empty()) track_monitoring(sim);
        for (const auto& action : sim.step_actions()) {
            const auto* declared = std::get_if<fsm::act::DeclareFailed>(&action);
            if (declared == nullptr || declared->reason != fsm::act::FailureReason::missed) continue;
            const NodeId target = declared->node;
            if (!sim.booted(node)) continue;
            // Fault model 3: a liar's declarations are its own; a liar may rightly be declared.
            if (sim.value_faulty(node) || sim.ever_value_faulty(target)) continue;
            // Self-suspicion: a monitor deaf for a whole period or more counts no miss, so it
            // declares no one that runs (spec/Exclusion.tla, rule 1).
            const auto deaf = sim.deaf_since(node);
            if (deaf && sim.now() - *deaf >= 2 * topology.heartbeat_period_ns() && sim.alive(target) &&
                !sim.ever_crashed(target) && !sim.paused(target)) {
                sim.report(invariant(), topology.node_name(node) + " declared " + topology.node_name(target) +
                                            " failed while it has been deaf for " +
                                            std::to_string((sim.now() - *deaf) / kMs) +
                                            " ms: it must suspect itself first");
                return;
            }
            if (!sim.node(node).monitor().heard_once().contains(target)) {
                const int grace = topology.startup_grace_periods();
                const TimeNs watched = since_[node] < 0 ? 0 : sim.now() - since_[node];
                if (watched < (grace - 1) * topology.heartbeat_period_ns()) {
                    sim.report(invariant(), topology.node_name(node) + " declared " +
                                                topology.node_name(target) +
                                                ", never heard since it booted, after " +
                                                std::to_string(watched / kMs) +
                                                " ms of monitoring (start-up grace " +
                                                std::to_string(grace) + " periods)");
                    return;
                }
                continue;
            }
            // A paused (stopped) process sends nothing, like a crashed one; any node with an
            // omission fault of its own may rightly be declared.
            if (!sim.alive(target) || sim.ever_crashed(target) || sim.omission_faulty(target)) continue;
            const int drops = sim.heartbeat_drops_in_row(target, node);
            if (drops < topology.miss_limit() - 1) {
                sim.report(invariant(), topology.node_name(node) + " declared " +
                                            topology.node_name(target) +
                                            " failed, but it is running and only " +
                                            std::to_string(drops) +
                                            " of its heartbeats in a row were lost (miss limit " +
                                            std::to_string(topology.miss_limit()) + ")");
                return;
            }
        }
    }

    // When each node began monitoring (a new incarnation starts afresh), as the
    // HeartbeatMonitor's counts do.
    void track_monitoring(const Simulation& sim) {
        if (since_.empty()) {
            since_.assign(static_cast<std::size_t>(sim.topology().node_count()), -1);
            incarnation_.assign(static_cast<std::size_t>(sim.topology().node_count()), 0);
        }
        for (NodeId m = 0; m < sim.topology().node_count(); ++m) {
            if (!sim.booted(m)) continue;
            const auto& monitor = sim.node(m).monitor();
            const bool monitoring = sim.alive(m) && monitor.monitoring();
            if (!monitoring || monitor.incarnation() != incarnation_[m]) {
                since_[m] = -1;
                incarnation_[m] = monitor.incarnation();
            }
            if (monitoring && since_[m] < 0) since_[m] = sim.now();
        }
    }

    // Per node of the mission (sized at the first step).
    std::vector<TimeNs> since_;
    std::vector<std::uint32_t> incarnation_;
};

}  // namespace

std::unique_ptr<Checker> make_accuracy() { return std::make_unique<Accuracy>(); }

}  // namespace keel::sim
