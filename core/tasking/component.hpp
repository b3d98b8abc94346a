// Component: the unit of application software, as in the paper's component model.
//
// A basic component is a task plus its input and output channels. Its life:
//
//   created --configure(ctx)--> configured --activate(snapshot?)--> active
//   active --execute(inputs, outputs)--> active          (any number of times)
//   active --deactivate()--> configured                  (returns the final snapshot)
//
// Every lifecycle call and every execution ends in an Outcome:
//   success  the step did what it should;
//   failure  it could not, but the component is sound and the step may be retried
//            (a parameter out of range, an unusable input sample);
//   error    the component is broken; the node runtime treats it like a failure of the
//            task (the master restarts it, then relocates it per the decision graph).
//
// Threading: the framework never calls one component from two threads at once, and never
// re-enters it; a component needs no locks of its own. It may be called from different
// threads over its life (the executor's worker pool).
//
// Checkpointing: snapshot() returns the component's state as versioned bytes; activate()
// restores from such bytes. The executor stamps the task name and sequence; the node
// runtime hands snapshots to the CheckpointStore and back.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/tasking/sample.hpp"

namespace keel::tasking {

enum class Outcome : std::uint8_t { success = 0, failure = 1, error = 2 };
std::string_view to_string(Outcome outcome);
// The more severe of two outcomes (error > failure > success).
Outcome worst(Outcome a, Outcome b);

struct LifecycleResult {
    Outcome outcome = Outcome::success;
    std::string message;  // a sentence for logs when not success

    static LifecycleResult ok() { return {}; }
    static LifecycleResult failed(std::string why) { return {Outcome::failure, std::move(why)}; }
    static LifecycleResult broken(std::string why) { return {Outcome::error, std::move(why)}; }
    bool succeeded() const { return outcome == Outcome::success; }
};

struct ExecutionResult {
    Outcome outcome = Outcome::success;
    // The paper's control value: checked by the task health monitor against the mission's
    // health.min/max for this task. Absent when the component has none to report.
    std::optional<double> control_value;
};

// A checkpoint of a task's state. A plain struct: the node runtime maps it to the
// CheckpointStore's record.
struct Snapshot {
    std::string task;                  // mission task name (stamped by the executor)
    std::uint64_t sequence = 0;        // executions of the task when taken (stamped)
    std::uint32_t format_version = 1;  // the component's own state format version
    std::vector<std::uint8_t> payload;

    friend bool operator==(const Snapshot&, const Snapshot&) = default;
};

// What a component learns about its task when configured. Parameters are merged: the
// task's `params`, then the current phase's `params` for the task (phase values win).
struct ComponentContext {
    std::string task;
    std::string component;
    PortNumber port = 0;
    std::string phase;                // empty when instantiated outside any phase
    std::vector<std::string> inputs;  // producer task names, in declaration order
    std::optional<std::int64_t> period_ms;
    mission::Params params;

    const mission::ParamValue* param(std::string_view name) const;
    // Typed look-ups: the default when absent; std::nullopt when present with another type
    // (an integer is accepted where a double is asked for).
    std::optional<std::int64_t> int_param(std::string_view name, std::int64_t fallback) const;
    std::optional<double> double_param(std::string_view name, double fallback) const;
    std::optional<std::string> string_param(std::string_view name, std::string fallback) const;
    std::optional<bool> bool_param(std::string_view name, bool fallback) const;
};

// Why a task runs now.
enum class Trigger : std::uint8_t { inputs = 0, timer = 1, event = 2 };
std::string_view to_string(Trigger trigger);

// The samples an execution consumes: at most one per declared input, in declaration
// order. On an `inputs` trigger every input is present; on `timer` and `event` only those
// that had a sample waiting.
class Inputs {
  public:
    Inputs(const std::vector<std::string>* names, Trigger trigger);

    Trigger trigger() const { return trigger_; }
    std::size_t size() const { return samples_.size(); }
    const std::string& name(std::size_t index) const;
    // nullptr when the input has no sample in this execution.
    const Sample* get(std::size_t index) const;
    const Sample* get(std::string_view input_name) const;
    std::size_t present() const;

    void set(std::size_t index, Sample sample);

  private:
    const std::vector<std::string>* names_;
    Trigger trigger_;
    std::vector<std::optional<Sample>> samples_;
};

// Where an execution writes what it produces. Every sample emitted is stamped with the
// task's port, its next sequence number and the execution's start time, and is delivered
// after execute() returns. At most `capacity` samples per execution: more is a component
// bug, counted in dropped() and not delivered.
class Outputs {
  public:
    Outputs(PortNumber port, std::uint64_t* sequence, std::int64_t timestamp_ns,
            std::size_t capacity);

    void emit(TypeId type_id, Payload payload);
    void emit(TypeId type_id, std::vector<std::uint8_t> bytes);

    const std::vector<Sample>& samples() const { return samples_; }
    std::vector<Sample>& samples() { return samples_; }
    std::size_t dropped() const { return dropped_; }
    std::int64_t timestamp_ns() const { return timestamp_ns_; }

  private:
    PortNumber port_;
    std::uint64_t* sequence_;
    std::int64_t timestamp_ns_;
    std::size_t capacity_;
    std::size_t dropped_ = 0;
    std::vector<Sample> samples_;
};

// The sample types a component's ports carry. An empty list means "any type".
struct PortTypes {
    std::vector<TypeId> inputs;   // accepted on every input port
    std::vector<TypeId> outputs;  // emitted on the output port

    bool accepts(TypeId type) const;
    bool emits(TypeId type) const;
};

class Component {
  public:
    virtual ~Component() = default;

    // The types of the component's ports, asked once when the task is added (after
    // configure()). The executor refuses samples of other types at the input (counted in
    // TaskStats::inputs_mistyped) and drops mistyped outputs (outputs_mistyped).
    virtual PortTypes port_types() const { return {}; }

    // Reads parameters; allocates what the task needs. Called once before activate(),
    // and again after deactivate() when the phase changes its parameters.
    virtual LifecycleResult configure(const ComponentContext& context) = 0;
    // Starts the task, restoring `snapshot` when given (a checkpoint of this task).
    virtual LifecycleResult activate(const std::optional<Snapshot>& snapshot) = 0;
    virtual ExecutionResult execute(const Inputs& inputs, Outputs& outputs) = 0;
    // Stops the task; returns its final state.
    virtual Snapshot deactivate() = 0;
    // The current state, for the checkpointing service (called between executions).
    virtual Snapshot snapshot() const = 0;
};

using ComponentPtr = std::unique_ptr<Component>;

}  // namespace keel::tasking
