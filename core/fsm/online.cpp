#include "core/fsm/online.hpp"

#include <algorithm>
#include <cassert>

#include "core/fsm/json.hpp"
#include "core/placement/check.hpp"
#include "core/placement/place.hpp"

namespace keel::fsm {

namespace {

using Problem = std::optional<std::string>;
using mission::PlacementMode;

int placement_id(NodeId node) { return node == kNoNode ? placement::kNone : static_cast<int>(node); }
NodeId node_of(int id) { return id == placement::kNone ? kNoNode : static_cast<NodeId>(id); }

// The configuration `view` stands for (its base in safe mode), as a Target, to compare.
bool same_configuration(const View& a, const View& b) {
    if (a.config != b.config || a.base != b.base) return false;
    if (!a.is_online()) return true;
    return a.online != nullptr && b.online != nullptr && *a.online == *b.online;
}

// The placer's answer for `phase` under `failed` from `current`, as a target: SAFE when it
// finds no placement of the essential tasks or its master is not `master`.
Target placed(const Topology& topology, PhaseId phase, const NodeSet& failed,
              const placement::Configuration& current, NodeId master) {
    const placement::Placement answer =
        placement::place(topology.placement_model(), phase, failed_of(topology, failed), current);
    if (answer.safe || (master != kNoNode && node_of(answer.config.master) != master)) return Target::safe();
    return Target{kOnlineConfig, online_of(topology, phase, answer.config)};
}

// The configuration the view runs, for the placer, run by `master` (in safe mode the base's
// master may have failed; the node that drives the view is its master now).
placement::Configuration current_of(const Topology& topology, const View& view) {
    placement::Configuration current = placement_of(topology, view);
    if (view.is_safe()) current.master = placement_id(view.master);
    return current;
}

std::string describe(const Topology& topology, const View& view) {
    if (view.config == kOnlineConfig) return "an online configuration of phase " +
                                             topology.phase(view.online->phase).name;
    return topology.config_name(view.config);
}

}  // namespace

NodeId master_of(const Topology& topology, const Target& target) {
    assert(!target.is_safe());
    return target.online ? target.online->master : topology.config(target.config).master;
}

placement::Configuration placement_of(const Topology& topology, const View& view) {
    placement::Configuration config;
    const ConfigId id = view.is_safe() ? view.base : view.config;
    const auto fill = [&](NodeId master, const std::vector<NodeId>& observers, const std::vector<NodeId>& host) {
        config.master = placement_id(master);
        for (NodeId observer : observers) config.observers.push_back(placement_id(observer));
        for (NodeId node : host) config.host.push_back(placement_id(node));
    };
    if (id == kOnlineConfig) {
        fill(view.online->master, view.online->observers, view.online->host);
    } else if (static_cast<int>(id) < topology.config_count()) {
        const TopologyConfig& graph = topology.config(id);
        fill(graph.master, graph.observers, graph.host);
    }
    return config;
}

placement::FailedSet failed_of(const Topology& topology, const NodeSet& failed) {
    placement::FailedSet set(static_cast<std::size_t>(topology.node_count()), false);
    failed.for_each([&](NodeId node) {
        if (static_cast<int>(node) < topology.node_count()) set[node] = true;
    });
    return set;
}

std::shared_ptr<const OnlineConfig> online_of(const Topology& topology, PhaseId phase,
                                              const placement::Configuration& config) {
    auto online = std::make_shared<OnlineConfig>();
    online->phase = phase;
    online->master = node_of(config.master);
    for (int observer : config.observers) online->observers.push_back(node_of(observer));
    online->host.assign(static_cast<std::size_t>(topology.task_count()), kNoNode);
    for (std::size_t task = 0; task < config.host.size() && task < online->host.size(); ++task) {
        online->host[task] = node_of(config.host[task]);
    }
    return online;
}

Target failure_target(const Topology& topology, const View& from, const std::vector<NodeId>& fresh,
                      const NodeSet& failed, NodeId master) {
    if (from.is_safe()) return Target::safe();
    const PhaseId phase = topology.phase_of(from);
    const PlacementMode mode = topology.phase(phase).placement;
    if (from.config != kOnlineConfig && mode != PlacementMode::online) {
        const ConfigId reached = topology.walk(from.config, fresh, failed).config;
        if (reached != kSafeConfig && (master == kNoNode || topology.config(reached).master == master)) {
            return Target::graph(reached);
        }
        if (mode == PlacementMode::graph) return Target::safe();
    }
    return placed(topology, phase, failed, current_of(topology, from), master);
}

Target recovery_target(const Topology& topology, const View& view, NodeId node) {
    const PhaseId phase = topology.phase_of(view);
    const PlacementMode mode = topology.phase(phase).placement;
    if (mode == PlacementMode::graph) return Target::graph(topology.recovery_target(view, node));
    NodeSet failed = view.failed;
    failed.erase(node);
    if (mode == PlacementMode::graph_online) {
        const ConfigId graph = view.is_online() ? topology.recovery_target(phase, failed)
                                               : topology.recovery_target(view, node);
        // The graph's configuration, driven by this Master or handed to the node that
        // comes back (as in a graph phase); one of a third node's, alive all along (the
        // placer kept the Master where it was), is not taken: the placer answers.
        if (graph != kSafeConfig &&
            (topology.config(graph).master == view.master || topology.config(graph).master == node)) {
            return Target::graph(graph);
        }
    }
    return placed(topology, phase, failed, current_of(topology, view), view.master);
}

std::optional<Target> phase_target(const Topology& topology, const View& from, PhaseId phase, NodeId master) {
    if (from.is_safe() || static_cast<int>(phase) >= topology.phase_count()) return std::nullopt;
    const PlacementMode mode = topology.phase(phase).placement;
    const auto usable = [&](ConfigId id) {
        if (id == kNoConfig || id == kSafeConfig) return false;
        const TopologyConfig& config = topology.config(id);
        if (config.master != master) return false;
        if (std::any_of(config.host.begin(), config.host.end(),
                        [&](NodeId host) { return host != kNoNode && from.failed.contains(host); })) {
            return false;
        }
        // Where the placer can answer, the graph's configuration only if it is valid under
        // the failed set (a failed observer, a failed storage node): keel-place --prove
        // explores this rule.
        if (mode == PlacementMode::graph) return true;
        View as_graph;
        as_graph.config = as_graph.base = id;
        return placement::valid(topology.placement_model(), static_cast<int>(phase),
                                failed_of(topology, from.failed), placement_of(topology, as_graph));
    };
    if (from.config != kOnlineConfig) {
        // The graph's phase edge; the verifier rejects one into a configuration that uses a
        // failed node, and should one slip through it is not taken.
        const ConfigId edge = topology.phase_target(from.config, phase);
        if (usable(edge)) return Target::graph(edge);
    } else if (mode != PlacementMode::online) {
        const ConfigId graph = topology.recovery_target(phase, from.failed);
        if (usable(graph)) return Target::graph(graph);
    }
    if (mode == PlacementMode::graph) return std::nullopt;
    const Target target = placed(topology, phase, from.failed, current_of(topology, from), master);
    if (target.is_safe()) return std::nullopt;
    return target;
}

Problem online_problem(const Topology& topology, const View& view) {
    const bool config_online = view.config == kOnlineConfig;
    if (!config_online && !view.is_online()) {
        if (view.online) return std::string("it carries an online configuration and names none");
        return std::nullopt;
    }
    if (!view.online) return std::string("it names an online configuration and carries none");
    if (config_online ? !view.is_online() : !view.is_safe()) {
        return "configuration " + topology.config_name(view.config) + " with base " +
               topology.config_name(view.base) + " (outside safe mode they are one)";
    }
    const OnlineConfig& online = *view.online;
    const TopologyPhase& phase = topology.phase(online.phase);
    if (phase.placement == PlacementMode::graph) {
        return "phase " + phase.name + " is placed by its graph alone, and the view carries an online configuration";
    }
    if (!config_online) return std::nullopt;  // safe mode's base: where it was entered from
    if (online.master != view.master) {
        return "the online configuration's master is " + topology.node_name(online.master) + ", not " +
               topology.node_name(view.master);
    }
    const auto findings = placement::check(topology.placement_model(), online.phase,
                                           failed_of(topology, view.failed), placement_of(topology, view),
                                           placement::Shedding::allowed);
    if (findings.empty()) return std::nullopt;
    std::string why = "the online configuration is not valid under its failed set (" + findings[0].kind + ": " +
                      findings[0].message + ")";
    if (findings.size() > 1) why += " and " + std::to_string(findings.size() - 1) + " more";
    return why;
}

Problem fresh_exclusions(const View& from, const View& next, std::vector<NodeId>* fresh) {
    if (from.failed.includes(next.failed) || !next.failed.includes(from.failed)) {
        return std::string("the next switch of a view never readmits a node (a readmission opens an epoch)");
    }
    fresh->clear();
    next.failed.minus(from.failed).for_each([&](NodeId node) { fresh->push_back(node); });
    // The Master excludes one node per switch; a few at once are checked in every order,
    // more than kMaxOrderedFailures are no switch an honest Master makes.
    constexpr std::size_t kMaxOrderedFailures = 5;
    if (fresh->size() > kMaxOrderedFailures) {
        return std::to_string(fresh->size()) + " nodes excluded in one switch (the Master excludes them one at a time)";
    }
    return std::nullopt;
}

Problem online_edge_problem(const Topology& topology, const View& from, const View& next) {
    const std::string target = describe(topology, next);
    const std::string source = describe(topology, from);
    if (next.failed == from.failed) {
        if (same_configuration(from, next)) return std::nullopt;
        if (from.is_safe()) {
            if (!next.is_safe() && topology.phase_of(next) == topology.phase_of(from)) return std::nullopt;
            return "safe mode is left only for a configuration of the phase it was entered in, not " + target;
        }
        if (!next.is_safe()) {
            const PhaseId phase = topology.phase_of(next);
            if (phase != topology.phase_of(from)) {
                // An online configuration of a phase that admits one (online_problem passed);
                // a graph configuration: the phase edge, or the phase's recovery target.
                if (next.config == kOnlineConfig) return std::nullopt;
                if (from.config != kOnlineConfig && topology.phase_target(from.config, phase) == next.config) {
                    return std::nullopt;
                }
                if (from.config == kOnlineConfig && topology.recovery_target(phase, next.failed) == next.config) {
                    return std::nullopt;
                }
            }
        }
        return "no phase change leads from " + source + " to " + target;
    }
    std::vector<NodeId> fresh;
    if (auto problem = fresh_exclusions(from, next, &fresh)) return problem;
    if (from.is_safe()) {
        if (next.is_safe() && same_configuration(View{0, 0, kSafeConfig, from.base, 0, {}, from.online},
                                                  View{0, 0, kSafeConfig, next.base, 0, {}, next.online})) {
            return std::nullopt;
        }
        return "a failure in safe mode keeps safe mode, not " + target;
    }
    const PhaseId phase = topology.phase_of(from);
    if (!next.is_safe() && topology.phase_of(next) != phase) {
        return "a failure switch keeps the phase; " + target + " is of another";
    }
    std::sort(fresh.begin(), fresh.end());
    if (next.config == kOnlineConfig) {
        // Any configuration the checker accepts (online_problem passed). In a graph+online
        // phase, from a configuration of the graph, only where the graph has no answer.
        if (from.config == kOnlineConfig || topology.phase(phase).placement == PlacementMode::online) {
            return std::nullopt;
        }
        do {
            const ConfigId reached = topology.walk(from.config, fresh, next.failed).config;
            if (reached == kSafeConfig || topology.config(reached).master != next.master) return std::nullopt;
        } while (std::next_permutation(fresh.begin(), fresh.end()));
        return "the graph leads from " + source + " to a configuration for the nodes this switch excludes, not " +
               "to an online one";
    }
    if (next.is_safe()) {
        // Safe mode only where the placer (and the graph, where it answers first) finds no
        // placement: a Master that gives up while one exists harms the mission.
        if (!same_configuration(View{0, 0, kSafeConfig, next.base, 0, {}, next.online},
                                View{0, 0, kSafeConfig, from.config, 0, {}, from.online})) {
            return "safe mode entered from " + source + " names another base";
        }
        do {
            if (failure_target(topology, from, fresh, next.failed, next.master).is_safe()) return std::nullopt;
        } while (std::next_permutation(fresh.begin(), fresh.end()));
        return "the placer places every essential task without the nodes this switch excludes, and " + target +
               " gives up";
    }
    if (from.config == kOnlineConfig) {
        return "a phase placed online stays online until a readmission; " + target + " is of the graph";
    }
    return std::nullopt;  // graph to graph: edge_problem's walk decides
}

std::string online_json(const Topology& topology, const OnlineConfig& online) {
    std::string hosts = "{";
    for (std::size_t task = 0; task < online.host.size(); ++task) {
        if (online.host[task] == kNoNode) continue;
        if (hosts.size() > 1) hosts += ',';
        append_json_string(hosts, topology.task(static_cast<TaskId>(task)).name);
        hosts += ':' + json_node(topology, online.host[task]);
    }
    hosts += '}';
    std::string observers = "[";
    for (NodeId observer : online.observers) {
        if (observers.size() > 1) observers += ',';
        observers += json_node(topology, observer);
    }
    observers += ']';
    return JsonObject()
        .field("phase", topology.phase(online.phase).name)
        .raw("m", json_node(topology, online.master))
        .raw("obs", observers)
        .raw("host", hosts)
        .str();
}

}  // namespace keel::fsm
