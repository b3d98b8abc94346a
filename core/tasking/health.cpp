#include "core/tasking/health.hpp"

#include <cmath>

#include "core/tasking/assert.hpp"

namespace keel::tasking {

namespace {

std::string format_value(double value) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g", value);
    return buffer;
}

// Why `value` breaks `health`, or nothing when it is within the bounds.
std::optional<std::string> bound_broken(const mission::Health& health, double value) {
    if (!health.min && !health.max) return std::nullopt;
    if (std::isnan(value)) return std::string("control value is NaN");
    if (health.min && value < *health.min) {
        return "control value " + format_value(value) + " below min " + format_value(*health.min);
    }
    if (health.max && value > *health.max) {
        return "control value " + format_value(value) + " above max " + format_value(*health.max);
    }
    return std::nullopt;
}

}  // namespace

std::string_view to_string(HealthEventKind kind) {
    switch (kind) {
        case HealthEventKind::out_of_bounds:
            return "out_of_bounds";
        case HealthEventKind::silent:
            return "silent";
        case HealthEventKind::error:
            return "error";
    }
    return "unknown";
}

TaskHealthMonitor::TaskHealthMonitor(HealthLimits limits) : limits_(limits) {
    KEEL_TASKING_ASSERT(limits_.max_tasks > 0);
    KEEL_TASKING_ASSERT(limits_.failure_limit > 0);
}

bool TaskHealthMonitor::watch(const std::string& task, const std::optional<mission::Health>& health,
                              std::int64_t now_ms) {
    KEEL_TASKING_ASSERT(!task.empty());
    auto found = tasks_.find(task);
    if (found == tasks_.end()) {
        if (tasks_.size() >= limits_.max_tasks) return false;
        found = tasks_.emplace(task, Watched{}).first;
    }
    found->second = Watched{};
    found->second.health = health;
    found->second.last_report_ms = now_ms;
    return true;
}

void TaskHealthMonitor::unwatch(const std::string& task) {
    const auto found = tasks_.find(task);
    if (found != tasks_.end()) tasks_.erase(found);
}

std::optional<HealthEvent> TaskHealthMonitor::report(const std::string& task,
                                                     const ExecutionResult& result,
                                                     std::int64_t now_ms) {
    const auto found = tasks_.find(task);
    if (found == tasks_.end()) return std::nullopt;
    Watched& watched = found->second;
    watched.last_report_ms = now_ms;
    watched.silent_raised = false;

    if (result.outcome == Outcome::success) {
        watched.consecutive_failures = 0;
        watched.error_raised = false;
    } else {
        if (result.outcome == Outcome::failure) ++watched.consecutive_failures;
        const bool is_error = result.outcome == Outcome::error ||
                              watched.consecutive_failures >= limits_.failure_limit;
        if (is_error && !watched.error_raised) {
            watched.error_raised = true;
            std::string detail =
                result.outcome == Outcome::error
                    ? "execution ended in error"
                    : std::to_string(watched.consecutive_failures) + " consecutive failures";
            return HealthEvent{task, HealthEventKind::error, result.control_value, now_ms,
                               std::move(detail)};
        }
    }
    if (result.control_value && watched.health) {
        const auto broken = bound_broken(*watched.health, *result.control_value);
        if (!broken) {
            watched.out_of_bounds_raised = false;
        } else if (!watched.out_of_bounds_raised) {
            watched.out_of_bounds_raised = true;
            return HealthEvent{task, HealthEventKind::out_of_bounds, result.control_value, now_ms,
                               *broken};
        }
    }
    return std::nullopt;
}

std::vector<HealthEvent> TaskHealthMonitor::tick(std::int64_t now_ms) {
    std::vector<HealthEvent> events;
    for (auto& [task, watched] : tasks_) {
        if (!watched.health || !watched.health->deadline_ms || watched.silent_raised) continue;
        const std::int64_t silent_ms = now_ms - watched.last_report_ms;
        if (silent_ms > *watched.health->deadline_ms) {
            watched.silent_raised = true;
            events.push_back(
                HealthEvent{task, HealthEventKind::silent, std::nullopt, now_ms,
                            "no execution for " + std::to_string(silent_ms) + " ms (deadline " +
                                std::to_string(*watched.health->deadline_ms) + " ms)"});
        }
    }
    return events;
}

}  // namespace keel::tasking
