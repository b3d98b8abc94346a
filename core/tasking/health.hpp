// TaskHealthMonitor: task-level health, as in the paper's monitor service.
//
// After each execution a component may report a control value; the monitor compares it with
// the bounds the mission sets for the task (health.min / health.max) and watches that the
// task reports at all (health.deadline_ms). What it finds becomes a HealthEvent, which the
// node runtime turns into an error notification; the master handles it like a failure of
// the task (restart, then relocate per the decision graph).
//
// Pure logic, no threads, no clock: time comes in as milliseconds with every call.
//
//   watch(task, health, now)  start watching (at activation); the deadline runs from now
//   report(task, result, now) after each execution; may raise one event
//   tick(now)                 periodically; raises `silent` for tasks past their deadline
//   unwatch(task)             at deactivation
//
// Each condition raises one event per episode, not one per execution: `out_of_bounds` is
// raised when a value leaves the bounds and re-armed by a value inside them; `silent` is
// raised once when the deadline passes and re-armed by the next report; `error` is raised
// by an execution whose outcome is error, or by `failure_limit` consecutive failures, and
// re-armed by a success. A value exactly on a bound is inside. A NaN value is out of bounds
// whenever the task has a bound.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/tasking/component.hpp"

namespace keel::tasking {

enum class HealthEventKind : std::uint8_t { out_of_bounds = 1, silent = 2, error = 3 };
std::string_view to_string(HealthEventKind kind);

struct HealthEvent {
    std::string task;
    HealthEventKind kind = HealthEventKind::error;
    std::optional<double> value;  // the control value, for out_of_bounds
    std::int64_t at_ms = 0;
    std::string detail;  // a sentence for logs and the error notification

    friend bool operator==(const HealthEvent&, const HealthEvent&) = default;
};

struct HealthLimits {
    std::size_t max_tasks = 4096;
    // Consecutive `failure` outcomes that count as an error of the task.
    std::uint32_t failure_limit = 3;
};

class TaskHealthMonitor {
  public:
    explicit TaskHealthMonitor(HealthLimits limits = {});

    // Starts (or restarts) watching `task`. False when max_tasks are watched already.
    bool watch(const std::string& task, const std::optional<mission::Health>& health,
               std::int64_t now_ms);
    void unwatch(const std::string& task);
    bool watching(const std::string& task) const { return tasks_.contains(task); }
    std::size_t size() const { return tasks_.size(); }

    // An execution of `task` ended with `result`. Reports for unwatched tasks are ignored.
    std::optional<HealthEvent> report(const std::string& task, const ExecutionResult& result,
                                      std::int64_t now_ms);
    // Tasks silent past their deadline at `now_ms`, in task-name order.
    std::vector<HealthEvent> tick(std::int64_t now_ms);

  private:
    struct Watched {
        std::optional<mission::Health> health;
        std::int64_t last_report_ms = 0;
        std::uint32_t consecutive_failures = 0;
        bool out_of_bounds_raised = false;
        bool silent_raised = false;
        bool error_raised = false;
    };

    HealthLimits limits_;
    std::map<std::string, Watched, std::less<>> tasks_;
};

}  // namespace keel::tasking
