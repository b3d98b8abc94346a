#include "core/tasking/executor.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <limits>

#include "core/tasking/assert.hpp"

namespace keel::tasking {

struct Executor::Slot {
    TaskSpec spec;
    ComponentPtr component;
    std::vector<std::string> input_names;
    std::vector<std::deque<Sample>> queues;
    PortTypes types;
    TaskLifecycle lifecycle = TaskLifecycle::configured;
    bool queued = false;                // in ready_
    bool running = false;               // executing, or between dequeue and completion
    Trigger trigger = Trigger::inputs;  // of the queued execution
    std::size_t pending_events = 0;
    std::optional<std::int64_t> next_due_ns;
    std::uint64_t output_sequence = 0;  // touched only by the running execution
    std::optional<Snapshot> checkpoint;
    TaskStats stats;

    void reset_inputs(const TaskSpec& new_spec) {
        input_names.clear();
        for (const InputSpec& input : new_spec.inputs) input_names.push_back(input.task);
        queues.assign(input_names.size(), {});
    }
};

namespace {

std::int64_t period_ns(const TaskSpec& spec) {
    return spec.period_ms ? *spec.period_ms * 1'000'000 : 0;
}

}  // namespace

Executor::Executor(Clock& clock, ExecutorLimits limits)
    : clock_(clock),
      limits_(limits),
      health_(HealthLimits{limits.max_tasks, limits.failure_limit}) {
    KEEL_TASKING_ASSERT(limits_.max_tasks > 0);
    KEEL_TASKING_ASSERT(limits_.input_queue_capacity > 0);
    KEEL_TASKING_ASSERT(limits_.max_outputs_per_execution > 0);
    KEEL_TASKING_ASSERT(limits_.max_pending_events > 0);
    KEEL_TASKING_ASSERT(limits_.max_pending_health_events > 0);
    std::size_t threads = limits_.threads;
    if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
    thread_count_ = std::min<std::size_t>(threads, 256);
    slots_.reserve(std::min<std::size_t>(limits_.max_tasks, 4096));
}

Executor::~Executor() {
    stop();
}

Executor::Slot* Executor::slot(TaskId id) const {
    return id < slots_.size() ? slots_[id].get() : nullptr;
}

Executor::AddResult Executor::add(TaskInstance instance) {
    KEEL_TASKING_ASSERT(instance.component != nullptr);
    {
        std::lock_guard lock(mutex_);
        if (task_count_ >= limits_.max_tasks) {
            return {std::nullopt,
                    LifecycleResult::failed("the executor holds its maximum of " +
                                            std::to_string(limits_.max_tasks) + " tasks")};
        }
        if (by_name_.contains(instance.spec.name)) {
            return {std::nullopt,
                    LifecycleResult::failed("task '" + instance.spec.name + "' is already held")};
        }
        if (by_port_.contains(instance.spec.port)) {
            return {std::nullopt,
                    LifecycleResult::failed("port " + std::to_string(instance.spec.port) +
                                            " is already held by another task")};
        }
    }
    // The task is not yet visible to anyone: configure it without the lock.
    LifecycleResult result = instance.component->configure(instance.spec.context());
    if (!result.succeeded()) return {std::nullopt, result};

    auto fresh = std::make_unique<Slot>();
    fresh->types = instance.component->port_types();
    fresh->reset_inputs(instance.spec);
    fresh->spec = std::move(instance.spec);
    fresh->component = std::move(instance.component);

    std::lock_guard lock(mutex_);
    // Lifecycle calls come from one thread, so nothing took the name since the check.
    KEEL_TASKING_ASSERT(!by_name_.contains(fresh->spec.name));
    TaskId id;
    if (!free_ids_.empty()) {
        id = free_ids_.back();
        free_ids_.pop_back();
    } else {
        id = static_cast<TaskId>(slots_.size());
        slots_.emplace_back();
    }
    KEEL_TASKING_ASSERT(slots_[id] == nullptr);
    by_name_.emplace(fresh->spec.name, id);
    by_port_.emplace(fresh->spec.port, id);
    index_consumers(id, *fresh);
    slots_[id] = std::move(fresh);
    ++task_count_;
    return {id, LifecycleResult::ok()};
}

void Executor::index_consumers(TaskId id, const Slot& target) {
    for (std::size_t input = 0; input < target.spec.inputs.size(); ++input) {
        consumers_.emplace(target.spec.inputs[input].port, Consumer{id, input});
    }
}

void Executor::unindex_consumers(TaskId id, const Slot& target) {
    for (const InputSpec& input : target.spec.inputs) {
        auto [first, last] = consumers_.equal_range(input.port);
        for (auto entry = first; entry != last;) {
            entry = entry->second.task == id ? consumers_.erase(entry) : std::next(entry);
        }
    }
}

LifecycleResult Executor::configure(TaskId id, TaskSpec spec) {
    Slot* target = nullptr;
    {
        std::lock_guard lock(mutex_);
        target = slot(id);
        KEEL_TASKING_ASSERT(target != nullptr);
        if (target->lifecycle != TaskLifecycle::configured) {
            return LifecycleResult::failed("task '" + target->spec.name +
                                           "' must be deactivated before it is configured");
        }
        if (spec.name != target->spec.name || spec.port != target->spec.port) {
            return LifecycleResult::failed("a new spec must keep the task's name and port");
        }
    }
    // Inactive and not running: the component is ours alone.
    LifecycleResult result = target->component->configure(spec.context());
    std::lock_guard lock(mutex_);
    if (!result.succeeded()) {
        target->stats.last_error = result.message;
        return result;
    }
    unindex_consumers(id, *target);
    target->types = target->component->port_types();
    target->reset_inputs(spec);
    target->spec = std::move(spec);
    index_consumers(id, *target);
    return result;
}

Executor::Activation Executor::activate_or_fresh(TaskId id, const std::optional<Snapshot>& snapshot) {
    Activation activation{activate(id, snapshot), std::nullopt};
    if (!activation.result.succeeded() && snapshot && stats(id).lifecycle != TaskLifecycle::active) {
        activation.refused = activation.result.message;
        activation.result = activate(id, std::nullopt);
    }
    return activation;
}

LifecycleResult Executor::activate(TaskId id, const std::optional<Snapshot>& snapshot) {
    Slot* target = nullptr;
    {
        std::lock_guard lock(mutex_);
        target = slot(id);
        KEEL_TASKING_ASSERT(target != nullptr);
        if (target->lifecycle == TaskLifecycle::active) {
            return LifecycleResult::failed("task '" + target->spec.name + "' is already active");
        }
        KEEL_TASKING_ASSERT(!target->running);
    }
    LifecycleResult result;
    try {
        result = target->component->activate(snapshot);
    } catch (const std::exception& thrown) {
        result = LifecycleResult::broken(std::string("activate threw: ") + thrown.what());
    }
    std::lock_guard lock(mutex_);
    if (!result.succeeded()) {
        target->stats.last_error = result.message;
        return result;
    }
    const std::int64_t now_ns = clock_.now_ns();
    target->lifecycle = TaskLifecycle::active;
    target->stats.lifecycle = TaskLifecycle::active;
    if (snapshot) target->stats.executions = snapshot->sequence;
    target->next_due_ns.reset();
    if (target->spec.period_ms) target->next_due_ns = now_ns;
    health_.watch(target->spec.name, target->spec.health, now_ns / 1'000'000);
    consider(id, now_ns);
    timer_cv_.notify_all();
    return result;
}

std::optional<Snapshot> Executor::deactivate(TaskId id) {
    Slot* target = nullptr;
    {
        std::unique_lock lock(mutex_);
        target = slot(id);
        KEEL_TASKING_ASSERT(target != nullptr);
        if (target->lifecycle != TaskLifecycle::active) return std::nullopt;
        // No new execution starts from here on; wait for the one that may be running.
        target->lifecycle = TaskLifecycle::configured;
        target->stats.lifecycle = TaskLifecycle::configured;
        target->next_due_ns.reset();
        target->pending_events = 0;
        done_cv_.wait(lock, [&] { return !target->running; });
        health_.unwatch(target->spec.name);
    }
    Snapshot final_state;
    try {
        final_state = target->component->deactivate();
    } catch (const std::exception& thrown) {
        std::lock_guard lock(mutex_);
        target->stats.last_error = std::string("deactivate threw: ") + thrown.what();
        final_state = Snapshot{};
    }
    std::lock_guard lock(mutex_);
    final_state.task = target->spec.name;
    final_state.sequence = target->stats.executions;
    return final_state;
}

std::optional<Snapshot> Executor::remove(TaskId id) {
    std::optional<Snapshot> final_state = deactivate(id);
    std::lock_guard lock(mutex_);
    Slot* target = slot(id);
    KEEL_TASKING_ASSERT(target != nullptr && !target->running);
    // A stale entry may remain in ready_; it is skipped because the slot is gone.
    unindex_consumers(id, *target);
    by_name_.erase(target->spec.name);
    by_port_.erase(target->spec.port);
    slots_[id].reset();
    free_ids_.push_back(id);
    --task_count_;
    return final_state;
}

std::optional<TaskId> Executor::find(std::string_view task) const {
    std::lock_guard lock(mutex_);
    const auto found = by_name_.find(std::string(task));
    if (found == by_name_.end()) return std::nullopt;
    return found->second;
}

std::optional<TaskId> Executor::find_port(PortNumber port) const {
    std::lock_guard lock(mutex_);
    const auto found = by_port_.find(port);
    if (found == by_port_.end()) return std::nullopt;
    return found->second;
}

std::size_t Executor::size() const {
    std::lock_guard lock(mutex_);
    return task_count_;
}

bool Executor::enqueue_input(Slot& target, TaskId id, std::size_t input, const Sample& sample,
                             std::int64_t now_ns) {
    if (!target.types.accepts(sample.type_id)) {
        ++target.stats.inputs_mistyped;
        return false;
    }
    std::deque<Sample>& queue = target.queues[input];
    if (queue.size() >= limits_.input_queue_capacity) {
        queue.pop_front();
        ++target.stats.inputs_dropped;
    }
    queue.push_back(sample);
    ++target.stats.inputs_received;
    KEEL_TASKING_ASSERT(queue.size() <= limits_.input_queue_capacity);
    consider(id, now_ns);
    return true;
}

bool Executor::post(TaskId consumer, const Sample& sample) {
    std::lock_guard lock(mutex_);
    Slot* target = slot(consumer);
    if (target == nullptr) return false;
    for (std::size_t input = 0; input < target->spec.inputs.size(); ++input) {
        if (target->spec.inputs[input].port == sample.source_port) {
            return enqueue_input(*target, consumer, input, sample, clock_.now_ns());
        }
    }
    return false;
}

std::size_t Executor::deliver(const Sample& sample) {
    std::lock_guard lock(mutex_);
    const std::int64_t now_ns = clock_.now_ns();
    std::size_t delivered = 0;
    auto [first, last] = consumers_.equal_range(sample.source_port);
    for (auto entry = first; entry != last; ++entry) {
        Slot* target = slot(entry->second.task);
        KEEL_TASKING_ASSERT(target != nullptr);
        if (enqueue_input(*target, entry->second.task, entry->second.input, sample, now_ns)) {
            ++delivered;
        }
    }
    return delivered;
}

bool Executor::raise_event(TaskId id) {
    std::lock_guard lock(mutex_);
    Slot* target = slot(id);
    if (target == nullptr || target->lifecycle != TaskLifecycle::active) return false;
    if (target->pending_events >= limits_.max_pending_events) {
        ++target->stats.events_dropped;
        return false;
    }
    ++target->pending_events;
    consider(id, clock_.now_ns());
    return true;
}

void Executor::consider(TaskId id, std::int64_t now_ns) {
    Slot* target = slot(id);
    if (target == nullptr || target->lifecycle != TaskLifecycle::active) return;
    if (target->queued || target->running) return;
    const bool all_inputs =
        !target->queues.empty() &&
        std::all_of(target->queues.begin(), target->queues.end(),
                    [](const std::deque<Sample>& queue) { return !queue.empty(); });
    const bool timer_due = target->next_due_ns && *target->next_due_ns <= now_ns;
    if (all_inputs) {
        target->trigger = Trigger::inputs;
    } else if (timer_due) {
        target->trigger = Trigger::timer;
        const std::int64_t period = period_ns(target->spec);
        KEEL_TASKING_ASSERT(period > 0);
        // The next period starts from the one due; periods already over are skipped.
        std::int64_t next = *target->next_due_ns + period;
        if (next <= now_ns) {
            const std::int64_t missed = (now_ns - next) / period + 1;
            target->stats.periods_missed += static_cast<std::uint64_t>(missed);
            next += missed * period;
        }
        KEEL_TASKING_ASSERT(next > now_ns);
        target->next_due_ns = next;
    } else if (target->pending_events > 0) {
        target->trigger = Trigger::event;
        --target->pending_events;
    } else {
        return;
    }
    target->queued = true;
    // Behind every task of its priority or above (a stale entry, whose slot is gone, is
    // passed over: run_one skips it).
    // Each entry keeps the priority it was queued with, so that a stale entry (its task
    // removed, its id reused) never puts the queue out of order.
    const std::int64_t priority = target->spec.priority;
    const auto behind = std::find_if(ready_.begin(), ready_.end(),
                                     [&](const Ready& other) { return other.priority < priority; });
    ready_.insert(behind, Ready{id, priority});
    KEEL_TASKING_ASSERT(ready_.size() <= limits_.max_tasks + slots_.size());
    work_cv_.notify_one();
}

void Executor::push_health_event(HealthEvent event) {
    if (health_events_.size() >= limits_.max_pending_health_events) {
        health_events_.pop_front();
        ++health_events_dropped_;
    }
    health_events_.push_back(std::move(event));
}

bool Executor::run_one(std::unique_lock<PiMutex>& lock, TaskId id) {
    KEEL_TASKING_ASSERT(lock.owns_lock());
    Slot* target = slot(id);
    // A stale entry: its task was removed (and the id perhaps reused) while queued.
    if (target == nullptr || !target->queued) return false;
    target->queued = false;
    if (target->lifecycle != TaskLifecycle::active) return false;  // deactivated while queued
    KEEL_TASKING_ASSERT(!target->running);
    target->running = true;
    ++running_;

    const Trigger trigger = target->trigger;
    Inputs inputs(&target->input_names, trigger);
    for (std::size_t input = 0; input < target->queues.size(); ++input) {
        std::deque<Sample>& queue = target->queues[input];
        if (queue.empty()) {
            KEEL_TASKING_ASSERT(trigger != Trigger::inputs);
            continue;
        }
        inputs.set(input, std::move(queue.front()));
        queue.pop_front();
    }
    const std::int64_t started_ns = clock_.now_ns();
    lock.unlock();

    if (dispatch_hook_) dispatch_hook_(&target->spec);
    // Exclusive: `running` keeps every other thread away from the component.
    Outputs outputs(target->spec.port, &target->output_sequence, started_ns,
                    limits_.max_outputs_per_execution);
    ExecutionResult result;
    std::optional<Snapshot> checkpoint;
    std::string thrown_message;
    try {
        result = target->component->execute(inputs, outputs);
        if (target->spec.checkpoint && result.outcome == Outcome::success) {
            checkpoint = target->component->snapshot();
        }
    } catch (const std::exception& thrown) {
        result = ExecutionResult{Outcome::error, std::nullopt};
        thrown_message = std::string("execute or snapshot threw: ") + thrown.what();
    } catch (...) {
        result = ExecutionResult{Outcome::error, std::nullopt};
        thrown_message = "execute or snapshot threw a non-exception";
    }
    // An execution that threw did not complete: what it emitted so far goes nowhere.
    if (!thrown_message.empty()) outputs.samples().clear();
    // A component emitting a type it did not declare has a bug: its sample goes nowhere.
    std::vector<Sample>& produced = outputs.samples();
    const auto mistyped = std::remove_if(produced.begin(), produced.end(), [&](const Sample& s) {
        return !target->types.emits(s.type_id);
    });
    const auto outputs_mistyped = static_cast<std::uint64_t>(produced.end() - mistyped);
    produced.erase(mistyped, produced.end());
    if (OutputSink* sink = sink_.load(std::memory_order_acquire)) {
        for (const Sample& sample : outputs.samples()) sink->publish(target->spec, sample);
    }
    if (dispatch_hook_) dispatch_hook_(nullptr);  // the execution is over

    lock.lock();
    const std::int64_t finished_ns = clock_.now_ns();
    TaskStats& stats = target->stats;
    ++stats.executions;
    switch (result.outcome) {
        case Outcome::success:
            ++stats.successes;
            break;
        case Outcome::failure:
            ++stats.failures;
            break;
        case Outcome::error:
            ++stats.errors;
            break;
    }
    switch (trigger) {
        case Trigger::inputs:
            ++stats.by_inputs;
            break;
        case Trigger::timer:
            ++stats.by_timer;
            break;
        case Trigger::event:
            ++stats.by_event;
            break;
    }
    if (result.control_value) stats.last_control_value = result.control_value;
    if (!thrown_message.empty()) stats.last_error = thrown_message;
    stats.outputs += outputs.samples().size();
    stats.outputs_dropped += outputs.dropped();
    stats.outputs_mistyped += outputs_mistyped;
    if (auto event = health_.report(target->spec.name, result, finished_ns / 1'000'000)) {
        if (!thrown_message.empty()) event->detail += ": " + thrown_message;
        push_health_event(std::move(*event));
    }
    if (checkpoint) {
        if (target->checkpoint) ++stats.checkpoints_superseded;
        checkpoint->task = target->spec.name;
        checkpoint->sequence = stats.executions;
        target->checkpoint = std::move(checkpoint);
    }
    for (const Sample& sample : outputs.samples()) {
        auto [first, last] = consumers_.equal_range(sample.source_port);
        for (auto entry = first; entry != last; ++entry) {
            Slot* consumer = slot(entry->second.task);
            KEEL_TASKING_ASSERT(consumer != nullptr);
            enqueue_input(*consumer, entry->second.task, entry->second.input, sample, finished_ns);
        }
    }
    target->running = false;
    KEEL_TASKING_ASSERT(running_ > 0);
    --running_;
    consider(id, finished_ns);
    done_cv_.notify_all();
    return true;
}

std::size_t Executor::run_ready(std::size_t max_executions) {
    std::unique_lock lock(mutex_);
    KEEL_TASKING_ASSERT(workers_.empty() && "run_ready() is for the manual mode only");
    if (max_executions == 0) {
        // Enough for every task to drain its events and a full input queue once; a cycle of
        // tasks feeding each other stops here instead of looping.
        const std::size_t per_task = limits_.max_pending_events + limits_.input_queue_capacity + 1;
        max_executions = std::max<std::size_t>(1, per_task * task_count_);
    }
    const std::int64_t now_ns = clock_.now_ns();
    for (TaskId id = 0; id < slots_.size(); ++id) consider(id, now_ns);
    if (now_ns >= run_until_ns_) {
        if (!ready_.empty()) ++executions_gated_;
        return 0;
    }
    std::size_t executed = 0;
    while (!ready_.empty() && executed < max_executions) {
        const TaskId id = ready_.front().id;
        ready_.pop_front();
        if (run_one(lock, id)) ++executed;
    }
    return executed;
}

void Executor::start() {
    std::lock_guard lock(mutex_);
    KEEL_TASKING_ASSERT(workers_.empty() && !timer_.joinable());
    stopping_ = false;
    for (std::size_t index = 0; index < thread_count_; ++index) {
        workers_.emplace_back([this] { worker_loop(); });
    }
    timer_ = std::thread([this] { timer_loop(); });
}

void Executor::stop() {
    {
        std::lock_guard lock(mutex_);
        if (workers_.empty() && !timer_.joinable()) return;
        stopping_ = true;
    }
    work_cv_.notify_all();
    timer_cv_.notify_all();
    for (std::thread& worker : workers_) worker.join();
    if (timer_.joinable()) timer_.join();
    std::lock_guard lock(mutex_);
    workers_.clear();
    stopping_ = false;
}

bool Executor::started() const {
    std::lock_guard lock(mutex_);
    return !workers_.empty();
}

void Executor::set_run_until(std::int64_t deadline_ns) {
    {
        std::lock_guard lock(mutex_);
        if (deadline_ns == run_until_ns_) return;
        run_until_ns_ = deadline_ns;
    }
    work_cv_.notify_all();
}

std::uint64_t Executor::executions_gated() const {
    std::lock_guard lock(mutex_);
    return executions_gated_;
}

void Executor::worker_loop() {
    std::unique_lock lock(mutex_);
    while (true) {
        work_cv_.wait(lock, [this] { return stopping_ || !ready_.empty(); });
        if (stopping_) return;
        if (clock_.now_ns() >= run_until_ns_) {
            // Past the deadline: wait for a new one (or a deactivation); look again now
            // and then, since a ManualClock in tests moves without notifying.
            ++executions_gated_;
            work_cv_.wait_for(lock, std::chrono::milliseconds(1));
            continue;
        }
        const TaskId id = ready_.front().id;
        ready_.pop_front();
        run_one(lock, id);
    }
}

void Executor::timer_loop() {
    // Wakes at the earliest due period; at most every max_sleep so that a clock that is
    // not the steady clock (a ManualClock moved by a test) is still followed.
    constexpr std::int64_t max_sleep_ns = 20'000'000;
    std::unique_lock lock(mutex_);
    while (!stopping_) {
        const std::int64_t now_ns = clock_.now_ns();
        std::int64_t next_ns = now_ns + max_sleep_ns;
        for (TaskId id = 0; id < slots_.size(); ++id) {
            Slot* target = slots_[id].get();
            if (target == nullptr || !target->next_due_ns) continue;
            consider(id, now_ns);
            // A queued or running task is considered again when its execution ends.
            if (target->queued || target->running) continue;
            next_ns = std::min(next_ns, *target->next_due_ns);
        }
        const std::int64_t sleep_ns = std::max<std::int64_t>(next_ns - now_ns, 100'000);
        timer_cv_.wait_for(lock, std::chrono::nanoseconds(sleep_ns));
    }
}

bool Executor::wait_idle(std::int64_t timeout_ms) {
    std::unique_lock lock(mutex_);
    return done_cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                             [this] { return ready_.empty() && running_ == 0; });
}

TaskStats Executor::stats(TaskId id) const {
    std::lock_guard lock(mutex_);
    const Slot* target = slot(id);
    KEEL_TASKING_ASSERT(target != nullptr);
    return target->stats;
}

std::vector<HealthEvent> Executor::take_health_events() {
    std::lock_guard lock(mutex_);
    for (HealthEvent& event : health_.tick(clock_.now_ms())) push_health_event(std::move(event));
    std::vector<HealthEvent> out(std::make_move_iterator(health_events_.begin()),
                                 std::make_move_iterator(health_events_.end()));
    health_events_.clear();
    return out;
}

std::uint64_t Executor::health_events_dropped() const {
    std::lock_guard lock(mutex_);
    return health_events_dropped_;
}

std::vector<Snapshot> Executor::take_checkpoints() {
    std::lock_guard lock(mutex_);
    std::vector<Snapshot> out;
    for (const auto& target : slots_) {
        if (target == nullptr || !target->checkpoint) continue;
        out.push_back(std::move(*target->checkpoint));
        target->checkpoint.reset();
    }
    return out;
}

}  // namespace keel::tasking
