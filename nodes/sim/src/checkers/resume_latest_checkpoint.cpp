// ResumeLatestCheckpointInv (spec/ConfigSwitch.tla's `stored` and `version`): when a
// checkpointed task starts on a node while the Storage node is alive and not excluded by
// that node's view, it starts from exactly the latest version stored (so a migrated task
// resumes where its previous owner's last checkpoint left it); the state it is given
// matches that version; and the stored version of a task never decreases. A task that
// resumes on its own node after a lease hold (Activate.resumed) continues from its own
// state: never below the stored version.
#include "core/fsm/json.hpp"
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class ResumeLatestCheckpoint final : public Checker {
public:
    const char* invariant() const override { return "ResumeLatestCheckpointInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        const auto& topology = sim.topology();
        const NodeId storage = topology.storage_node();
        if (storage == fsm::kNoNode || !sim.booted(storage)) return;
        const fsm::CheckpointStore* store = sim.node(storage).store();
        for (const auto& action : sim.step_actions()) {
            const auto* activate = std::get_if<fsm::act::Activate>(&action);
            if (activate == nullptr || !topology.task(activate->task).checkpoint) continue;
            if (sim.value_faulty(node) || sim.state_at_liars_word(activate->task)) continue;
            if (!activate->state.empty() && decode_counter(activate->state) != activate->version.count) {
                sim.report(invariant(), topology.task(activate->task).name + " on " +
                                            topology.node_name(node) +
                                            " was given a state that does not match version " +
                                            fsm::version_text(activate->version));
                return;
            }
            const bool usable = sim.alive(storage) && !sim.node(node).view().failed.contains(storage);
            if (!usable || store == nullptr) continue;
            const fsm::Version stored = store->latest_version(activate->task).value_or(fsm::Version{});
            if (activate->resumed ? activate->version < stored : activate->version != stored) {
                sim.report(invariant(), topology.task(activate->task).name + " started on " +
                                            topology.node_name(node) + " at version " +
                                            fsm::version_text(activate->version) +
                                            " but the Storage node holds version " +
                                            fsm::version_text(stored));
                return;
            }
        }
        if (node != storage || store == nullptr) return;
        if (highest_.empty()) highest_.resize(static_cast<std::size_t>(topology.task_count()));
        for (TaskId task = 0; task < topology.task_count(); ++task) {
            const fsm::Version now = store->latest_version(task).value_or(fsm::Version{});
            if (now < highest_[task] && !sim.state_at_liars_word(task)) {
                sim.report(invariant(), "stored version of " + topology.task(task).name +
                                            " went back from " + fsm::version_text(highest_[task]) +
                                            " to " + fsm::version_text(now));
                return;
            }
            highest_[task] = now;
        }
    }

private:
    std::vector<fsm::Version> highest_;  // per task (sized at the first store)
};

}  // namespace

std::unique_ptr<Checker> make_resume_latest_checkpoint() { return std::make_unique<ResumeLatestCheckpoint>(); }

}  // namespace keel::sim
