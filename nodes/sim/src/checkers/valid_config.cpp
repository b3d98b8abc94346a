// ValidConfigInv (spec/ValueFault.tla): no correct node holds a view, nor drives one as
// Master, that the proven decision graph does not place (admission.hpp's view_problem:
// outside safe mode the configuration is its base and names the view's master; in safe
// mode the master is a processing node; the master is not failed; no task is on a failed
// node; the epoch belongs to the master). Every honest Master commands only such views,
// so a violation needs a value-faulty node (keel-sim --liar) whose Command a receiver
// followed unchecked (mutant no-view-check). A node with no view yet holds none.
#include "core/fsm/admission.hpp"
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class ValidConfig final : public Checker {
public:
    const char* invariant() const override { return "ValidConfigInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        if (!sim.alive(node) || sim.value_faulty(node)) return;
        const auto& protocol = sim.node(node);
        check(sim, node, protocol.view(), "holds");
        if (protocol.is_master()) check(sim, node, protocol.manager().driving(), "drives");
    }

private:
    void check(Simulation& sim, NodeId node, const fsm::View& view, const char* verb) {
        if (view.config == fsm::kNoConfig || view.epoch == 0) return;
        if (auto problem = fsm::view_problem(view, sim.topology())) {
            sim.report(invariant(), sim.topology().node_name(node) + " " + verb + " view " +
                                        sim.topology().config_name(view.config) + " (epoch " +
                                        std::to_string(view.epoch) + " seq " + std::to_string(view.seq) +
                                        "), which the graph does not place: " + *problem);
        }
    }
};

}  // namespace

std::unique_ptr<Checker> make_valid_config() { return std::make_unique<ValidConfig>(); }

}  // namespace keel::sim
