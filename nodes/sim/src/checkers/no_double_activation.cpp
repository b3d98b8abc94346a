// NoDoubleActivationInv (spec/ConfigSwitch.tla): a task runs on two live nodes only when
// one of them is excluded by the other's view — a node the cluster has declared failed
// may still run what it ran until it hears so, but two nodes that both count each other
// as live never run the same task. Checked on the tasks actually running (ground truth).
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class NoDoubleActivation final : public Checker {
public:
    const char* invariant() const override { return "NoDoubleActivationInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        // A stopped (paused) process runs nothing until it resumes.
        // Fault model 3: the correct nodes (a liar's own tasks are its own business).
        if (!sim.alive(node) || sim.paused(node) || sim.value_faulty(node)) return;
        const auto& topology = sim.topology();
        const fsm::TaskSet& mine = sim.running(node);
        if (mine.empty()) return;
        const fsm::View& my_view = sim.node(node).view();
        for (NodeId other = 0; other < topology.node_count(); ++other) {
            if (other == node || !sim.alive(other) || sim.paused(other) || sim.value_faulty(other)) continue;
            if (!mine.intersects(sim.running(other))) continue;
            const fsm::TaskSet both = mine & sim.running(other);
            const fsm::View& other_view = sim.node(other).view();
            if (my_view.failed.contains(other) || other_view.failed.contains(node)) continue;
            both.for_each([&](TaskId task) {
                sim.report(invariant(), topology.task(task).name + " runs on " +
                                            topology.node_name(node) + " (epoch " +
                                            std::to_string(my_view.epoch) + " seq " +
                                            std::to_string(my_view.seq) + ") and " +
                                            topology.node_name(other) + " (epoch " +
                                            std::to_string(other_view.epoch) + " seq " +
                                            std::to_string(other_view.seq) + ")");
            });
            return;
        }
    }
};

}  // namespace

std::unique_ptr<Checker> make_no_double_activation() { return std::make_unique<NoDoubleActivation>(); }

}  // namespace keel::sim
