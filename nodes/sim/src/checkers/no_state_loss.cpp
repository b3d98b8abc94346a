// NoStateLossInv (fault model 2, item 4): a checkpointed task that starts on a node (not a
// lease resume) never starts below the state that another live node, a member of the
// starting node's view, handed off for it (its state when a switch moved the task away
// while it was a member: ConfigSwitch::handed_off_version), nor below its own hand-off
// (as it stood before the step that starts it). With the Storage node usable
// the final flush has already put that state there (ResumeLatestCheckpointInv); without
// it, the new host must take it from the old one. A state held only by crashed or
// excluded nodes is out of reach: starting below it is the counted, unavoidable loss
// (ConfigSwitch::unrecoverable_starts), not a violation.
#include "core/fsm/json.hpp"
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class NoStateLoss final : public Checker {
public:
    const char* invariant() const override { return "NoStateLossInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        const auto& topology = sim.topology();
        if (own_.size() != static_cast<std::size_t>(topology.node_count())) {
            own_.assign(static_cast<std::size_t>(topology.node_count()),
                        std::vector<std::optional<fsm::Version>>(static_cast<std::size_t>(topology.task_count())));
        }
        check(sim, node);
        for (TaskId task = 0; task < topology.task_count(); ++task) {
            own_[node][task] = sim.node(node).config_switch().handed_off_version(task);
        }
    }

private:
    void check(Simulation& sim, NodeId node) {
        const auto& topology = sim.topology();
        for (const auto& action : sim.step_actions()) {
            const auto* activate = std::get_if<fsm::act::Activate>(&action);
            if (activate == nullptr || activate->resumed ||
                !topology.task(activate->task).checkpoint || sim.value_faulty(node) ||
                sim.state_at_liars_word(activate->task)) {
                continue;
            }
            const fsm::View& view = sim.node(node).view();
            for (NodeId holder = 0; holder < topology.node_count(); ++holder) {
                if (holder != node && (!sim.alive(holder) || view.failed.contains(holder))) continue;
                const auto held =
                    holder == node
                        ? own_[node][activate->task]
                        : sim.node(holder).config_switch().handed_off_version(activate->task);
                if (!held || *held <= activate->from) continue;
                sim.report(invariant(), topology.task(activate->task).name + " started on " +
                                            topology.node_name(node) + " at version " +
                                            fsm::version_text(activate->from) + " while " +
                                            topology.node_name(holder) +
                                            ", a live member of its view, had handed off version " +
                                            fsm::version_text(*held));
                return;
            }
        }
    }

    // Per node, its hand-offs after its last step.
    std::vector<std::vector<std::optional<fsm::Version>>> own_;  // per node, per task
};

}  // namespace

std::unique_ptr<Checker> make_no_state_loss() { return std::make_unique<NoStateLoss>(); }

}  // namespace keel::sim
