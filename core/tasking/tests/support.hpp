// Helpers shared by the tasking tests: a mission built in code and a scriptable component.
#pragma once

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/tasking/component.hpp"
#include "core/tasking/registry.hpp"

namespace keel::tasking::testing {

inline mission::Task make_task(std::string name, std::int64_t port, std::string component,
                               std::vector<std::string> inputs = {},
                               std::optional<std::int64_t> period_ms = std::nullopt) {
    mission::Task task;
    task.name = std::move(name);
    task.port = port;
    task.component = std::move(component);
    task.inputs = std::move(inputs);
    task.period_ms = period_ms;
    return task;
}

// A spec for `task` straight from its fields (no mission needed).
inline TaskSpec spec_of(const mission::Task& task, const std::vector<mission::Task>& all) {
    TaskSpec spec;
    spec.name = task.name;
    spec.component = task.component;
    spec.port = task.port;
    spec.period_ms = task.period_ms;
    spec.health = task.health;
    spec.checkpoint = task.checkpoint;
    spec.priority = task.priority.value_or(0);
    spec.params = task.params;
    for (const std::string& input : task.inputs) {
        for (const mission::Task& other : all) {
            if (other.name == input) spec.inputs.push_back({other.name, other.port});
        }
    }
    return spec;
}

// What a Scripted component was asked to do, shared with the test after the executor
// took ownership of the component.
struct Script {
    std::vector<std::string> calls;       // "configure", "activate", "activate+snapshot", ...
    std::deque<ExecutionResult> results;  // returned in order; success when empty
    LifecycleResult configure_result;
    LifecycleResult activate_result;
    std::optional<LifecycleResult> snapshot_result;  // when set, what an activation from a snapshot returns
    std::vector<Trigger> triggers;
    std::vector<std::vector<std::int64_t>> seen_ports;  // source ports present per execution
    ComponentContext context;
    int emit_per_execution = 0;  // samples of type 7 per execution
    PortTypes types;
    bool throw_on_execute = false;
};

class Scripted final : public Component {
  public:
    explicit Scripted(std::shared_ptr<Script> script) : script_(std::move(script)) {}

    PortTypes port_types() const override { return script_->types; }

    LifecycleResult configure(const ComponentContext& context) override {
        script_->calls.push_back("configure");
        script_->context = context;
        return script_->configure_result;
    }
    LifecycleResult activate(const std::optional<Snapshot>& snapshot) override {
        script_->calls.push_back(snapshot ? "activate+snapshot" : "activate");
        if (snapshot && script_->snapshot_result) return *script_->snapshot_result;
        return script_->activate_result;
    }
    ExecutionResult execute(const Inputs& inputs, Outputs& outputs) override {
        script_->calls.push_back("execute");
        script_->triggers.push_back(inputs.trigger());
        std::vector<std::int64_t> ports;
        for (std::size_t index = 0; index < inputs.size(); ++index) {
            if (const Sample* sample = inputs.get(index)) ports.push_back(sample->source_port);
        }
        script_->seen_ports.push_back(ports);
        for (int count = 0; count < script_->emit_per_execution; ++count) {
            outputs.emit(7, std::vector<std::uint8_t>{static_cast<std::uint8_t>(count)});
        }
        if (script_->throw_on_execute) throw std::runtime_error("scripted failure");
        if (script_->results.empty()) return {};
        ExecutionResult result = script_->results.front();
        script_->results.pop_front();
        return result;
    }
    Snapshot deactivate() override {
        script_->calls.push_back("deactivate");
        return snapshot();
    }
    Snapshot snapshot() const override {
        Snapshot state;
        state.payload = {1, 2, 3};
        return state;
    }

  private:
    std::shared_ptr<Script> script_;
};

inline Sample sample_from(std::int64_t port, std::uint64_t sequence = 1) {
    Sample sample;
    sample.type_id = 7;
    sample.sequence = sequence;
    sample.source_port = port;
    sample.payload = make_payload({static_cast<std::uint8_t>(sequence)});
    return sample;
}

}  // namespace keel::tasking::testing
