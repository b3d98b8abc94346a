// NoFalseExclusionInv (spec/Exclusion.tla): a node the acting Master excludes is down, or
// had an omission fault of its own (deaf, paused, a blocked link to or from it, resigned,
// held out by the ground, restarted, booted just now after being declared while down), or its heartbeats were lost at least miss_limit - 1 times in a row on the
// link to a monitor that has no omission fault itself: evidence a single faulty monitor
// cannot fabricate. (miss_limit - 1, as AccuracyInv: one empty period is all jitter alone
// can cause.) Checked at the step in which the exclusion enters the Master's view, while
// at most one node has crashed or had an omission fault: the guarantee is about a single
// faulty node.
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class NoFalseExclusion final : public Checker {
public:
    const char* invariant() const override { return "NoFalseExclusionInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        // A value-faulty Master may fence a correct node (docs/fault-model.md, not covered).
        if (!sim.alive(node) || !sim.node(node).is_master() || sim.value_faulty(node)) return;
        const auto& topology = sim.topology();
        if (seen_.empty()) {
            seen_.resize(static_cast<std::size_t>(topology.node_count()));
            epoch_.resize(static_cast<std::size_t>(topology.node_count()));
        }
        const auto& protocol = sim.node(node);
        const NodeSet excluded = protocol.manager().driving().failed;
        const NodeSet fresh = excluded.minus(seen_[node]);
        seen_[node] = excluded;
        if (protocol.epoch() != epoch_[node]) {
            // A Master of a new epoch starts from the view it took over: only what it adds
            // from now on is its own decision.
            epoch_[node] = protocol.epoch();
            return;
        }
        // The guarantee is about one faulty node: with two (a crash that leaves the Master
        // the last voter, and a Master deaf to the rest), no rule can tell (spec/Exclusion.tla).
        int faulty = 0;
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            const TimeNs grace = topology.startup_grace_periods() * topology.heartbeat_period_ns();
            const bool late_boot = !sim.booted(n) || sim.booted_at(n).value_or(0) > grace;
            if (sim.ever_crashed(n) || sim.omission_faulty(n) || sim.ever_value_faulty(n) || late_boot) ++faulty;
        }
        if (faulty > 1) return;
        fresh.for_each([&](NodeId target) {
            if (!sim.alive(target) || sim.ever_crashed(target) || sim.omission_faulty(target) ||
                sim.ever_value_faulty(target) || sim.fenced_by_liar(target)) {
                return;
            }
            if (!sim.booted(target)) return;
            // A node that booted after its start-up grace was declared while it was down:
            // an exclusion that lands just after its boot is right.
            const TimeNs recent = (topology.miss_limit() + 1) * topology.heartbeat_period_ns();
            const TimeNs booted = sim.booted_at(target).value_or(0);
            if (sim.now() - booted < recent) return;
            // Or it booted after the start-up grace: it was rightly declared while down, and
            // the Master may act on that evidence late (it was paused, e.g.).
            if (booted > topology.startup_grace_periods() * topology.heartbeat_period_ns()) return;
            // The node's own word: it resigned, or stepped down as a cut-off Master.
            if (sim.node(target).resign_state() != fsm::NodeProtocol::Resign::none) return;
            // The ground's: the Master holds it out (docs/operations.md, `exclude`).
            if (protocol.held_out().contains(target)) return;
            // The run may have ended since: a monitor declares at the boundary after it, and
            // a heartbeat delivered before the Master decides (its reports count for 2
            // periods) ends it (keel-sim --loss 5%, earth-observation seed 11901: two of
            // IF1's heartbeats to PN2 lost, PN2 declared IF1, IF1's next one arrived 2 ms
            // before PN1 excluded it).
            const TimeNs within = 3 * topology.heartbeat_period_ns();
            bool evidence = false;
            topology.processing_nodes().for_each([&](NodeId monitor) {
                if (monitor == target || sim.omission_faulty(monitor) || !sim.alive(monitor)) return;
                if (sim.heartbeat_drops_in_row_within(target, monitor, within) >= topology.miss_limit() - 1) {
                    evidence = true;
                }
            });
            if (evidence) return;
            sim.report(invariant(), topology.node_name(node) + " excluded " + topology.node_name(target) +
                                        ", which is running and has no omission fault, while no "
                                        "healthy monitor lost " +
                                        std::to_string(topology.miss_limit() - 1) +
                                        " of its heartbeats in a row");
        });
    }

private:
    // Per node of the mission (sized at the first step).
    std::vector<NodeSet> seen_;
    std::vector<fsm::Epoch> epoch_;
};

}  // namespace

std::unique_ptr<Checker> make_no_false_exclusion() { return std::make_unique<NoFalseExclusion>(); }

}  // namespace keel::sim
