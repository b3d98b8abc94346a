// SwitchConverges: once faults have stopped and the cluster has had time to settle, there is
// one acting Master (the alive Master of the highest epoch) and it is idle; every alive
// node it has not excluded holds exactly its view, is Stable and runs exactly the tasks
// that view places on it (but those the ground paused, as that node took its commands);
// every alive node it has excluded runs nothing, and stays excluded only while the
// configuration of the smaller failed set is safe mode (reintegration, spec/Rejoin.tla);
// every crashed node is among the excluded. A cluster with no alive Master agrees only when no alive,
// non-excluded Observer could have taken over (more failures than monitors: headless by
// the fault model, not by a protocol error), or when the Observers that could lack the
// second monitor's evidence a take-over needs, or the lease (spec/Lease.tla: a monitor
// behind them that they cannot hear might succeed them). A down node the Master holds failed without
// the second monitor's evidence it needs (spec/Exclusion.tla) may stay unexcluded.
#include <algorithm>

#include "core/fsm/json.hpp"
#include "core/fsm/online.hpp"
#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {

bool check_converged(const Simulation& sim, std::string* why) {
    const auto& topology = sim.topology();
    auto fail = [&](std::string message) {
        if (why != nullptr) *why = std::move(message);
        return false;
    };
    const auto master = sim.acting_master();
    // A whole-cluster power cycle: every processing node is up and waits to be commanded,
    // or knows itself excluded (fenced by a value-faulty Master that then restarted). One
    // of them warm-boots (spec/MasterElection.tla, WarmBoot) once it has heard them all
    // for miss_limit periods: not settled before.
    if (!master) {
        bool all_waiting = true;
        topology.processing_nodes().for_each([&](NodeId n) {
            if (!sim.alive(n) || !(sim.node(n).waiting() || sim.node(n).view().failed.contains(n))) {
                all_waiting = false;
            }
        });
        // The warm boot is the initial Master's, which must not have resigned.
        const NodeId first = topology.priority().front();
        if (all_waiting && sim.node(first).resign_state() == fsm::NodeProtocol::Resign::none) {
            return fail("every processing node waits to be commanded (no warm boot yet)");
        }
    }
    // An Observer stalled by the lease holds back the ones behind it, which wait for it.
    if (!master && sim.lease_stalled()) return true;
    // So does one that lacks the evidence a take-over needs (a majority of its view's
    // monitors: spec/Quorum.tla) because too few of those monitors can give it: they went
    // down, their lease lapsed (by a joint view where the node down was one of the last
    // two), or they never adopted the view (a partition cut the switch to it, so they do
    // not know they monitor, or their newer view excluded it and they watch it no more),
    // and a node it waits on is down. Beyond the tolerance that evidence may never come; within it
    // the plan's own check still reports a cluster without a Master.
    if (!master) {
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            if (!sim.alive(n) || !sim.node(n).awaiting_takeover_evidence()) continue;
            const fsm::View& held = sim.node(n).view();
            // Nodes ahead of it that are all alive can still give their own word (a Master
            // that resigned says so): wait for them. One that is down cannot.
            bool ahead_down = held.master < topology.node_count() && !sim.alive(held.master);
            for (NodeId observer : topology.observers(held)) {
                if (observer == n) break;
                if (!held.failed.contains(observer) && !sim.alive(observer)) ahead_down = true;
            }
            if (!ahead_down) continue;
            const fsm::NodeSet members = topology.monitors(held).minus(held.failed);
            int able = 0;
            members.for_each([&](NodeId m) {
                // Only a member that holds its lease reports (spec/Quorum.tla, rule 4).
                if (m != held.master && sim.alive(m) && sim.node(m).view() == held &&
                    sim.node(m).holds_lease()) {
                    ++able;
                }
            });
            const int quorum = std::max(1, std::min(members.size() / 2 + 1, members.size() - 1));
            if (able < quorum) return true;
        }
    }
    if (!master) {
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            if (!sim.alive(n)) continue;
            const auto& protocol = sim.node(n);
            // An Observer that asked to be excluded (resign) never takes over.
            if (protocol.election().role() == fsm::Role::Observer && !protocol.config_switch().excluded() &&
                protocol.resign_state() == fsm::NodeProtocol::Resign::none &&
                !protocol.awaiting_takeover_evidence()) {
                return fail("no alive Master, yet Observer " + topology.node_name(n) +
                            " is alive and was not excluded");
            }
        }
        return true;
    }
    const auto& leader = sim.node(*master);
    const fsm::View& view = leader.manager().driving();
    // A Master that lacks a second monitor's evidence on a node that is down (monitors that
    // went down together, beyond the tolerance) stalls where it is: by the fault model,
    // not a protocol error.
    for (NodeId n = 0; n < topology.node_count(); ++n) {
        if (!sim.alive(n) && leader.awaiting_evidence(n)) return true;
    }
    if (leader.config_switch().master_stage() != fsm::MasterStage::Idle) {
        return fail("Master " + topology.node_name(*master) + " is still switching (" +
                    fsm::to_string(leader.config_switch().master_stage()) + ")");
    }
    for (NodeId n = 0; n < topology.node_count(); ++n) {
        if (!sim.alive(n)) {
            if (!view.failed.contains(n)) {
                return fail(topology.node_name(n) + " is down but Master " +
                            topology.node_name(*master) + " has not excluded it");
            }
            continue;
        }
        const auto& protocol = sim.node(n);
        if (view.failed.contains(n)) {
            if (!sim.running(n).empty()) {
                return fail("excluded " + topology.node_name(n) + " still runs " +
                            fsm::json_tasks(topology, sim.running(n)));
            }
            // Reintegration (spec/Rejoin.tla): an alive node stays out only while the
            // configuration of the smaller failed set is still safe mode.
            const fsm::Target back = fsm::recovery_target(topology, view, n);
            if (!back.is_safe()) {
                return fail(topology.node_name(n) + " is alive and still excluded, though " +
                            topology.config_name(back.config) + " would take it back");
            }
            continue;
        }
        const fsm::View& held = protocol.view();
        if (!(held == view)) {
            return fail(topology.node_name(n) + " holds " + topology.config_name(held.config) +
                        " epoch " + std::to_string(held.epoch) + " seq " + std::to_string(held.seq) +
                        ", Master " + topology.node_name(*master) + " drives " +
                        topology.config_name(view.config) + " epoch " + std::to_string(view.epoch) +
                        " seq " + std::to_string(view.seq));
        }
        if (protocol.config_switch().stage() != fsm::Stage::Stable) {
            return fail(topology.node_name(n) + " is " + fsm::to_string(protocol.config_switch().stage()));
        }
        if (n != *master && protocol.is_master()) {
            return fail(topology.node_name(n) + " also acts as Master");
        }
        // Less the tasks the ground paused, as this node took its commands.
        const fsm::TaskSet expected = topology.tasks_on(view, n).minus(protocol.paused());
        if (!(sim.running(n) == expected)) {
            return fail(topology.node_name(n) + " runs " + fsm::json_tasks(topology, sim.running(n)) +
                        ", its view places " + fsm::json_tasks(topology, topology.tasks_on(view, n)) +
                        (protocol.paused().empty() ? std::string() :
                                                     ", the ground paused " + fsm::json_tasks(topology, protocol.paused())));
        }
    }
    return true;
}

}  // namespace keel::sim
