#include "core/node/scheduling.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <exception>
#include <functional>
#include <fstream>

namespace keel::node {

namespace {

// A number from a /proc file; kUnknown when it cannot be read.
std::int64_t read_number(const char* path) {
    std::ifstream file(path);
    std::int64_t value = 0;
    if (!(file >> value)) return SchedulingReport::kUnknown;
    return value;
}

// Whether the process holds CAP_IPC_LOCK (bit 14 of CapEff in /proc/self/status).
bool has_ipc_lock() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("CapEff:", 0) != 0) continue;
        try {
            return (std::stoull(line.substr(7), nullptr, 16) >> 14 & 1U) != 0;
        } catch (const std::exception&) {
            return false;
        }
    }
    return false;
}

std::string fifo(int priority) {
    return priority > 0 ? "SCHED_FIFO " + std::to_string(priority) : "normal scheduling";
}

}  // namespace

std::string validate(const SchedulingOptions& options) {
    if (options.loop_priority < 1 || options.loop_priority > 99) {
        return "--realtime-priority " + std::to_string(options.loop_priority) +
               ": a SCHED_FIFO priority, 1..99";
    }
    if (options.task_priority < 0 || options.task_priority >= options.loop_priority) {
        return "--task-priority " + std::to_string(options.task_priority) +
               ": 0 (normal scheduling) or a SCHED_FIFO priority below the loop's (" +
               std::to_string(options.loop_priority) + ")";
    }
    if (options.budget_percent < 1 || options.budget_percent > 100) {
        return "--loop-budget " + std::to_string(options.budget_percent) +
               ": a percentage of each 10 ms the loop may run, 1..100";
    }
    return {};
}

SchedulingReport enter_loop_scheduling(const SchedulingOptions& options) {
    SchedulingReport report;
    report.rt_runtime_us = read_number("/proc/sys/kernel/sched_rt_runtime_us");
    report.rt_period_us = read_number("/proc/sys/kernel/sched_rt_period_us");
    if (!options.realtime) {
        report.fallback = "not asked (--realtime)";
        return report;
    }
    sched_param param{};
    param.sched_priority = options.loop_priority;
    const int result = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (result != 0) {
        report.fallback = "SCHED_FIFO priority " + std::to_string(options.loop_priority) +
                          ": " + std::strerror(result);
        return report;
    }
    report.realtime = true;
    report.loop_priority = options.loop_priority;
    report.task_priority = options.task_priority;
    // MCL_ONFAULT: pages are locked as they are touched, so the DDS threads' 8 MiB stacks
    // are not faulted in whole; none is ever paged out. Under a finite RLIMIT_MEMLOCK
    // without CAP_IPC_LOCK, every mapping past the limit would fail (a thread, a buffer):
    // then nothing is locked, and the report says why.
    rlimit limit{};
    if (getrlimit(RLIMIT_MEMLOCK, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY &&
        !has_ipc_lock()) {
        report.lock_error = "RLIMIT_MEMLOCK is " + std::to_string(limit.rlim_cur / 1024) +
                            " KiB and no CAP_IPC_LOCK: a locked node could not grow";
    } else if (mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) == 0) {
        report.memory_locked = true;
    } else {
        report.lock_error = std::string("mlockall: ") + std::strerror(errno);
    }
    return report;
}

std::string SchedulingReport::describe(const SchedulingOptions& options) const {
    if (!realtime) {
        return "protocol loop and tasks at normal scheduling (real-time scheduling unavailable: " +
               fallback + "); memory not locked";
    }
    std::string line = "protocol loop " + fifo(loop_priority) + ", tasks " + fifo(task_priority) +
                       ", memory " + (memory_locked ? "locked" : "not locked (" + lock_error + ")");
    if (options.budget_percent < 100) {
        line += ", loop budget " + std::to_string(options.budget_percent) + "% of every " +
                std::to_string(options.budget_window_ns / 1'000'000) + " ms";
    } else {
        line += ", no loop budget";
    }
    if (rt_runtime_us == kUnknown || rt_period_us == kUnknown) {
        line += ", kernel real-time throttling unknown (/proc/sys/kernel/sched_rt_* unreadable)";
    } else if (rt_runtime_us < 0) {
        line += ", kernel real-time throttling off";
    } else {
        line += ", kernel real-time throttling " + std::to_string(rt_runtime_us) + "/" +
                std::to_string(rt_period_us) + " us";
    }
    return line;
}

TaskPriorityScope::TaskPriorityScope(SchedulingReport& report) : report_(report) {
    if (!report.realtime) return;
    sched_param saved{};
    int result = pthread_getschedparam(pthread_self(), &policy_, &saved);
    if (result == 0) {
        priority_ = saved.sched_priority;
        sched_param param{};
        param.sched_priority = report.task_priority;
        const int policy = report.task_priority > 0 ? SCHED_FIFO : SCHED_OTHER;
        result = pthread_setschedparam(pthread_self(), policy, &param);
    }
    changed_ = result == 0;
    if (!changed_) {
        // The tasks' threads are created at the loop's priority: said, not hidden.
        report.task_priority = report.loop_priority;
        report.problems += "tasks at the loop's priority (lowering failed: " +
                           std::string(std::strerror(result)) + "); ";
    }
}

TaskPriorities::TaskPriorities(int task_priority, std::vector<std::int64_t> mission_priorities)
    : top_(std::max(1, task_priority)), ranked_(std::move(mission_priorities)) {
    std::sort(ranked_.begin(), ranked_.end(), std::greater<>());
    ranked_.erase(std::unique(ranked_.begin(), ranked_.end()), ranked_.end());
}

int TaskPriorities::of(std::int64_t mission_priority) const {
    // Its rank: how many distinct priorities stand above it (one not in the mission ranks
    // where it would).
    const auto above = std::lower_bound(ranked_.begin(), ranked_.end(), mission_priority, std::greater<>());
    const auto rank = static_cast<int>(above - ranked_.begin());
    return std::max(1, top_ - rank);
}

int set_thread_fifo(int priority) {
    thread_local int current = -1;
    if (priority == current) return 0;
    sched_param param{};
    param.sched_priority = priority;
    const int result = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (result == 0) current = priority;
    return result;
}

TaskPriorityScope::~TaskPriorityScope() {
    if (!changed_) return;
    sched_param param{};
    param.sched_priority = priority_;
    const int result = pthread_setschedparam(pthread_self(), policy_, &param);
    if (result != 0) {
        report_.loop_priority = report_.task_priority;
        report_.problems += "the loop stayed at the tasks' priority (restoring failed: " +
                            std::string(std::strerror(result)) + "); ";
    }
}

LoopBudget::LoopBudget(std::int64_t window_ns, int budget_percent)
    : window_ns_(window_ns > 0 ? window_ns : 1),
      percent_(budget_percent < 1 ? 1 : budget_percent > 100 ? 100 : budget_percent) {}

void LoopBudget::begin_pass(std::int64_t wall_ns, std::int64_t cpu_ns) {
    if (open_ && wall_ns - window_start_wall_ < window_ns_) return;
    open_ = true;
    window_start_wall_ = wall_ns;
    window_start_cpu_ = cpu_ns;
}

std::int64_t LoopBudget::end_pass(std::int64_t wall_ns, std::int64_t cpu_ns) {
    if (!enabled() || !open_) return 0;
    const std::int64_t used = cpu_ns - window_start_cpu_;
    if (used * 100 <= window_ns_ * percent_) return 0;
    // Over budget: sleep until the CPU used is budget_percent of the time since the window
    // started (so past the window's end), but for one window at most.
    ++throttled_;
    open_ = false;
    // At most one window: a long pass (a backlog after a stall) must not silence the
    // node's heartbeats for longer than that.
    const std::int64_t elapsed = wall_ns - window_start_wall_;
    const std::int64_t until = used * 100 / percent_;
    return until > elapsed ? std::min(until - elapsed, window_ns_) : 0;
}

std::int64_t thread_cpu_ns() {
    timespec now{};
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now) != 0) return 0;
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace keel::node
