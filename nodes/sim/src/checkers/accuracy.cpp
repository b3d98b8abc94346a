// AccuracyInv (spec/Heartbeat.tla): with fewer than miss_limit heartbeats lost in a row,
// no running node is declared failed. The simulator knows every heartbeat the network
// dropped on each link, so a declaration of a node that is running and never crashed
// must follow at least miss_limit - 1 drops in a row on that link (network delay stays
// below half a period, so one empty period is all jitter alone can cause).
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class Accuracy final : public Checker {
public:
    const char* invariant() const override { return "AccuracyInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        const auto& topology = sim.topology();
        for (const auto& action : sim.step_actions()) {
            const auto* declared = std::get_if<fsm::act::DeclareFailed>(&action);
            if (declared == nullptr || declared->reason != fsm::act::FailureReason::missed) continue;
            const NodeId target = declared->node;
            if (!sim.alive(target) || sim.ever_crashed(target)) continue;
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
};

}  // namespace

std::unique_ptr<Checker> make_accuracy() { return std::make_unique<Accuracy>(); }

}  // namespace keel::sim
