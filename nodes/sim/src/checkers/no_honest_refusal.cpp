// NoHonestRefusalInv (fault model 3, core/fsm/admission.hpp): every node of a simulation is
// honest, so no node ever refuses a message as malformed, unauthorized or no Master's, nor
// hears a member prepare another view under its own view's id (prepared_diverged). The
// receivers' checks must never cost a correct cluster anything: a refusal here is a check
// that is wrong about an honest message (a switch the graph allows, an epoch a take-over
// may open, a sender whose role may send it), which would stall or split the cluster.
// Nor does the Storage node ever replace a stored checkpoint by its host's older write
// (CheckpointStore::overridden): that branch is for a foreign writer's pin only.
#include <numeric>

#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class NoHonestRefusal final : public Checker {
public:
    const char* invariant() const override { return "NoHonestRefusalInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        if (!sim.booted(node)) return;
        const auto& protocol = sim.node(node);
        const fsm::NodeStats& stats = protocol.stats();
        const auto sum = [](const auto& counts) { return std::accumulate(counts.begin(), counts.end(), std::uint64_t{0}); };
        // A Prepared naming another view under a view's id: only a Master's two views make
        // one, or a liar's changed copy of its Command, which the member follows honestly.
        const std::uint64_t refused = sum(stats.malformed) + sum(stats.unauthorized) + stats.commands_refused +
                                      (sim.any_value_faulty() ? 0 : stats.prepared_diverged);
        // Fault model 3: refusing a liar's message is the point; a correct node refusing a
        // correct node's message is still a violation, whatever the liar said before.
        bool honest = !sim.value_faulty(node) && !sim.delivered_lie();
        // A task's state the liar spoke for within its authority (a restore reply of a
        // value-faulty Storage node, say, of a lineage from the future) makes its host's
        // honest writes refusable: not covered (docs/fault-model.md).
        if (const fsm::Message* message = sim.delivered()) {
            if (const auto* write = std::get_if<fsm::CheckpointWrite>(message)) {
                if (write->task < sim.topology().task_count() && sim.state_at_liars_word(write->task)) honest = false;
            }
        }
        if (refused > reported_ && !honest) reported_ = refused;
        if (refused > reported_) {
            reported_ = refused;
            sim.report(invariant(), sim.topology().node_name(node) + " refused an honest node's message: " +
                                        protocol.last_refusal());
        }
        const std::uint64_t overridden = protocol.store() != nullptr ? protocol.store()->overridden() : 0;
        // A liar that may host a task can pin it; the host's write replacing the pin is right.
        if (overridden > overridden_ && sim.any_value_faulty()) overridden_ = overridden;
        if (overridden > overridden_) {
            overridden_ = overridden;
            sim.report(invariant(), sim.topology().node_name(node) +
                                        " replaced a stored checkpoint by its host's older write");
        }
    }

private:
    std::uint64_t reported_ = 0;  // once per new refusal, not after every later step
    std::uint64_t overridden_ = 0;
};

}  // namespace

std::unique_ptr<Checker> make_no_honest_refusal() { return std::make_unique<NoHonestRefusal>(); }

}  // namespace keel::sim
