// Executor: runs a node's tasks, as the paper's Tasking framework does.
//
// Triggering. An active task becomes ready when
//   - every one of its declared inputs has a sample waiting (trigger `inputs`), or
//   - its period has elapsed (trigger `timer`; first at activation, then every period_ms;
//     periods missed because the task was still busy are skipped and counted), or
//   - an event was raised for it (trigger `event`),
// whichever holds first, checked in that order. On an `inputs` trigger the execution
// consumes the oldest sample of every input; on `timer` and `event` it consumes the oldest
// sample of each input that has one. A task runs at most once at a time: it is never
// re-entered and never runs on two threads at once; readiness that arises while it runs
// is acted on when it finishes.
//
// Types. A component may declare the sample types its ports carry (port_types()): samples
// of another type are refused at its inputs and dropped from its outputs, both counted.
//
// Inputs. Each input port holds a bounded queue (ExecutorLimits::input_queue_capacity).
// Overflow policy: drop-oldest. A sample arriving at a full queue evicts the oldest one
// waiting, and TaskStats::inputs_dropped counts it; the newest data always gets in.
// Samples for a task that is configured but not active wait in its queue until it is
// activated.
//
// Outputs. After execute() returns, the samples a task emitted are handed to the
// OutputSink, if one is set (that is where the node runtime plugs in delivery to remote
// nodes: logical address + port, over the network layer), then queued on every local task
// that declares the producer among its inputs (the handle is copied, never the payload).
// Samples from the network enter through deliver() (by source port) or post() (one task).
//
// Priority. Ready tasks wait in one queue, the highest TaskSpec::priority (the mission's)
// first, in the order they became ready among equals: when more tasks are ready than
// there are workers, the more important runs first. As on any priority scheduler, as many
// tasks of a higher priority as there are workers, always ready (inputs arriving faster
// than they run), starve the others, whose health monitors then see them silent. A
// dispatch hook (set_dispatch_hook) runs on the worker just before and just after each
// execution: the node runtime sets the thread's real-time priority there.
//
// Two modes drive the same logic:
//   - manual: run_ready() runs, on the calling thread, every task ready at the clock's
//     current time, including those made ready by what it runs (bounded), then returns.
//     Tests and the simulator use it with a ManualClock;
//   - threaded: start() spawns a bounded pool of worker threads (ExecutorLimits::threads,
//     default std::thread::hardware_concurrency()) and one timer thread; stop() joins them.
// Never call run_ready() while the pool runs.
//
// Threading contract. Lifecycle calls (add, configure, activate, deactivate, remove,
// set_output_sink, start, stop) come from one thread, the node's control thread, and never
// from inside a component or an OutputSink. post(), deliver(), raise_event(), stats(),
// take_health_events() and take_checkpoints() may be called from any thread, including
// from inside execute() and OutputSink::publish(). The ready queue holds each task at most
// once, so it is bounded by max_tasks.
//
// Health and checkpoints. Every execution's result goes to a TaskHealthMonitor configured
// from the task's mission health bounds; take_health_events() runs its deadline check
// and hands over what it raised (bounded queue, drop-oldest, counted). After each
// successful execution of a task with `checkpoint: true`, its snapshot() is kept as the
// task's pending checkpoint (a newer one supersedes it); take_checkpoints() hands them over
// for the CheckpointStore.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <vector>

#include "core/tasking/clock.hpp"
#include "core/tasking/component.hpp"
#include "core/tasking/health.hpp"
#include "core/tasking/pi_mutex.hpp"
#include "core/tasking/registry.hpp"

namespace keel::tasking {

using TaskId = std::uint32_t;

struct ExecutorLimits {
    std::size_t max_tasks = 4096;
    std::size_t threads = 0;  // worker threads in threaded mode; 0: hardware_concurrency
    std::size_t input_queue_capacity = 8;  // samples per input port
    std::size_t max_outputs_per_execution = 64;
    std::size_t max_pending_events = 64;  // raised and not yet run, per task
    std::size_t max_pending_health_events = 1024;
    std::uint32_t failure_limit = 3;  // consecutive failures that count as an error
};

// The hook through which the node runtime sends a task's outputs off the node.
class OutputSink {
  public:
    virtual ~OutputSink() = default;
    // Called once per sample, before local delivery, on the thread that ran the producer,
    // without the executor's lock held, while the producer is still marked running.
    // Must be thread-safe (several producers may publish at once), should not block and
    // must not throw.
    virtual void publish(const TaskSpec& producer, const Sample& sample) = 0;
};

enum class TaskLifecycle : std::uint8_t { configured = 0, active = 1 };

struct TaskStats {
    TaskLifecycle lifecycle = TaskLifecycle::configured;
    std::uint64_t executions = 0;  // including those before a restore from a snapshot
    std::uint64_t successes = 0;
    std::uint64_t failures = 0;
    std::uint64_t errors = 0;
    std::uint64_t by_inputs = 0;
    std::uint64_t by_timer = 0;
    std::uint64_t by_event = 0;
    std::uint64_t inputs_received = 0;
    std::uint64_t inputs_dropped = 0;   // evicted by drop-oldest
    std::uint64_t inputs_mistyped = 0;  // refused: a type the component does not accept
    std::uint64_t events_dropped = 0;   // raised beyond max_pending_events
    std::uint64_t outputs = 0;
    std::uint64_t outputs_dropped = 0;   // beyond max_outputs_per_execution
    std::uint64_t outputs_mistyped = 0;  // not of a type the component declared
    std::uint64_t periods_missed = 0;
    std::uint64_t checkpoints_superseded = 0;
    std::optional<double> last_control_value;
    std::string last_error;  // message of the last non-success lifecycle call or exception
};

class Executor {
  public:
    explicit Executor(Clock& clock, ExecutorLimits limits = {});
    ~Executor();  // stops the pool; does not deactivate tasks
    Executor(const Executor&) = delete;
    Executor& operator=(const Executor&) = delete;

    struct AddResult {
        std::optional<TaskId> id;  // set when the task was configured and added
        LifecycleResult result;
    };
    // Configures the component with its spec's context and adds the task, inactive.
    // Refused (failure) when the name or port is taken or max_tasks are held.
    AddResult add(TaskInstance instance);
    // Re-configures an inactive task with a new spec of the same task (a phase change).
    LifecycleResult configure(TaskId id, TaskSpec spec);
    LifecycleResult activate(TaskId id, const std::optional<Snapshot>& snapshot = std::nullopt);
    // Activates from `snapshot`; when the component refuses it (a state it cannot read:
    // another format, bytes that do not decode for it), the task starts fresh instead, and
    // `refused` holds the component's reason. A state the component cannot read is a loss,
    // reported by the caller, never a task left stopped on a node the cluster places it on.
    struct Activation {
        LifecycleResult result;
        std::optional<std::string> refused;
    };
    Activation activate_or_fresh(TaskId id, const std::optional<Snapshot>& snapshot);
    // Stops the task after any running execution; its final snapshot, stamped with the
    // task name and execution count. Nothing when the task is not active.
    std::optional<Snapshot> deactivate(TaskId id);
    // Deactivates if needed and forgets the task; its id may be reused.
    std::optional<Snapshot> remove(TaskId id);

    std::optional<TaskId> find(std::string_view task) const;
    std::optional<TaskId> find_port(PortNumber port) const;
    std::size_t size() const;

    // Queues `sample` on the input of `consumer` that `sample.source_port` feeds. False when
    // there is no such task or input, or the consumer does not accept the sample's type.
    bool post(TaskId consumer, const Sample& sample);
    // Queues `sample` on every task with an input fed by its source port; how many.
    std::size_t deliver(const Sample& sample);
    bool raise_event(TaskId id);

    void set_output_sink(OutputSink* sink) { sink_.store(sink, std::memory_order_release); }
    // Called on the thread that runs the task, without the executor's lock, with the task's
    // spec just before each execution and with nullptr once it is over (a lifecycle call:
    // set it before start()). Must not throw.
    void set_dispatch_hook(std::function<void(const TaskSpec*)> hook) { dispatch_hook_ = std::move(hook); }

    // No execution starts at or after `deadline_ns` (the node's lease: NodeRuntime sets it
    // after every protocol step). Ready tasks wait until a later deadline is set or they
    // are deactivated. A process stopped and resumed past its lease runs nothing on its
    // pool before its loop has judged the lease (fault model 2). Default: never.
    void set_run_until(std::int64_t deadline_ns);
    // Times a worker found the deadline passed with a task ready.
    std::uint64_t executions_gated() const;

    // Manual mode: runs ready tasks until none is ready or `max_executions` ran (0: per
    // task held, max_pending_events + input_queue_capacity + 1). Returns the number of
    // executions.
    std::size_t run_ready(std::size_t max_executions = 0);

    // Threaded mode.
    void start();
    void stop();
    bool started() const;
    std::size_t thread_count() const { return thread_count_; }
    // Blocks until no task is ready or running, or the timeout passes; true when idle.
    // Timers keep firing: with periodic tasks, the pool is idle only between periods.
    bool wait_idle(std::int64_t timeout_ms);

    TaskStats stats(TaskId id) const;
    const Clock& clock() const { return clock_; }
    std::vector<HealthEvent> take_health_events();
    std::uint64_t health_events_dropped() const;
    std::vector<Snapshot> take_checkpoints();

  private:
    struct Slot;
    struct Consumer {
        TaskId task;
        std::size_t input;
    };

    Slot* slot(TaskId id) const;                    // nullptr when absent; lock held
    void consider(TaskId id, std::int64_t now_ns);  // lock held
    // False when the consumer refuses the sample's type. Lock held.
    bool enqueue_input(Slot& slot, TaskId id, std::size_t input, const Sample& sample,
                       std::int64_t now_ns);
    // Runs one task taken from the ready queue; releases the lock while executing.
    // False for a stale entry (a task removed or deactivated while queued).
    bool run_one(std::unique_lock<PiMutex>& lock, TaskId id);
    void push_health_event(HealthEvent event);            // lock held
    void index_consumers(TaskId id, const Slot& slot);    // lock held
    void unindex_consumers(TaskId id, const Slot& slot);  // lock held
    void worker_loop();
    void timer_loop();

    Clock& clock_;
    const ExecutorLimits limits_;
    std::size_t thread_count_ = 0;

    // Priority-inheriting: the node's real-time loop takes it too (pi_mutex.hpp).
    mutable PiMutex mutex_;
    std::condition_variable_any work_cv_;   // ready queue not empty, or stopping
    std::condition_variable_any done_cv_;   // an execution finished
    std::condition_variable_any timer_cv_;  // a timer may have changed, or stopping
    std::vector<std::unique_ptr<Slot>> slots_;
    std::vector<TaskId> free_ids_;
    std::size_t task_count_ = 0;
    std::unordered_map<std::string, TaskId> by_name_;
    std::unordered_map<PortNumber, TaskId> by_port_;
    std::unordered_multimap<PortNumber, Consumer> consumers_;
    struct Ready {
        TaskId id;
        std::int64_t priority;  // the task's when it was queued
    };
    std::deque<Ready> ready_;  // highest priority first, then in the order made ready
    std::function<void(const TaskSpec*)> dispatch_hook_;
    std::size_t running_ = 0;
    TaskHealthMonitor health_;
    std::deque<HealthEvent> health_events_;
    std::uint64_t health_events_dropped_ = 0;
    std::atomic<OutputSink*> sink_{nullptr};
    bool stopping_ = false;
    std::int64_t run_until_ns_ = std::numeric_limits<std::int64_t>::max();
    std::uint64_t executions_gated_ = 0;
    std::vector<std::thread> workers_;
    std::thread timer_;
};

}  // namespace keel::tasking
