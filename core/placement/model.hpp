// The placement model: a mission's nodes, tasks and phases as indices and bit sets, for the
// checker (check.hpp) and the placer (place.hpp). No IO; built once from a loaded mission
// (core/mission/mission.hpp) and immutable after.
//
// Ids are indices in the mission's file order: node i is mission.nodes[i] (its logical
// address), task j is mission.tasks[j]. A configuration is written with them: its master,
// its observers in election order, and each task's host (kNone: not placed).
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/mission/mission.hpp"

namespace keel::placement {

inline constexpr int kNone = -1;
// A capacity the mission leaves unbounded.
inline constexpr std::int64_t kUnbounded = std::numeric_limits<std::int64_t>::max();

// A set of capabilities, interned per mission: bit i is the mission's i-th capability name.
class Capabilities {
  public:
    void add(int capability);
    bool contains_all(const Capabilities& required) const {  // in the placer's inner loop
        for (std::size_t i = 0; i < required.words_.size(); ++i) {
            const std::uint64_t have = i < words_.size() ? words_[i] : 0;
            if ((required.words_[i] & ~have) != 0) return false;
        }
        return true;
    }
    bool empty() const;

  private:
    std::vector<std::uint64_t> words_;
};

struct NodeInfo {
    std::string name;
    bool processing = false;
    bool storage = false;
    Capabilities capabilities;
    std::int64_t cpu = kUnbounded;
    std::int64_t mem_mb = kUnbounded;
};

struct TaskInfo {
    // What the placer and the checker read per task and step first, on one cache line.
    std::int64_t cpu = 0;
    std::int64_t mem_mb = 0;
    std::int64_t priority = 0;  // the placer sheds the lowest first
    int group = kNone;          // tasks of one group go on different nodes where they can
    bool essential = false;
    bool checkpoint = false;
    std::vector<int> capable;   // the nodes with every capability it requires, ascending
    std::string name;
    Capabilities requires_capabilities;
};

struct PhaseInfo {
    std::string name;
    std::vector<int> tasks;          // ascending
    std::vector<int> by_need;        // the placer's order: essential, priority, load; then id
    std::vector<std::uint8_t> in_phase;  // per task of the mission: 1 if the phase's
    int initial = kNone;             // index into configurations
    std::vector<std::string> configurations;  // the graph's, file order
};

// A configuration of one phase. `host` has one entry per task of the mission.
struct Configuration {
    int master = kNone;
    std::vector<int> observers;
    std::vector<int> host;

    friend bool operator==(const Configuration&, const Configuration&) = default;
};

// Which nodes have failed: one entry per node of the mission.
using FailedSet = std::vector<std::uint8_t>;  // one byte per node: read in the placer's inner loops

class Model {
  public:
    // The model of a loaded mission (every name in it is defined: the loader checked). Fails
    // only past the limits below, naming why in `error`.
    static std::optional<Model> build(const mission::Mission& mission, std::string* error);

    // Limits of the wire and of the placer's bounded work.
    static constexpr int kMaxNodes = 256;
    static constexpr int kMaxTasks = 1024;

    // (Kept as ints: the placer's and the checker's loops read them per step.)
    int node_count() const { return node_count_; }
    int task_count() const { return task_count_; }
    int phase_count() const { return static_cast<int>(phases_.size()); }
    const NodeInfo& node(int id) const { return nodes_[static_cast<std::size_t>(id)]; }
    const TaskInfo& task(int id) const { return tasks_[static_cast<std::size_t>(id)]; }
    const PhaseInfo& phase(int id) const { return phases_[static_cast<std::size_t>(id)]; }
    int group_count() const { return groups_; }
    // Whether `node` has every capability `task` requires (a table: the placer and the
    // checker ask it per task and node).
    bool capable(int task, int node) const {
        return capable_[static_cast<std::size_t>(task) * static_cast<std::size_t>(node_count_) +
                        static_cast<std::size_t>(node)] != 0;
    }
    // Every node's capacity by id (the placer's bins start from them).
    struct Room {
        std::int64_t cpu = kUnbounded;
        std::int64_t mem_mb = kUnbounded;
    };
    const std::vector<Room>& capacity() const { return capacity_; }

    int node_id(const std::string& name) const;
    int task_id(const std::string& name) const;
    int phase_id(const std::string& name) const;
    // A configuration of the graph by its name, in ids; nullopt when `mission` has none.
    std::optional<Configuration> configuration(const mission::Mission& mission,
                                               const std::string& name) const;
    // The empty failed set of this mission.
    FailedSet no_failures() const { return FailedSet(nodes_.size(), false); }

  private:
    std::vector<NodeInfo> nodes_;
    std::vector<TaskInfo> tasks_;
    std::vector<PhaseInfo> phases_;
    std::vector<Room> capacity_;
    std::vector<std::uint8_t> capable_;  // [task][node]
    int node_count_ = 0;
    int task_count_ = 0;
    int groups_ = 0;
};

}  // namespace keel::placement
