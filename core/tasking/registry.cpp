#include "core/tasking/registry.hpp"

#include <string_view>
#include <unordered_map>
#include <variant>

#include "core/tasking/assert.hpp"

namespace keel::tasking {

namespace {

// Looks names up by walking the model's vectors, so that this file depends on the
// mission model's layout only.
const mission::Task* find_task(const mission::Mission& mission, const std::string& name) {
    for (const mission::Task& task : mission.tasks) {
        if (task.name == name) return &task;
    }
    return nullptr;
}

const mission::Phase* find_phase(const mission::Mission& mission, const std::string& name) {
    for (const mission::Phase& phase : mission.phases) {
        if (phase.name == name) return &phase;
    }
    return nullptr;
}

std::string where(const mission::Mission& mission, int line) {
    const std::string file = mission.path.empty() ? "<mission " + mission.name + ">" : mission.path;
    return line > 0 ? file + ":" + std::to_string(line) : file;
}

// Mission look-ups by name: a linear walk for one task, a hash index for many.
class Lookup {
  public:
    explicit Lookup(const mission::Mission& mission) : mission_(mission) {}
    void build_index() {
        for (const mission::Task& task : mission_.tasks) index_.emplace(task.name, &task);
    }
    const mission::Task* task(const std::string& name) const {
        if (index_.empty()) return find_task(mission_, name);
        const auto found = index_.find(name);
        return found == index_.end() ? nullptr : found->second;
    }

  private:
    const mission::Mission& mission_;
    std::unordered_map<std::string_view, const mission::Task*> index_;
};

std::variant<TaskSpec, std::string> spec_of(const mission::Mission& mission, const Lookup& lookup,
                                            const std::string& task_name,
                                            const mission::Phase* phase,
                                            const std::string& phase_name) {
    const mission::Task* task = lookup.task(task_name);
    if (task == nullptr) {
        return where(mission, 0) + ": no task named '" + task_name + "'";
    }
    TaskSpec spec;
    spec.name = task->name;
    spec.component = task->component.empty() ? task->name : task->component;
    spec.port = task->port;
    spec.phase = phase_name;
    spec.period_ms = task->period_ms;
    spec.health = task->health;
    spec.checkpoint = task->checkpoint;
    spec.essential = task->essential;
    spec.priority = task->priority.value_or(0);
    spec.params = task->params;
    spec.mission_path = mission.path;
    spec.line = task->line;
    for (const std::string& input : task->inputs) {
        const mission::Task* producer = lookup.task(input);
        if (producer == nullptr) {
            return where(mission, task->line) + ": task '" + task->name + "': input '" + input +
                   "' is not a task";
        }
        spec.inputs.push_back({producer->name, producer->port});
    }
    if (!phase_name.empty()) {
        if (phase == nullptr) {
            return where(mission, task->line) + ": task '" + task->name + "': no phase named '" +
                   phase_name + "'";
        }
        for (const auto& [name, params] : phase->params) {
            if (name != task->name) continue;
            spec.params.insert(spec.params.end(), params.begin(), params.end());
        }
    }
    return spec;
}

}  // namespace

ComponentContext TaskSpec::context() const {
    ComponentContext context;
    context.task = name;
    context.component = component;
    context.port = port;
    context.phase = phase;
    context.inputs.reserve(inputs.size());
    for (const InputSpec& input : inputs) context.inputs.push_back(input.task);
    context.period_ms = period_ms;
    context.params = params;
    return context;
}

std::variant<TaskSpec, std::string> make_task_spec(const mission::Mission& mission,
                                                   const std::string& task_name,
                                                   const std::string& phase_name) {
    return spec_of(mission, Lookup(mission), task_name, find_phase(mission, phase_name),
                   phase_name);
}

bool ComponentRegistry::add(std::string name, ComponentFactory factory) {
    if (name.empty() || !factory) return false;
    return factories_.emplace(std::move(name), std::move(factory)).second;
}

std::optional<std::string> ComponentRegistry::merge(ComponentRegistry&& other) {
    for (const auto& [name, factory] : other.factories_) {
        if (factories_.contains(name)) return name;
    }
    factories_.merge(other.factories_);
    KEEL_TASKING_ASSERT(other.factories_.empty());
    return std::nullopt;
}

std::vector<std::string> ComponentRegistry::names() const {
    std::vector<std::string> out;
    out.reserve(factories_.size());
    for (const auto& entry : factories_) out.push_back(entry.first);
    return out;
}

ComponentPtr ComponentRegistry::create(const std::string& name) const {
    const auto found = factories_.find(name);
    if (found == factories_.end()) return nullptr;
    return found->second();
}

InstantiateResult ComponentRegistry::instantiate(const mission::Mission& mission,
                                                 const std::string& task,
                                                 const std::string& phase) const {
    return instantiate_spec(mission, make_task_spec(mission, task, phase));
}

std::vector<InstantiateResult> ComponentRegistry::instantiate_all(
    const mission::Mission& mission, const std::string& phase_name,
    const std::vector<std::string>& tasks) const {
    Lookup lookup(mission);
    lookup.build_index();
    const mission::Phase* phase = find_phase(mission, phase_name);
    std::vector<std::string> names = tasks;
    if (names.empty() && phase != nullptr) names = phase->tasks;
    if (names.empty()) {
        for (const mission::Task& task : mission.tasks) names.push_back(task.name);
    }
    std::vector<InstantiateResult> out;
    out.reserve(names.size());
    for (const std::string& name : names) {
        out.push_back(instantiate_spec(mission, spec_of(mission, lookup, name, phase, phase_name)));
    }
    return out;
}

InstantiateResult ComponentRegistry::instantiate_spec(
    const mission::Mission& mission, std::variant<TaskSpec, std::string> spec_or_error) const {
    if (auto* error = std::get_if<std::string>(&spec_or_error)) return {std::nullopt, *error};
    TaskSpec& spec = std::get<TaskSpec>(spec_or_error);
    const auto found = factories_.find(spec.component);
    if (found == factories_.end()) {
        std::string known;
        for (const auto& entry : factories_) {
            known += (known.empty() ? "" : ", ") + entry.first;
        }
        return {std::nullopt, where(mission, spec.line) + ": task '" + spec.name +
                                  "': unknown component '" + spec.component +
                                  "' (registered: " + (known.empty() ? "none" : known) + ")"};
    }
    ComponentPtr component = found->second();
    if (component == nullptr) {
        return {std::nullopt, where(mission, spec.line) + ": task '" + spec.name +
                                  "': the factory of component '" + spec.component +
                                  "' returned nothing"};
    }
    return {TaskInstance{std::move(spec), std::move(component)}, {}};
}

}  // namespace keel::tasking
