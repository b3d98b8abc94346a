// ComponentRegistry: component names -> factories, and instantiation of a mission's tasks.
//
// A mission task names its component (`component:`, by default the task's own name). Each
// node holds every component it may run (the paper stores tasks locally on each processing
// node, so a reconfiguration only has to broadcast a configuration id); the registry turns
// a task of the mission into a TaskInstance: the component, plus a TaskSpec saying how the
// executor must drive it (port, inputs, period, health bounds, merged parameters).
//
// The registry is filled at start-up and read afterwards: instantiate() is const and may be
// called from any thread once registration is over.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/tasking/component.hpp"

namespace keel::tasking {

struct InputSpec {
    std::string task;     // the producing task
    PortNumber port = 0;  // its mission port: samples from it carry this source_port
};

// How the executor drives one task; everything the mission says about it, resolved.
struct TaskSpec {
    std::string name;
    std::string component;
    PortNumber port = 0;
    std::string phase;
    std::vector<InputSpec> inputs;
    std::optional<std::int64_t> period_ms;
    std::optional<mission::Health> health;
    bool checkpoint = false;
    bool essential = false;
    // The mission's priority (0-1000000, 0 when it states none): of the tasks ready at once
    // on a node the highest runs first (Executor), and under keel-node --realtime with
    // real-time tasks its executions run at a real-time priority by its rank.
    std::int64_t priority = 0;
    // Task params, then the phase's params for the task (later entries win on look-up).
    mission::Params params;
    std::string mission_path;
    int line = 0;

    ComponentContext context() const;
};

struct TaskInstance {
    TaskSpec spec;
    ComponentPtr component;
};

struct InstantiateResult {
    std::optional<TaskInstance> instance;
    // "mission.yaml:12: task 'acca0': unknown component 'acca' (registered: ...)".
    std::string error;

    bool ok() const { return instance.has_value(); }
};

// The spec of `task` in `phase` (empty phase: task params only), or an error sentence.
std::variant<TaskSpec, std::string> make_task_spec(const mission::Mission& mission,
                                                   const std::string& task,
                                                   const std::string& phase);

using ComponentFactory = std::function<ComponentPtr()>;

class ComponentRegistry {
  public:
    // Registers `factory` under `name`. False when the name is taken or the factory empty.
    bool add(std::string name, ComponentFactory factory);
    bool contains(const std::string& name) const { return factories_.contains(name); }
    std::vector<std::string> names() const;  // sorted
    std::size_t size() const { return factories_.size(); }
    // Moves every factory of `other` into this registry, unless a name is registered in
    // both: then nothing moves and that name (the first, in name order) is returned.
    std::optional<std::string> merge(ComponentRegistry&& other);

    // A fresh component, or nullptr when `name` is not registered.
    ComponentPtr create(const std::string& name) const;

    // The component of `task` of `mission`, with its spec for `phase`. Errors (unknown
    // task, phase or component, a factory returning null) name the mission file and the
    // task's line.
    InstantiateResult instantiate(const mission::Mission& mission, const std::string& task,
                                  const std::string& phase = {}) const;

    // Every task of `phase` (its `tasks`; all tasks when it lists none), in mission order,
    // or just `tasks` when given: one result per task. Looks names up through an index
    // built once, so configuring thousands of tasks stays linear.
    std::vector<InstantiateResult> instantiate_all(
        const mission::Mission& mission, const std::string& phase,
        const std::vector<std::string>& tasks = {}) const;

  private:
    InstantiateResult instantiate_spec(const mission::Mission& mission,
                                       std::variant<TaskSpec, std::string> spec_or_error) const;

    std::map<std::string, ComponentFactory, std::less<>> factories_;
};

}  // namespace keel::tasking
