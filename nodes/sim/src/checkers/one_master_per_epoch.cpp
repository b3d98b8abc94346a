// OneMasterPerEpochInv (spec/MasterElection.tla): no two nodes are ever Master of the same
// epoch, over the whole run (a Master that crashed still owned its epoch).
#include <map>

#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {
namespace {

class OneMasterPerEpoch final : public Checker {
public:
    const char* invariant() const override { return "OneMasterPerEpochInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        // A value-faulty node's own role is not what it says: only correct nodes count.
        if (!sim.alive(node) || sim.value_faulty(node)) return;
        const auto& protocol = sim.node(node);
        if (protocol.election().role() != fsm::Role::Master) return;
        const fsm::Epoch epoch = protocol.epoch();
        auto [it, inserted] = masters_.emplace(epoch, node);
        if (!inserted && it->second != node) {
            const auto& topology = sim.topology();
            sim.report(invariant(), topology.node_name(node) + " and " +
                                        topology.node_name(it->second) +
                                        " are both Master of epoch " + std::to_string(epoch));
        }
    }

private:
    std::map<fsm::Epoch, NodeId> masters_;
};

}  // namespace

std::unique_ptr<Checker> make_one_master_per_epoch() { return std::make_unique<OneMasterPerEpoch>(); }

}  // namespace keel::sim
