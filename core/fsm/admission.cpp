#include "core/fsm/admission.hpp"

#include <algorithm>
#include <vector>

#include "core/fsm/online.hpp"
#include "core/fsm/overloaded.hpp"

namespace keel::fsm {

namespace {

using Problem = std::optional<std::string>;

Problem node_problem(NodeId node, const Topology& topology, const char* field) {
    if (static_cast<int>(node) < topology.node_count()) return std::nullopt;
    return std::string(field) + " " + std::to_string(node) + " is not a node of the mission (" +
           std::to_string(topology.node_count()) + " nodes)";
}

Problem task_problem(TaskId task, const Topology& topology) {
    if (static_cast<int>(task) < topology.task_count()) return std::nullopt;
    return "task " + std::to_string(task) + " is not a task of the mission (" +
           std::to_string(topology.task_count()) + " tasks)";
}

// The ids of an online configuration (the phase, its master and observers, one host per
// task of the mission).
Problem online_ids_problem(const OnlineConfig& online, const Topology& topology, const std::string& prefix) {
    if (static_cast<int>(online.phase) >= topology.phase_count()) {
        return prefix + ".phase " + std::to_string(online.phase) + " is not a phase of the mission (" +
               std::to_string(topology.phase_count()) + " phases)";
    }
    if (auto problem = node_problem(online.master, topology, (prefix + ".master").c_str())) return problem;
    if (online.observers.size() > static_cast<std::size_t>(topology.node_count())) {
        return prefix + ".observers lists " + std::to_string(online.observers.size()) + " nodes, the mission has " +
               std::to_string(topology.node_count());
    }
    for (NodeId observer : online.observers) {
        if (auto problem = node_problem(observer, topology, (prefix + ".observers").c_str())) return problem;
    }
    if (online.host.size() != static_cast<std::size_t>(topology.task_count())) {
        return prefix + ".host places " + std::to_string(online.host.size()) + " tasks, the mission has " +
               std::to_string(topology.task_count());
    }
    for (NodeId host : online.host) {
        if (host == kNoNode) continue;
        if (auto problem = node_problem(host, topology, (prefix + ".host").c_str())) return problem;
    }
    return std::nullopt;
}

Problem view_ids_problem(const View& view, const Topology& topology, const char* name) {
    const std::string prefix(name);
    const auto graph_id = [&](ConfigId id) {
        return static_cast<int>(id) < topology.config_count() || (id == kOnlineConfig && topology.has_online());
    };
    if (view.config != kSafeConfig && !graph_id(view.config)) {
        return prefix + ".config " + std::to_string(view.config) + " is not a configuration of the mission (" +
               std::to_string(topology.config_count()) + " configurations)";
    }
    if (!graph_id(view.base)) {
        return prefix + ".base " + std::to_string(view.base) + " is not a configuration of the mission (" +
               std::to_string(topology.config_count()) + " configurations)";
    }
    if (auto problem = node_problem(view.master, topology, (prefix + ".master").c_str())) return problem;
    if (!topology.all_nodes().includes(view.failed)) {
        return prefix + ".failed names a node beyond the mission's " + std::to_string(topology.node_count());
    }
    if (view.is_online() != static_cast<bool>(view.online)) {
        return prefix + (view.online ? " carries an online configuration and its base is not one"
                                     : " names an online configuration and carries none");
    }
    if (view.online) return online_ids_problem(*view.online, topology, prefix + ".online");
    return std::nullopt;
}

}  // namespace

std::optional<std::string> out_of_mission(const Message& message, const Topology& topology) {
    if (auto problem = node_problem(sender_of(message), topology, "from")) return problem;
    return std::visit(
        Overloaded{
            [&](const Heartbeat& heartbeat) -> Problem {
                for (const HeartbeatAck& ack : heartbeat.acks) {
                    if (auto problem = node_problem(ack.node, topology, "acks.node")) return problem;
                }
                return std::nullopt;
            },
            [&](const Command& command) -> Problem {
                if (auto problem = view_ids_problem(command.view, topology, "view")) return problem;
                for (const View& joint : command.joint) {
                    if (auto problem = view_ids_problem(joint, topology, "joint")) return problem;
                }
                return std::nullopt;
            },
            [&](const ActivateCommand&) -> Problem { return std::nullopt; },
            [&](const Ack&) -> Problem { return std::nullopt; },
            [&](const ErrorNotification& notification) -> Problem {
                return node_problem(notification.failed_node, topology, "failed_node");
            },
            [&](const CheckpointWrite& write) -> Problem { return task_problem(write.task, topology); },
            [&](const CheckpointAck& ack) -> Problem { return task_problem(ack.task, topology); },
            [&](const CheckpointRequest& request) -> Problem { return task_problem(request.task, topology); },
            [&](const CheckpointReply& reply) -> Problem { return task_problem(reply.task, topology); },
            [&](const PhaseRequest& request) -> Problem {
                if (static_cast<int>(request.phase) < topology.phase_count()) return std::nullopt;
                return "phase " + std::to_string(request.phase) + " is not a phase of the mission (" +
                       std::to_string(topology.phase_count()) + " phases)";
            },
        },
        message);
}

std::optional<std::string> view_problem(const View& view, const Topology& topology) {
    if (view.epoch == 0 || topology.owner(view.epoch) != view.master) {
        return "epoch " + std::to_string(view.epoch) + " is not " + topology.node_name(view.master) +
               "'s to open (its owner in the succession is " +
               (view.epoch == 0 ? std::string("no node") : topology.node_name(topology.owner(view.epoch))) + ")";
    }
    if (view.failed.contains(view.master)) {
        return "the view excludes its own master " + topology.node_name(view.master);
    }
    if (view.is_safe()) {
        if (!topology.processing_nodes().contains(view.master)) {
            return "safe mode's master " + topology.node_name(view.master) + " is not a processing node";
        }
        return online_problem(topology, view);
    }
    if (view.config == kOnlineConfig || view.is_online()) return online_problem(topology, view);
    if (view.base != view.config) {
        return "configuration " + topology.config_name(view.config) + " with base " +
               topology.config_name(view.base) + " (outside safe mode they are one)";
    }
    const TopologyConfig& config = topology.config(view.config);
    if (config.master != view.master) {
        return "configuration " + config.name + "'s master is " + topology.node_name(config.master) + ", not " +
               topology.node_name(view.master);
    }
    for (std::size_t task = 0; task < config.host.size(); ++task) {
        const NodeId host = config.host[task];
        if (host != kNoNode && view.failed.contains(host)) {
            return "configuration " + config.name + " places " + topology.task(static_cast<TaskId>(task)).name +
                   " on " + topology.node_name(host) + ", which the view excludes";
        }
    }
    return std::nullopt;
}

std::optional<std::string> edge_problem(const View& from, const View& next, const Topology& topology) {
    // Where either end is online, or a phase it touches places online, online.hpp's rules
    // (a switch to SAFE only where the placer finds nothing either); between two graph
    // configurations the graph's edges below too.
    const auto placed_by_graph = [&](const View& view) {
        return topology.phase(topology.phase_of(view)).placement == mission::PlacementMode::graph;
    };
    if (from.is_online() || next.is_online() || !placed_by_graph(from) || !placed_by_graph(next)) {
        if (auto problem = online_edge_problem(topology, from, next)) return problem;
        if (from.is_online() || next.is_online()) return std::nullopt;
    }
    const std::string target = topology.config_name(next.config);
    const std::string source = topology.config_name(from.config);
    if (next.failed == from.failed) {
        if (next.config == from.config && next.base == from.base) return std::nullopt;
        if (from.is_safe()) {
            // Leaving safe mode (the ground's recovery command) for a configuration of the
            // phase safe mode was entered in.
            if (!next.is_safe() && topology.config(next.config).phase == topology.config(from.base).phase) {
                return std::nullopt;
            }
            return "safe mode entered in phase " + topology.phase(topology.config(from.base).phase).name +
                   " is left only for a configuration of that phase, not " + target;
        }
        if (!next.is_safe()) {
            const PhaseId phase = topology.config(next.config).phase;
            if (phase != topology.config(from.config).phase && topology.phase_target(from.config, phase) == next.config) {
                return std::nullopt;
            }
        }
        return "the graph has no phase edge from " + source + " to " + target;
    }
    std::vector<NodeId> fresh;
    if (auto problem = fresh_exclusions(from, next, &fresh)) return problem;
    if (from.is_safe()) {
        if (next.is_safe() && next.base == from.base) return std::nullopt;
        return "a failure in safe mode keeps safe mode, not " + target;
    }
    do {
        ConfigId reached = topology.walk(from.config, fresh, next.failed).config;
        if (reached != kSafeConfig && topology.config(reached).master != next.master) reached = kSafeConfig;
        if (reached == next.config && (!next.is_safe() || next.base == from.config)) return std::nullopt;
    } while (std::next_permutation(fresh.begin(), fresh.end()));
    return "the graph leads from " + source + " to no " + target + " for the nodes this switch excludes";
}

std::uint64_t view_digest(const View& view) {
    std::uint64_t hash = 0xcbf29ce484222325ull;
    const auto mix = [&](std::uint64_t value, int bytes) {
        for (int i = 0; i < bytes; ++i) {
            hash ^= (value >> (8 * i)) & 0xFFu;
            hash *= 0x100000001b3ull;
        }
    };
    mix(view.epoch, 4);
    mix(view.seq, 4);
    mix(view.config, 2);
    mix(view.base, 2);
    mix(view.master, 2);
    const int words = view.failed.used_words();
    mix(static_cast<std::uint64_t>(words), 1);
    for (int i = 0; i < words; ++i) mix(view.failed.word(i), 8);
    if (view.online) {
        const OnlineConfig& online = *view.online;
        mix(online.phase, 1);
        mix(online.master, 2);
        mix(online.observers.size(), 2);
        for (NodeId observer : online.observers) mix(observer, 2);
        mix(online.host.size(), 2);
        for (NodeId host : online.host) mix(host, 2);
    }
    return hash;
}

}  // namespace keel::fsm
