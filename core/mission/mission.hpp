// The mission model: nodes, tasks, phases and the decision graph of a mission.
//
// A node reads a mission only from its proven image (core/mission/image.hpp: the output of
// `keel-verify compile`); the YAML a team writes is read by the verifier alone
// (verify/keel_verify/mission.py, the contract in config/schema/README.md). A Mission is
// immutable once loaded; every name it holds refers to something defined (the verifier
// proved it and the image loader checks it again), so code that walks the decision graph
// may look names up without checking again.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace keel::mission {

// The decision graph's safe-mode target; reserved, never a node or configuration name.
inline constexpr const char* kSafe = "SAFE";

// A parameter value: string, number or boolean, as written in the mission file. Integers
// in the file are kept as std::int64_t; other numbers as double.
using ParamValue = std::variant<std::string, std::int64_t, double, bool>;
// Parameters in file order.
using Params = std::vector<std::pair<std::string, ParamValue>>;

struct Resources {
    // std::nullopt means unbounded (capacity only; a task's load defaults to 0).
    std::optional<std::int64_t> cpu;
    std::optional<std::int64_t> mem_mb;
};

enum class NodeKind { processing, interface };
enum class NodeRole { none, storage, interface };

struct Node {
    std::string name;
    NodeKind kind = NodeKind::processing;
    NodeRole role = NodeRole::none;  // none for processing nodes; interface by default
    std::vector<std::string> capabilities;
    Resources capacity;
    // Where it is defined, for messages: 0 in a mission read from an image (an image has
    // no source positions); set by code that builds a Mission itself.
    int line = 0;

    bool is_processing() const { return kind == NodeKind::processing; }
    bool is_storage() const { return role == NodeRole::storage; }
    bool has_capability(const std::string& capability) const;
};

struct Health {
    std::optional<double> min;
    std::optional<double> max;
    std::optional<std::int64_t> deadline_ms;
};

struct Task {
    std::string name;
    std::int64_t port = 0;
    std::string component;  // registered component; defaults to the task's name
    std::vector<std::string> requires_capabilities;  // `requires` in the file
    Resources load;  // never nullopt after loading: missing values are 0
    bool essential = false;
    bool checkpoint = false;
    std::vector<std::string> inputs;
    std::optional<std::int64_t> period_ms;
    std::optional<Health> health;
    Params params;
    // The largest sample the task outputs (its payload, bytes); nullopt: not stated.
    std::optional<std::int64_t> max_sample_bytes;
    // The largest checkpoint state its component writes (the snapshot's payload, bytes), for
    // a checkpointed task; nullopt: not stated.
    std::optional<std::int64_t> max_state_bytes;
    // For the online placer (core/placement): it sheds non-essential tasks lowest priority
    // first; tasks of one group (redundant copies) go on different nodes where they can.
    // Absent from the image when the mission does not state them (0 and no group).
    std::optional<std::int64_t> priority;
    std::optional<std::string> group;
    int line = 0;
};

struct Configuration {
    std::string name;
    std::string phase;
    std::string master;
    std::vector<std::string> observers;  // priority order: the first alive one is elected
    std::vector<std::pair<std::string, std::string>> placement;  // task -> node, file order
    int line = 0;

    // The node hosting `task`, or nullptr when the configuration does not place it.
    const std::string* node_of(const std::string& task) const;
};

struct FailureEdge {
    std::string config;  // configuration in which the failure is detected
    std::string node;    // the failed node
    std::string next;    // next configuration of the same phase, or kSafe
    int line = 0;
};

struct PhaseEdge {
    std::string phase;  // target phase
    std::string from;   // configuration of this phase
    std::string to;     // configuration of the target phase
    int line = 0;
};

// How a phase chooses the configuration after a failure (docs/missions.md, "Placement
// modes"): its decision graph alone, the online placer (core/placement) alone, or the graph
// first and the placer where the graph says SAFE or has no edge.
enum class PlacementMode { graph, online, graph_online };

// The image's spelling of a mode: "graph", "online", "graph+online". Inline: keel_fsm uses
// the mission's types without linking keel_mission.
inline const char* placement_name(PlacementMode mode) {
    switch (mode) {
        case PlacementMode::graph: return "graph";
        case PlacementMode::online: return "online";
        case PlacementMode::graph_online: return "graph+online";
    }
    return "graph";
}

struct Phase {
    std::string name;
    PlacementMode placement = PlacementMode::graph;
    std::vector<std::string> tasks;  // the phase's tasks; default: every task
    std::string initial;
    std::vector<Configuration> configurations;  // file order
    std::vector<FailureEdge> on_failure;        // file order
    // Recovery edges: `node` readmitted in `config` leads to `next` (never kSafe); without
    // one the cluster returns to the configuration of the smaller failed set.
    std::vector<FailureEdge> on_recovery;       // file order
    std::vector<PhaseEdge> on_phase;            // file order
    std::vector<std::pair<std::string, Params>> params;  // task -> parameters for this phase
    int line = 0;

    const Configuration* configuration(const std::string& name) const;
    // The edge taken when `node` fails in configuration `config`, or nullptr.
    const FailureEdge* failure_edge(const std::string& config, const std::string& node) const;
    // The edge taken when `node` is readmitted in configuration `config`, or nullptr.
    const FailureEdge* recovery_edge(const std::string& config, const std::string& node) const;
    // The configuration of `target_phase` that `config` maps to, or nullptr.
    const PhaseEdge* phase_edge(const std::string& target_phase, const std::string& config) const;
};

// heartbeat.startup_grace_ms when the mission does not set it (mission.schema.json).
inline constexpr std::int64_t kDefaultStartupGraceMs = 2000;

struct Heartbeat {
    std::int64_t period_ms = 0;
    std::int64_t miss_limit = 0;
    // How long a monitor waits for a node it has never heard before declaring it failed.
    std::int64_t startup_grace_ms = kDefaultStartupGraceMs;
    // Periods a node runs in a tie on the ground's standing acknowledgement
    // (spec/Designate.tla, TieGrace). 0, the default: the ground is no voter and the quorum
    // rule is spec/Quorum.tla's alone. An image states it only when it is not 0.
    std::int64_t tie_grace = 0;

    // Periods a never-heard node is given: max(miss_limit, ceil(grace / period)).
    std::int64_t startup_grace_periods() const {
        const std::int64_t periods = (startup_grace_ms + period_ms - 1) / period_ms;
        return periods > miss_limit ? periods : miss_limit;
    }
};

struct Tolerance {
    std::int64_t node_failures = 0;
    std::vector<std::string> nodes;  // default: every node, file order
};

struct Mission {
    std::string name;
    std::string path;  // the file it was loaded from
    // The mission's revision (it only grows from one image to the next); none when the
    // mission states none (read as 0). A node refuses an image of a lower revision than
    // the last one it flew.
    std::optional<std::int64_t> revision;
    Heartbeat heartbeat;
    Tolerance tolerance;
    std::vector<Node> nodes;    // file order
    std::vector<Task> tasks;    // file order
    std::vector<Phase> phases;  // file order

    const Node* node(const std::string& name) const;
    const Task* task(const std::string& name) const;
    const Phase* phase(const std::string& name) const;
    // A configuration by its mission-wide name, or nullptr.
    const Configuration* configuration(const std::string& name) const;
    // Logical address of a node: its index in `nodes` (file order), or -1.
    int address_of(const std::string& node) const;
    std::vector<std::string> processing_nodes() const;
    std::vector<std::string> storage_nodes() const;
};

// One loader error, reported as "file:line:col: rule: message".
struct LoadError {
    std::string file;
    int line = 1;
    int col = 1;
    std::string rule;  // see config/schema/README.md
    std::string message;

    std::string to_string() const;
    // Rules of the shape stages are input errors (exit 2); unknown-reference and
    // port-conflict are violations of a well-formed file (exit 1).
    bool is_input_error() const;
};

// The outcome of loading: a mission, or every error of the first step that found any,
// sorted by position.
struct LoadResult {
    std::optional<Mission> mission;
    std::vector<LoadError> errors;

    bool ok() const { return mission.has_value(); }
    // 0 when loaded, else 2 if any error is an input error, else 1.
    int exit_code() const;
};

// The normalised JSON form of a mission (config/schema/README.md): the JSON `keel-verify
// load --json` prints for the YAML it was compiled from, up to whitespace and key order
// (written in the image's canonical encoding, core/mission/image.cpp).
std::string to_json(const Mission& mission);

}  // namespace keel::mission
