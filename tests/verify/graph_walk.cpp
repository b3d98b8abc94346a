// keel-graph-walk IMAGE: the runtime's reading of a mission's decision graph, for the
// differential test of tests/verify/test_graph_semantics.py (a test tool: no node runs it).
//
// Reads queries from stdin, one per line: `CONFIG X FAILED...` (the configuration the
// cluster is in, the node that fails, the nodes that had failed before). Prints, per query,
// the configuration the cluster switches to, as keel-node's state machines decide it:
//  - X is the configuration's master: the node the election makes Master (the first
//    observer of the view that has not failed, else the first processing node of the
//    succession) takes over (ReconfigurationManager::take_over with X suspected);
//  - another node: the master excludes it (ReconfigurationManager::exclude).
// `SAFE` for safe mode. A query `recover CONFIG X FAILED...` (X among FAILED) prints where
// readmitting X leads (Topology::recovery_target: the on_recovery edge, else the walk from
// the phase's initial configuration). Exit 2 with a message when the image does not load
// or a query names what the mission does not have.
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "core/fsm/reconfiguration_manager.hpp"
#include "core/fsm/topology.hpp"
#include "core/mission/image.hpp"

namespace {

using namespace keel::fsm;

ConfigId decide(const Topology& topology, ConfigId config, NodeId failing, const NodeSet& failed) {
    View view;
    view.epoch = 1;
    view.seq = 1;
    view.config = view.base = config;
    view.master = topology.config(config).master;
    view.failed = failed;
    Outbox out{false};
    if (failing == view.master) {
        NodeSet after = failed;
        after.insert(failing);
        View without = view;
        without.failed = after;
        NodeId taker = kNoNode;
        for (NodeId observer : topology.observers(without)) {
            if (!after.contains(observer)) {
                taker = observer;
                break;
            }
        }
        for (NodeId node : topology.priority()) {
            if (taker == kNoNode && !after.contains(node)) taker = node;
        }
        if (taker == kNoNode) return kSafeConfig;
        ReconfigurationManager manager(topology, taker, Mutant::none);
        NodeSet suspects;
        suspects.insert(failing);
        return manager.take_over(view, 2, suspects, TakeOverEvidence{}, out).config;
    }
    ReconfigurationManager manager(topology, view.master, Mutant::none);
    manager.take_over(view, 2, NodeSet{}, TakeOverEvidence{}, out);  // drive (config, failed)
    const auto next = manager.exclude(failing, Evidence::own_word(), out);
    return next ? next->config : manager.driving().config;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: keel-graph-walk IMAGE < QUERIES\n";
        return 2;
    }
    const keel::mission::LoadResult loaded = keel::mission::load_mission_image(argv[1], {});
    if (!loaded.ok()) {
        for (const auto& error : loaded.errors) std::cerr << error.to_string() << '\n';
        return 2;
    }
    std::string why;
    const auto topology = Topology::build(*loaded.mission, &why);
    if (!topology) {
        std::cerr << argv[1] << ": topology: " << why << '\n';
        return 2;
    }
    std::string line;
    for (int number = 1; std::getline(std::cin, line); ++number) {
        std::istringstream words(line);
        std::string config_name;
        std::string failing_name;
        if (!(words >> config_name >> failing_name)) continue;
        const bool recover = config_name == "recover";
        if (recover) {
            config_name = failing_name;
            if (!(words >> failing_name)) continue;
        }
        const auto config = topology->config_id(config_name);
        const auto failing = topology->node_id(failing_name);
        NodeSet failed;
        bool known = config && *config != kSafeConfig && failing;
        for (std::string name; words >> name;) {
            const auto node = topology->node_id(name);
            if (node) failed.insert(*node);
            known = known && node;
        }
        if (!known) {
            std::cerr << "stdin:" << number << ": a name the mission does not have: " << line << '\n';
            return 2;
        }
        if (recover) {
            View view;
            view.config = view.base = *config;
            view.master = topology->config(*config).master;
            view.failed = failed;
            std::cout << topology->config_name(topology->recovery_target(view, *failing)) << '\n';
            continue;
        }
        std::cout << topology->config_name(decide(*topology, *config, *failing, failed)) << '\n';
    }
    return std::cout ? 0 : 2;
}
