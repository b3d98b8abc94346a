// Topology: the mission file compiled into the ids and tables the state machines use.
//
// A Topology is built once from a loaded keel::mission::Mission and is immutable after;
// every node of a cluster builds the same one from the same file, so ids agree without
// negotiation. It answers the questions the protocols ask on every event — who hosts a
// task in a view, who monitors, which configuration the decision graph picks — in
// constant time, without string lookups.
//
// Succession (MasterElection's `Priority`): the processing nodes, starting with the
// initial configuration of the first phase — its master, then its observers in order —
// then the other processing nodes in file order. Epoch e belongs to
// Owner(e) = Priority[(e - 1) % |Priority|], so epoch 1 is the initial master's and no two
// nodes can ever claim the same epoch.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/fsm/types.hpp"
#include "core/mission/mission.hpp"

namespace keel::placement {
class Model;
}

namespace keel::fsm {

struct TopologyNode {
    std::string name;
    bool processing = false;
    bool storage = false;
};

struct TopologyTask {
    std::string name;
    bool checkpoint = false;
    bool essential = false;
    // The largest checkpoint state (CheckpointWrite::state: the snapshot header and the
    // mission's max_state_bytes) when the mission states it.
    std::optional<std::size_t> max_state_bytes;
};

struct TopologyConfig {
    std::string name;
    PhaseId phase = 0;
    NodeId master = kNoNode;
    std::vector<NodeId> observers;  // priority order
    std::vector<NodeId> host;       // per task: the hosting node, kNoNode when not placed
    TaskSet tasks;                  // the phase's tasks
    NodeSet matters;                // nodes whose failure needs an edge (docs/missions.md)
    // Per node: the configuration its failure leads to, kSafeConfig, or kNoConfig (no edge).
    std::vector<ConfigId> on_failure;
    // Per node: the configuration its readmission leads to (the mission's on_recovery
    // edge), or kNoConfig (no edge: the configuration of the smaller failed set).
    std::vector<ConfigId> on_recovery;
    // Per target phase: the configuration of that phase this one maps to, or kNoConfig.
    std::vector<ConfigId> on_phase;
};

struct TopologyPhase {
    std::string name;
    ConfigId initial = kNoConfig;
    TaskSet tasks;
    TaskSet essential_tasks;
    // Where its configurations come from (docs/missions.md, "Placement modes"): the graph
    // alone, the placer alone beyond the initial configuration, or the placer beyond the
    // graph (core/fsm/online.hpp).
    keel::mission::PlacementMode placement = keel::mission::PlacementMode::graph;
};

// Where a walk of the decision graph ended.
struct WalkResult {
    ConfigId config = kNoConfig;  // a configuration or kSafeConfig
    // The failed nodes the walk followed an edge for, in order (for traces and messages).
    std::vector<NodeId> path_nodes;
};

class Topology {
public:
    // Compiles a loaded mission; returns an error sentence for missions beyond the limits
    // in types.hpp (more nodes or tasks than its capacity, no processing node).
    static std::optional<Topology> build(const keel::mission::Mission& mission,
                                         std::string* error);

    std::string_view mission_name() const { return mission_name_; }
    TimeNs heartbeat_period_ns() const { return heartbeat_period_ns_; }
    int miss_limit() const { return miss_limit_; }
    // Periods a monitor gives a node it has never heard since it booted before declaring
    // it failed: max(miss_limit, ceil(heartbeat.startup_grace_ms / period_ms)), so that a
    // node whose process starts late joins instead of being excluded at once.
    int startup_grace_periods() const { return startup_grace_periods_; }
    // Periods a node runs in a tie on the ground's standing acknowledgement
    // (heartbeat.tie_grace; spec/Designate.tla, TieGrace). 0: the ground is no voter.
    int tie_grace() const { return tie_grace_; }
    int node_failures_tolerated() const { return node_failures_; }

    int node_count() const { return static_cast<int>(nodes_.size()); }
    int task_count() const { return static_cast<int>(tasks_.size()); }
    int config_count() const { return static_cast<int>(configs_.size()); }
    int phase_count() const { return static_cast<int>(phases_.size()); }
    const TopologyNode& node(NodeId id) const { return nodes_.at(id); }
    const TopologyTask& task(TaskId id) const { return tasks_.at(id); }
    const TopologyConfig& config(ConfigId id) const { return configs_.at(id); }
    const TopologyPhase& phase(PhaseId id) const { return phases_.at(id); }
    const NodeSet& all_nodes() const { return all_nodes_; }
    const NodeSet& processing_nodes() const { return processing_nodes_; }
    // The nodes the mission may ever place `task` on: its host in any configuration, and,
    // for a task essential in some phase, every node that may become Master (safe mode runs
    // the essential tasks on the Master). No other node ever runs it, or writes its
    // checkpoint.
    const NodeSet& may_host(TaskId task) const { return may_host_.at(task); }
    // The mission as the placer and the checker read it (core/placement/model.hpp), for a
    // mission with a phase that is not placed by its graph alone (has_online()).
    bool has_online() const { return placement_model_ != nullptr; }
    const placement::Model& placement_model() const { return *placement_model_; }
    // The storage node checkpoints go to (the first one in file order), or kNoNode.
    NodeId storage_node() const { return storage_node_; }

    std::optional<NodeId> node_id(std::string_view name) const;
    std::optional<TaskId> task_id(std::string_view name) const;
    std::optional<ConfigId> config_id(std::string_view name) const;  // "SAFE" -> kSafeConfig
    std::optional<PhaseId> phase_id(std::string_view name) const;
    std::string config_name(ConfigId id) const;  // "SAFE" for kSafeConfig
    const std::string& node_name(NodeId id) const { return nodes_.at(id).name; }

    // MasterElection's succession and epoch ownership.
    const std::vector<NodeId>& priority() const { return priority_; }
    NodeId owner(Epoch epoch) const;
    // The smallest epoch above `above` that `node` owns (NextEpoch in the spec).
    Epoch next_epoch(NodeId node, Epoch above) const;

    // The view every node boots into: the first phase's initial configuration, epoch 1.
    View initial_view() const;

    // Questions about a view. In safe mode only the phase's essential tasks run, all on
    // the view's master; the observers are the base configuration's monitors that are
    // still alive. An online configuration (View::online) answers for itself.
    PhaseId phase_of(const View& view) const;
    NodeId host(const View& view, TaskId task) const;
    TaskSet tasks_on(const View& view, NodeId node) const;
    std::vector<NodeId> observers(const View& view) const;
    NodeSet monitors(const View& view) const;  // master + observers
    Role role_in(const View& view, NodeId node) const;

    // Walks the decision graph from `from` applying `failures` (in the given order), one
    // edge per failure the configuration reached so far has an edge for or that matters to
    // it; a failure of a node that matters to nothing and has no edge keeps the
    // configuration (the verifier's reading: verify/README.md, "Which edge"). A missing
    // edge, or an edge to SAFE, ends the walk in SAFE. Also ends in SAFE when the resulting
    // master or a task host is itself failed.
    WalkResult walk(ConfigId from, const std::vector<NodeId>& failures, NodeSet all_failed) const;
    // The configuration of `target` that `from` maps to, or kNoConfig.
    ConfigId phase_target(ConfigId from, PhaseId target) const;
    // Reintegration (fault model 2, rule 4): the configuration of `phase` the cluster
    // returns to when only `failed` have failed, i.e. the walk from the phase's initial
    // configuration through `failed` in id order. keel-verify check explores every order
    // of every failure set from every phase's initial configuration, so this is a state
    // it has proved (within the tolerance, a valid configuration). kSafeConfig when the
    // walk ends in safe mode (beyond the tolerance).
    ConfigId recovery_target(PhaseId phase, NodeSet failed) const;
    // The configuration the cluster moves to when `node` is readmitted while `view` is
    // driven: the mission's on_recovery edge from view.config when it has one (keel-verify
    // check proves that it leads to a state the failure exploration reaches, with
    // view.failed less `node`), else recovery_target(phase, view.failed less `node`).
    ConfigId recovery_target(const View& view, NodeId node) const;

private:
    // The configuration a view runs (its base in safe mode): a graph one or its online one.
    struct Placed {
        NodeId master;
        const std::vector<NodeId>* observers;
        const std::vector<NodeId>* host;
    };
    Placed placed(const View& view) const;

    std::string mission_name_;
    TimeNs heartbeat_period_ns_ = 0;
    int miss_limit_ = 0;
    int startup_grace_periods_ = 0;
    int tie_grace_ = 0;
    int node_failures_ = 0;
    std::vector<TopologyNode> nodes_;
    std::vector<TopologyTask> tasks_;
    std::vector<TopologyConfig> configs_;
    std::vector<TopologyPhase> phases_;
    std::vector<NodeId> priority_;
    NodeSet all_nodes_;
    NodeSet processing_nodes_;
    std::vector<NodeSet> may_host_;  // per task
    std::shared_ptr<const placement::Model> placement_model_;
    NodeId storage_node_ = kNoNode;
};

}  // namespace keel::fsm
