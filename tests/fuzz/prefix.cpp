#include "tests/fuzz/prefix.hpp"

#include <cassert>

namespace keel::fuzz {

std::vector<Scenario> scenarios(const fsm::Topology& topology) {
    using Kind = ScenarioEvent::Kind;
    const int nodes = topology.node_count();
    const fsm::NodeSet all = topology.all_nodes();
    const auto name = [&](int node) { return topology.node_name(static_cast<NodeId>(node)); };
    std::vector<Scenario> list;
    list.push_back({"boot", all, {}});
    for (int n = 0; n < nodes; ++n) {
        list.push_back({"crash " + name(n), all, {{kEventRound, Kind::crash, n}}});
    }
    for (int n = 0; n < nodes; ++n) {
        fsm::NodeSet booted = all;
        booted.erase(static_cast<NodeId>(n));
        list.push_back({"late " + name(n), booted, {{kLateBootRound, Kind::restart, n}}});
    }
    for (int n = 0; n < nodes; ++n) {
        list.push_back(
            {"restart " + name(n),
             all,
             {{kEventRound, Kind::crash, n}, {kEventRound + kRestartDelay, Kind::restart, n}}});
    }
    for (int n = 0; n < nodes; ++n) {
        list.push_back({"resign " + name(n), all, {{kEventRound, Kind::resign, n}}});
    }
    for (int p = 1; p < topology.phase_count(); ++p) {
        list.push_back({"phase " + topology.phase(static_cast<fsm::PhaseId>(p)).name,
                        all,
                        {{kEventRound, Kind::phase, p}}});
    }
    std::vector<int> processing;
    topology.processing_nodes().for_each([&](NodeId node) { processing.push_back(node); });
    for (std::size_t a = 0; a < processing.size(); ++a) {
        for (std::size_t b = a + 1; b < processing.size(); ++b) {
            list.push_back({"crash " + name(processing[a]) + " then " + name(processing[b]),
                            all,
                            {{kEventRound, Kind::crash, processing[a]},
                             {kEventRound + kSecondCrashDelay, Kind::crash, processing[b]}}});
        }
    }
    return list;
}

Prefixes::Prefixes(const fsm::Topology& topology, bool tracing) : scenarios_(scenarios(topology)) {
    using Kind = ScenarioEvent::Kind;
    const TimeNs period = topology.heartbeat_period_ns();
    const NodeId initial_master = topology.initial_view().master;
    for (const Scenario& scenario : scenarios_) {
        std::vector<Cluster> rounds;
        rounds.reserve(kPrefixRounds + 1);
        Cluster cluster(topology, scenario.booted, tracing);
        for (int round = 0; round <= kPrefixRounds; ++round) {
            cluster.run_until(round * period);
            for (const ScenarioEvent& event : scenario.events) {
                if (event.round != round) continue;
                const auto node = static_cast<NodeId>(event.argument);
                switch (event.kind) {
                    case Kind::crash:
                        cluster.crash(node);
                        break;
                    case Kind::restart:
                        cluster.restart(node);
                        break;
                    case Kind::resign:
                        cluster.resign(node);
                        break;
                    case Kind::phase:
                        cluster.request_phase(initial_master,
                                              static_cast<fsm::PhaseId>(event.argument));
                        break;
                }
            }
            rounds.push_back(cluster);
        }
        clusters_.push_back(std::move(rounds));
    }
}

const Cluster& Prefixes::at(int scenario, int rounds) const {
    assert(scenario >= 0 && scenario < scenario_count() && rounds >= 0 && rounds <= kPrefixRounds);
    return clusters_[static_cast<std::size_t>(scenario)][static_cast<std::size_t>(rounds)];
}

}  // namespace keel::fuzz
