// ResumeLatestCheckpointInv (spec/ConfigSwitch.tla's `stored` and `version`): when a
// checkpointed task starts on a node while the Storage node is alive and not excluded by
// that node's view, it starts from exactly the latest version stored (so a migrated task
// resumes where its previous owner's last checkpoint left it); the state it is given
// matches that version. A task that resumes on its own node after a lease hold
// (Activate.resumed) continues from its own state: never below the stored version.
//
// Stored means durable (spec/Handoff.tla's StoredMonotoneProp; core/node/driver.hpp, rule
// 2): the version the Storage node holds never falls within one of its boots, and never
// below a version it acknowledged or sent in a restore reply, in any boot. A write it had
// not finished when it crashed, and so never confirmed, may be lost.
#include <algorithm>

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
        if (sim.boots(storage) != boot_) {
            // A new boot holds what its disk held: its first step sets the floor.
            boot_ = sim.boots(storage);
            std::fill(highest_.begin(), highest_.end(), fsm::Version{});
        }
        for (TaskId task = 0; task < topology.task_count(); ++task) {
            if (sim.state_at_liars_word(task)) continue;
            const fsm::Version now = store->latest_version(task).value_or(fsm::Version{});
            if (now < highest_[task]) {
                sim.report(invariant(), "stored version of " + topology.task(task).name +
                                            " went back from " + fsm::version_text(highest_[task]) +
                                            " to " + fsm::version_text(now));
                return;
            }
            highest_[task] = now;
            if (const auto said = sim.storage_said(task); said && now < *said) {
                sim.report(invariant(), "the Storage node holds version " + fsm::version_text(now) + " of " +
                                            topology.task(task).name + " after it confirmed version " +
                                            fsm::version_text(*said) + " stored");
                return;
            }
        }
    }

private:
    std::vector<fsm::Version> highest_;  // per task, in the Storage node's boot boot_
    std::uint32_t boot_ = 0;
};

}  // namespace

std::unique_ptr<Checker> make_resume_latest_checkpoint() { return std::make_unique<ResumeLatestCheckpoint>(); }

}  // namespace keel::sim
