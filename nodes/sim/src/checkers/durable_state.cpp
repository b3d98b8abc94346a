// DurableStateInv (core/node/driver.hpp, rule 1; the specs' Restart keeps the epoch, the
// view and the incarnation a node persisted): a node's state is on its disk before any
// message that depends on it leaves, so a node restarts with an epoch no lower than any its
// own Commands named, a view (epoch, seq) no lower than any its Acks named, and an
// incarnation above any its heartbeats carried. A restart from a state that went back on purpose (Simulation::restart with
// rolled_back: a lost write, a restored file) is the environment's doing and exempt; what
// the node says from then on is held to the state it found. A value-faulty node's lies are
// not counted (Simulation::Host records only what a correct node says).
#include "nodes/sim/src/checkers.hpp"

#include <string>
#include <vector>

namespace keel::sim {
namespace {

class DurableState final : public Checker {
public:
    const char* invariant() const override { return "DurableStateInv"; }

    void after_step(Simulation& sim, NodeId node) override {
        if (boots_.empty()) boots_.assign(static_cast<std::size_t>(sim.topology().node_count()), 0);
        if (!sim.booted(node) || sim.boots(node) == boots_[node]) return;
        const bool restart = boots_[node] > 0;
        boots_[node] = sim.boots(node);
        if (!restart || sim.rolled_back(node) || sim.value_faulty(node)) return;
        const fsm::NodeProtocol& protocol = sim.node(node);
        const fsm::PersistentState saved = protocol.persistent_state();
        const fsm::View& view = saved.view;
        const auto [epoch, seq] = sim.said_view(node);
        const std::string name = sim.topology().node_name(node);
        if (saved.epoch < sim.said_epoch(node)) {
            sim.report(invariant(), name + " restarted with epoch " + std::to_string(saved.epoch) +
                                        " saved, though before it commanded in epoch " +
                                        std::to_string(sim.said_epoch(node)));
            return;
        }
        if (std::pair{view.epoch, view.seq} < std::pair{epoch, seq}) {
            sim.report(invariant(), name + " restarted with view " + std::to_string(view.epoch) + "." +
                                        std::to_string(view.seq) + " saved, though before it said " +
                                        std::to_string(epoch) + "." + std::to_string(seq));
            return;
        }
        if (protocol.monitor().incarnation() <= sim.said_incarnation(node)) {
            sim.report(invariant(), name + " restarted as incarnation " +
                                        std::to_string(protocol.monitor().incarnation()) +
                                        ", though its heartbeats already carried " +
                                        std::to_string(sim.said_incarnation(node)));
        }
    }

private:
    std::vector<std::uint32_t> boots_;  // per node, the boot last seen
};

}  // namespace

std::unique_ptr<Checker> make_durable_state() { return std::make_unique<DurableState>(); }

}  // namespace keel::sim
