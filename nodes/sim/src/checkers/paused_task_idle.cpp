// PausedTaskIdleInv (docs/operations.md, `pause-task`; trace validation's rule that a task
// a node holds paused takes no step there, spec/trace/TraceConfigSwitch.tla): a task the
// ground paused runs on no node that took the pause, and no node holds an essential task
// paused (an essential task always runs). Checked on the tasks actually running.
#include "core/fsm/json.hpp"
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class PausedTaskIdle final : public Checker {
public:
    const char* invariant() const override { return "PausedTaskIdleInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        if (!sim.alive(node) || !sim.booted(node) || sim.value_faulty(node)) return;  // correct nodes only
        const auto& topology = sim.topology();
        const auto& protocol = sim.node(node);
        const fsm::TaskSet& paused = protocol.paused();
        if (paused.empty()) return;
        if (paused.intersects(sim.running(node))) {
            sim.report(invariant(), topology.node_name(node) + " runs " +
                                        fsm::json_tasks(topology, paused & sim.running(node)) +
                                        ", paused by the ground");
            return;
        }
        paused.for_each([&](TaskId task) {
            if (topology.task(task).essential) {
                sim.report(invariant(), topology.node_name(node) + " holds " + topology.task(task).name +
                                            " paused, an essential task");
            }
        });
    }
};

}  // namespace

std::unique_ptr<Checker> make_paused_task_idle() { return std::make_unique<PausedTaskIdle>(); }

}  // namespace keel::sim
