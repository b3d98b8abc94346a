// NoTaskOnFailedNodeInv (spec/ConfigSwitch.tla; the verifier's task-on-failed-node): no
// view a node holds or a Master drives places a task on a node that view has declared
// failed, and a node its own view excludes runs nothing.
#include "core/fsm/json.hpp"
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class NoTaskOnFailedNode final : public Checker {
public:
    const char* invariant() const override { return "NoTaskOnFailedNodeInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        if (!sim.alive(node) || sim.value_faulty(node)) return;  // correct nodes only
        const auto& protocol = sim.node(node);
        check_view(sim, node, protocol.view(), "holds");
        if (protocol.is_master()) check_view(sim, node, protocol.manager().driving(), "drives");
        if (protocol.view().failed.contains(node) && !sim.running(node).empty()) {
            sim.report(invariant(), sim.topology().node_name(node) +
                                        " is excluded by its own view but still runs " +
                                        fsm::json_tasks(sim.topology(), sim.running(node)));
        }
    }

private:
    void check_view(Simulation& sim, NodeId node, const fsm::View& view, const char* verb) {
        const auto& topology = sim.topology();
        for (TaskId task = 0; task < topology.task_count(); ++task) {
            const NodeId host = topology.host(view, task);
            if (host != fsm::kNoNode && view.failed.contains(host)) {
                sim.report(invariant(), topology.node_name(node) + " " + verb + " view " +
                                            topology.config_name(view.config) + " (epoch " +
                                            std::to_string(view.epoch) + " seq " +
                                            std::to_string(view.seq) + ") placing " +
                                            topology.task(task).name + " on failed " +
                                            topology.node_name(host));
                return;
            }
        }
    }
};

}  // namespace

std::unique_ptr<Checker> make_no_task_on_failed_node() { return std::make_unique<NoTaskOnFailedNode>(); }

}  // namespace keel::sim
