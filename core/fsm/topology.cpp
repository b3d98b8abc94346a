#include "core/fsm/topology.hpp"

#include <algorithm>
#include <cassert>
#include <map>

#include "core/fsm/codec.hpp"
#include "core/placement/model.hpp"

namespace keel::fsm {

const char* to_string(Role role) {
    switch (role) {
        case Role::Master: return "Master";
        case Role::Observer: return "Observer";
        case Role::Worker: return "Worker";
    }
    return "Worker";
}

std::optional<Topology> Topology::build(const keel::mission::Mission& mission,
                                        std::string* error) {
    auto fail = [&](std::string message) -> std::optional<Topology> {
        if (error != nullptr) *error = std::move(message);
        return std::nullopt;
    };
    if (mission.nodes.empty() || mission.nodes.size() > static_cast<std::size_t>(kMaxNodes)) {
        return fail("a mission needs between 1 and " + std::to_string(kMaxNodes) +
                    " nodes, this one has " + std::to_string(mission.nodes.size()));
    }
    if (mission.tasks.size() > static_cast<std::size_t>(kMaxTasks)) {
        return fail("a mission has at most " + std::to_string(kMaxTasks) + " tasks, this one has " +
                    std::to_string(mission.tasks.size()));
    }
    if (mission.phases.empty()) return fail("the mission has no phase");
    if (mission.heartbeat.period_ms <= 0 || mission.heartbeat.miss_limit <= 0) {
        return fail("heartbeat period_ms and miss_limit must be positive");
    }

    Topology topology;
    topology.mission_name_ = mission.name;
    topology.heartbeat_period_ns_ = mission.heartbeat.period_ms * kNanosecondsPerMillisecond;
    topology.miss_limit_ = static_cast<int>(mission.heartbeat.miss_limit);
    if (mission.heartbeat.startup_grace_ms < 0) {
        return fail("heartbeat startup_grace_ms must not be negative");
    }
    topology.startup_grace_periods_ = static_cast<int>(mission.heartbeat.startup_grace_periods());
    if (mission.heartbeat.tie_grace < 0) return fail("heartbeat tie_grace must not be negative");
    topology.tie_grace_ = static_cast<int>(mission.heartbeat.tie_grace);
    topology.node_failures_ = static_cast<int>(mission.tolerance.node_failures);

    std::map<std::string, NodeId, std::less<>> node_ids;
    for (const auto& node : mission.nodes) {
        const auto id = static_cast<NodeId>(topology.nodes_.size());
        node_ids[node.name] = id;
        topology.nodes_.push_back({node.name, node.is_processing(), node.is_storage()});
        topology.all_nodes_.insert(id);
        if (node.is_processing()) topology.processing_nodes_.insert(id);
        if (node.is_storage() && topology.storage_node_ == kNoNode) topology.storage_node_ = id;
    }
    if (topology.processing_nodes_.empty()) return fail("the mission has no processing node");

    std::map<std::string, TaskId, std::less<>> task_ids;
    for (const auto& task : mission.tasks) {
        task_ids[task.name] = static_cast<TaskId>(topology.tasks_.size());
        std::optional<std::size_t> max_state;
        if (task.max_state_bytes) {
            max_state = kSnapshotHeaderBytes + static_cast<std::size_t>(*task.max_state_bytes);
        }
        topology.tasks_.push_back({task.name, task.checkpoint, task.essential, max_state});
    }

    auto lookup_node = [&](const std::string& name) -> std::optional<NodeId> {
        auto it = node_ids.find(name);
        if (it == node_ids.end()) return std::nullopt;
        return it->second;
    };

    // Configurations first (ids are needed by the edges), every phase in file order.
    std::map<std::string, ConfigId, std::less<>> config_ids;
    for (std::size_t p = 0; p < mission.phases.size(); ++p) {
        const auto& phase = mission.phases[p];
        TopologyPhase compiled;
        compiled.name = phase.name;
        compiled.placement = phase.placement;
        for (const auto& task_name : phase.tasks) {
            auto it = task_ids.find(task_name);
            if (it == task_ids.end()) return fail("phase " + phase.name + " names unknown task " + task_name);
            compiled.tasks.insert(it->second);
            if (topology.tasks_[it->second].essential) compiled.essential_tasks.insert(it->second);
        }
        for (const auto& configuration : phase.configurations) {
            TopologyConfig config;
            config.name = configuration.name;
            config.phase = static_cast<PhaseId>(p);
            config.tasks = compiled.tasks;
            auto master = lookup_node(configuration.master);
            if (!master) return fail("configuration " + configuration.name + " names unknown master");
            config.master = *master;
            config.matters.insert(*master);
            for (const auto& observer : configuration.observers) {
                auto id = lookup_node(observer);
                if (!id) return fail("configuration " + configuration.name + " names unknown observer");
                config.observers.push_back(*id);
                config.matters.insert(*id);
            }
            config.host.assign(topology.tasks_.size(), kNoNode);
            bool places_checkpointed = false;
            for (const auto& [task_name, node_name] : configuration.placement) {
                auto task = task_ids.find(task_name);
                auto node = lookup_node(node_name);
                if (task == task_ids.end() || !node) {
                    return fail("configuration " + configuration.name + " places an unknown task or node");
                }
                config.host[task->second] = *node;
                config.matters.insert(*node);
                places_checkpointed = places_checkpointed || topology.tasks_[task->second].checkpoint;
            }
            // The Storage node matters only to a configuration that places a checkpointed
            // task (keel-verify check's rule): elsewhere its failure keeps the configuration.
            if (topology.storage_node_ != kNoNode && places_checkpointed) {
                config.matters.insert(topology.storage_node_);
            }
            config.on_failure.assign(topology.nodes_.size(), kNoConfig);
            config.on_recovery.assign(topology.nodes_.size(), kNoConfig);
            config.on_phase.assign(mission.phases.size(), kNoConfig);
            config_ids[config.name] = static_cast<ConfigId>(topology.configs_.size());
            topology.configs_.push_back(std::move(config));
        }
        topology.phases_.push_back(std::move(compiled));
    }
    if (topology.configs_.size() >= kNoConfig) return fail("too many configurations");

    auto lookup_config = [&](const std::string& name) -> std::optional<ConfigId> {
        if (name == keel::mission::kSafe) return kSafeConfig;
        auto it = config_ids.find(name);
        if (it == config_ids.end()) return std::nullopt;
        return it->second;
    };
    std::map<std::string, PhaseId, std::less<>> phase_ids;
    for (std::size_t p = 0; p < mission.phases.size(); ++p) {
        phase_ids[mission.phases[p].name] = static_cast<PhaseId>(p);
    }

    for (std::size_t p = 0; p < mission.phases.size(); ++p) {
        const auto& phase = mission.phases[p];
        auto initial = lookup_config(phase.initial);
        if (!initial || *initial == kSafeConfig) return fail("phase " + phase.name + " has no valid initial configuration");
        topology.phases_[p].initial = *initial;
        for (const auto& edge : phase.on_failure) {
            auto from = lookup_config(edge.config);
            auto node = lookup_node(edge.node);
            auto next = lookup_config(edge.next);
            if (!from || *from == kSafeConfig || !node || !next) {
                return fail("phase " + phase.name + " has a failure edge with an unknown name");
            }
            topology.configs_[*from].on_failure[*node] = *next;
        }
        for (const auto& edge : phase.on_recovery) {
            auto from = lookup_config(edge.config);
            auto node = lookup_node(edge.node);
            auto next = lookup_config(edge.next);
            if (!from || *from == kSafeConfig || !node || !next || *next == kSafeConfig) {
                return fail("phase " + phase.name + " has a recovery edge with an unknown name");
            }
            topology.configs_[*from].on_recovery[*node] = *next;
        }
        for (const auto& edge : phase.on_phase) {
            auto from = lookup_config(edge.from);
            auto to = lookup_config(edge.to);
            auto target = phase_ids.find(edge.phase);
            if (!from || !to || *from == kSafeConfig || *to == kSafeConfig ||
                target == phase_ids.end()) {
                return fail("phase " + phase.name + " has a phase edge with an unknown name");
            }
            topology.configs_[*from].on_phase[target->second] = *to;
        }
    }

    // Succession: the first phase's initial master and observers, then the other
    // processing nodes in file order.
    const auto& first = topology.configs_[topology.phases_[0].initial];
    auto add_priority = [&](NodeId id) {
        if (!topology.nodes_[id].processing) return;
        if (std::find(topology.priority_.begin(), topology.priority_.end(), id) !=
            topology.priority_.end()) {
            return;
        }
        topology.priority_.push_back(id);
    };
    add_priority(first.master);
    for (NodeId observer : first.observers) add_priority(observer);
    for (NodeId id = 0; id < topology.nodes_.size(); ++id) add_priority(id);
    if (topology.priority_.empty() || topology.priority_[0] != first.master) {
        return fail("the initial master must be a processing node");
    }

    topology.may_host_.assign(topology.tasks_.size(), NodeSet{});
    for (const TopologyConfig& config : topology.configs_) {
        for (TaskId task = 0; task < config.host.size(); ++task) {
            if (config.host[task] != kNoNode) topology.may_host_[task].insert(config.host[task]);
        }
    }
    for (const TopologyPhase& phase : topology.phases_) {
        phase.essential_tasks.for_each([&](TaskId task) {
            for (NodeId master : topology.priority_) topology.may_host_[task].insert(master);
        });
    }
    // A phase placed online may put its tasks on any node able to run them (the checker's
    // capability rule), and its observers on any processing node.
    const bool online = std::any_of(topology.phases_.begin(), topology.phases_.end(), [](const TopologyPhase& phase) {
        return phase.placement != keel::mission::PlacementMode::graph;
    });
    if (online) {
        std::string why;
        auto model = placement::Model::build(mission, &why);
        if (!model) return fail("the placer's model: " + why);
        for (const TopologyPhase& phase : topology.phases_) {
            if (phase.placement == keel::mission::PlacementMode::graph) continue;
            phase.tasks.for_each([&](TaskId task) {
                for (NodeId node = 0; node < topology.nodes_.size(); ++node) {
                    if (model->node(node).capabilities.contains_all(model->task(task).requires_capabilities)) {
                        topology.may_host_[task].insert(node);
                    }
                }
            });
        }
        topology.placement_model_ = std::make_shared<const placement::Model>(std::move(*model));
    }
    return topology;
}

std::optional<NodeId> Topology::node_id(std::string_view name) const {
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
        if (nodes_[i].name == name) return static_cast<NodeId>(i);
    }
    return std::nullopt;
}

std::optional<TaskId> Topology::task_id(std::string_view name) const {
    for (std::size_t i = 0; i < tasks_.size(); ++i) {
        if (tasks_[i].name == name) return static_cast<TaskId>(i);
    }
    return std::nullopt;
}

std::optional<ConfigId> Topology::config_id(std::string_view name) const {
    if (name == keel::mission::kSafe) return kSafeConfig;
    for (std::size_t i = 0; i < configs_.size(); ++i) {
        if (configs_[i].name == name) return static_cast<ConfigId>(i);
    }
    return std::nullopt;
}

std::optional<PhaseId> Topology::phase_id(std::string_view name) const {
    for (std::size_t i = 0; i < phases_.size(); ++i) {
        if (phases_[i].name == name) return static_cast<PhaseId>(i);
    }
    return std::nullopt;
}

std::string Topology::config_name(ConfigId id) const {
    if (id == kSafeConfig) return keel::mission::kSafe;
    if (id == kOnlineConfig) return "online";
    if (id < configs_.size()) return configs_[id].name;
    return "none";
}

NodeId Topology::owner(Epoch epoch) const {
    assert(epoch >= 1);
    return priority_[(epoch - 1) % priority_.size()];
}

Epoch Topology::next_epoch(NodeId node, Epoch above) const {
    // At most one lap of the ring: every processing node owns one epoch per lap.
    for (Epoch candidate = above + 1; candidate <= above + priority_.size(); ++candidate) {
        if (owner(candidate) == node) return candidate;
    }
    assert(false && "next_epoch: node is not in the succession");
    return 0;
}

View Topology::initial_view() const {
    View view;
    view.epoch = 1;
    view.seq = 0;
    view.config = phases_[0].initial;
    view.base = view.config;
    view.master = configs_[view.config].master;
    return view;
}

ConfigId Topology::recovery_target(PhaseId phase, NodeSet failed) const {
    assert(phase < phases_.size());
    std::vector<NodeId> order;
    failed.for_each([&](NodeId node) { order.push_back(node); });
    return walk(phases_[phase].initial, order, failed).config;
}

ConfigId Topology::recovery_target(const View& view, NodeId node) const {
    NodeSet failed = view.failed;
    failed.erase(node);
    if (!view.is_safe() && !view.is_online()) {
        assert(view.config < configs_.size() && node < configs_[view.config].on_recovery.size());
        const ConfigId edge = configs_[view.config].on_recovery[node];
        if (edge != kNoConfig) return edge;
    }
    return recovery_target(phase_of(view), failed);
}

PhaseId Topology::phase_of(const View& view) const {
    if (view.is_online()) {
        assert(view.online);
        return view.online->phase;
    }
    assert(view.base < configs_.size());
    return configs_[view.base].phase;
}

Topology::Placed Topology::placed(const View& view) const {
    const ConfigId id = view.is_safe() ? view.base : view.config;
    if (id == kOnlineConfig) {
        assert(view.online);
        return Placed{view.online->master, &view.online->observers, &view.online->host};
    }
    assert(id < configs_.size());
    const TopologyConfig& config = configs_[id];
    return Placed{config.master, &config.observers, &config.host};
}

NodeId Topology::host(const View& view, TaskId task) const {
    if (view.is_safe()) {
        const auto& phase = phases_[phase_of(view)];
        return phase.essential_tasks.contains(task) ? view.master : kNoNode;
    }
    const std::vector<NodeId>& hosts = *placed(view).host;
    return task < hosts.size() ? hosts[task] : kNoNode;
}

TaskSet Topology::tasks_on(const View& view, NodeId node) const {
    TaskSet tasks;
    if (view.failed.contains(node)) return tasks;
    if (view.is_safe()) {
        if (node == view.master) tasks = phases_[phase_of(view)].essential_tasks;
        return tasks;
    }
    const std::vector<NodeId>& hosts = *placed(view).host;
    for (std::size_t t = 0; t < hosts.size(); ++t) {
        if (hosts[t] == node) tasks.insert(static_cast<TaskId>(t));
    }
    return tasks;
}

std::vector<NodeId> Topology::observers(const View& view) const {
    std::vector<NodeId> result;
    auto add = [&](NodeId id) {
        if (id == view.master || view.failed.contains(id)) return;
        if (std::find(result.begin(), result.end(), id) != result.end()) return;
        result.push_back(id);
    };
    const Placed config = placed(view);
    if (view.is_safe()) add(config.master);
    for (NodeId id : *config.observers) add(id);
    return result;
}

NodeSet Topology::monitors(const View& view) const {
    // The master and observers(view), without building the list: a set holds each once.
    NodeSet set;
    auto add = [&](NodeId id) {
        if (id != kNoNode && id < kMaxNodes && !view.failed.contains(id)) set.insert(id);
    };
    add(view.master);
    const Placed config = placed(view);
    if (view.is_safe()) add(config.master);
    for (NodeId id : *config.observers) add(id);
    return set;
}

Role Topology::role_in(const View& view, NodeId node) const {
    if (node == view.master) return Role::Master;
    const auto list = observers(view);
    return std::find(list.begin(), list.end(), node) != list.end() ? Role::Observer
                                                                   : Role::Worker;
}

WalkResult Topology::walk(ConfigId from, const std::vector<NodeId>& failures,
                          NodeSet all_failed) const {
    WalkResult result;
    result.config = from;
    if (from == kSafeConfig) return result;
    // Each pass applies the first pending failure the configuration reached so far has an
    // edge for, or that matters to it (no edge then: SAFE); a failure of a node that
    // matters to nothing and has no edge keeps the configuration. An explicit edge is
    // followed also for a node that matters to nothing, as the verifier follows it
    // (verify/README.md, "Which edge"). A configuration reached later may make an
    // earlier-skipped failure apply, so the walk repeats until nothing applies.
    std::vector<NodeId> pending = failures;
    for (std::size_t guard = 0; guard <= failures.size(); ++guard) {
        const auto& config = configs_[result.config];
        auto it = std::find_if(pending.begin(), pending.end(), [&](NodeId id) {
            return config.matters.contains(id) || config.on_failure[id] != kNoConfig;
        });
        if (it == pending.end()) break;
        const NodeId failed = *it;
        pending.erase(it);
        result.path_nodes.push_back(failed);
        const ConfigId next = config.on_failure[failed];
        if (next == kNoConfig || next == kSafeConfig) {
            result.config = kSafeConfig;
            return result;
        }
        result.config = next;
    }
    // A configuration whose master or a task host has failed is not a valid place to
    // stop (the verifier rejects such graphs); safe mode is the only honest answer.
    const auto& reached = configs_[result.config];
    if (all_failed.contains(reached.master)) {
        result.config = kSafeConfig;
        return result;
    }
    for (NodeId host_node : reached.host) {
        if (host_node != kNoNode && all_failed.contains(host_node)) {
            result.config = kSafeConfig;
            return result;
        }
    }
    return result;
}

ConfigId Topology::phase_target(ConfigId from, PhaseId target) const {
    if (from == kSafeConfig || from >= configs_.size()) return kNoConfig;
    return configs_[from].on_phase.at(target);
}

}  // namespace keel::fsm
