// Scheduling of a node's threads under --realtime: the protocol loop above its tasks.
//
// Heartbeats, the monitors' verdicts and the switch must not wait behind a component or an
// unrelated process, or a loaded node is declared failed (fault-model.md, "Timing"). Under
// --realtime keel-node therefore runs:
//
//   the protocol loop, its DDS participant's threads    SCHED_FIFO at the loop priority
//   (receive, delivery) and the checkpoint persister
//   the executor's workers and timer, the data plane    the task priority: normal
//   (its thread and its DDS participant's threads)      scheduling by default, or
//                                                       SCHED_FIFO below the loop
//
// with every page of the process locked in memory as it is first touched (mlockall with
// MCL_ONFAULT: no page is ever swapped out, and thread stacks are not faulted in whole).
// A real-time thread that never blocks would starve the machine, so the loop has a budget:
// in every window of `budget_window_ns` it may use at most `budget_percent` of it on the
// CPU; past that it sleeps until it has kept that share, for one window at most (LoopBudget,
// counted as throttled).
// The kernel's own real-time throttling (sched_rt_runtime_us) bounds the rest.
//
// Where the process may not use SCHED_FIFO (no CAP_SYS_NICE, RLIMIT_RTPRIO 0, a container),
// everything runs at normal priority and the node says so at boot and in every status line
// (SchedulingReport); it flies, with the timing margins of docs/fault-model.md.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace keel::node {

struct SchedulingOptions {
    bool realtime = false;
    int loop_priority = 50;  // SCHED_FIFO priority of the loop, 1..99
    // Of the tasks, below loop_priority; 0: normal scheduling (the default: a CPU-bound
    // component under SCHED_FIFO would starve every process at normal priority).
    int task_priority = 0;
    int budget_percent = 50;  // of each window the loop may run, 1..100 (100: no budget)
    std::int64_t budget_window_ns = 10'000'000;
};

// What the node got, said at boot and in the status line.
struct SchedulingReport {
    static constexpr std::int64_t kUnknown = -2;  // a /proc value that could not be read
    bool realtime = false;      // the loop runs under SCHED_FIFO
    int loop_priority = 0;      // 0: normal scheduling
    int task_priority = 0;      // 0: normal scheduling
    bool memory_locked = false;
    std::string fallback;       // why real-time scheduling is not in force (empty: it is)
    std::string lock_error;     // why memory is not locked (empty: it is, or not asked)
    // What a TaskPriorityScope could not do ("...; "), logged by the runtime.
    std::string problems;
    std::int64_t rt_runtime_us = kUnknown;  // the kernel's RT throttling: -1 off
    std::int64_t rt_period_us = kUnknown;

    // One line for the log: "protocol loop SCHED_FIFO 50, tasks normal scheduling, ...".
    std::string describe(const SchedulingOptions& options) const;
};

// Checks `options` (priorities in range, task below loop, budget 1..100): an empty string
// or what is wrong, naming the flag.
std::string validate(const SchedulingOptions& options);

// Puts the calling thread (the loop, before it creates any other) under the loop's
// priority and locks memory, as `options` asks. Never throws: what failed is reported.
SchedulingReport enter_loop_scheduling(const SchedulingOptions& options);

// While alive, the calling thread runs at the task priority (threads it creates inherit
// it); restores the thread's scheduling when it ends. Does nothing unless `report.realtime`.
// What fails is written into `report` (its priorities as they are, and `problems`).
class TaskPriorityScope {
public:
    explicit TaskPriorityScope(SchedulingReport& report);
    ~TaskPriorityScope();
    TaskPriorityScope(const TaskPriorityScope&) = delete;
    TaskPriorityScope& operator=(const TaskPriorityScope&) = delete;

private:
    SchedulingReport& report_;
    bool changed_ = false;
    int policy_ = 0;
    int priority_ = 0;
};

// The real-time priority of a task's executions, under --realtime with a task priority P
// above 0 (SCHED_FIFO tasks): the mission's distinct task priorities ranked, the highest
// at P, each next one a step below, none below 1 (ranks past P - 1 share priority 1). The
// executor's dispatch hook (tasking::Executor::set_dispatch_hook) puts the worker there
// before each execution, so a task the mission ranks higher preempts a lower one running
// on the same core, and every task stays below the loop.
class TaskPriorities {
public:
    TaskPriorities(int task_priority, std::vector<std::int64_t> mission_priorities);
    int of(std::int64_t mission_priority) const;

private:
    int top_;
    std::vector<std::int64_t> ranked_;  // distinct, highest first
};

// Puts the calling thread under SCHED_FIFO `priority` unless it is there already (each
// thread remembers the last it set); 0 on success, else the error pthread_setschedparam
// returned.
int set_thread_fifo(int priority);

// The loop's CPU budget: a duty-cycle limit. Each window starts with the first pass after
// the last one ended; when the loop's CPU time since the window started exceeds its budget,
// it sleeps long enough that its CPU time is at most `budget_percent` of the wall time
// since then (so at least to the end of the window), but for one window at most, and the
// next window starts after it.
class LoopBudget {
public:
    LoopBudget(std::int64_t window_ns, int budget_percent);

    // Before a pass, with the wall clock and the loop thread's CPU time.
    void begin_pass(std::int64_t wall_ns, std::int64_t cpu_ns);
    // After it: the nanoseconds to sleep now (0: go on).
    std::int64_t end_pass(std::int64_t wall_ns, std::int64_t cpu_ns);

    std::uint64_t throttled() const { return throttled_; }
    bool enabled() const { return percent_ < 100; }

private:
    std::int64_t window_ns_;
    int percent_;
    bool open_ = false;
    std::int64_t window_start_wall_ = 0;
    std::int64_t window_start_cpu_ = 0;
    std::uint64_t throttled_ = 0;
};

// The calling thread's CPU time (CLOCK_THREAD_CPUTIME_ID), nanoseconds.
std::int64_t thread_cpu_ns();

}  // namespace keel::node
