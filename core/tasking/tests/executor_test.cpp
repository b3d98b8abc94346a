// The executor in manual mode: triggering rules, input overflow, lifecycle, routing,
// health and checkpoints, all on a ManualClock.
#include "core/tasking/executor.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>

#include "core/tasking/builtin.hpp"
#include "core/tasking/tests/support.hpp"

namespace keel::tasking {
namespace {

using testing::make_task;
using testing::sample_from;
using testing::Script;
using testing::Scripted;

class ExecutorTest : public ::testing::Test {
  protected:
    explicit ExecutorTest(ExecutorLimits limits = {}) : executor_(clock_, limits) {}

    TaskId add(mission::Task task, ComponentPtr component) {
        tasks_.push_back(task);
        Executor::AddResult added =
            executor_.add({testing::spec_of(task, tasks_), std::move(component)});
        EXPECT_TRUE(added.id.has_value()) << added.result.message;
        return added.id.value_or(0);
    }
    TaskId add_active(mission::Task task, ComponentPtr component) {
        const TaskId id = add(std::move(task), std::move(component));
        EXPECT_TRUE(executor_.activate(id).succeeded());
        return id;
    }
    std::shared_ptr<Script> scripted(mission::Task task, TaskId* id = nullptr) {
        auto script = std::make_shared<Script>();
        const TaskId added = add_active(std::move(task), std::make_unique<Scripted>(script));
        if (id != nullptr) *id = added;
        return script;
    }

    ManualClock clock_{1'000'000'000};
    Executor executor_;
    std::vector<mission::Task> tasks_;
};

TEST_F(ExecutorTest, InputTriggeredTaskWaitsForAllItsInputs) {
    add(make_task("a", 10, "x"), make_passthrough());
    add(make_task("b", 11, "x"), make_passthrough());
    TaskId fusion = 0;
    auto script = scripted(make_task("fusion", 20, "x", {"a", "b"}), &fusion);
    EXPECT_EQ(executor_.run_ready(), 0u);
    EXPECT_TRUE(executor_.post(fusion, sample_from(10)));
    EXPECT_EQ(executor_.run_ready(), 0u);  // only one of two inputs
    EXPECT_TRUE(executor_.post(fusion, sample_from(10, 2)));
    EXPECT_EQ(executor_.run_ready(), 0u);  // still nothing from b
    EXPECT_TRUE(executor_.post(fusion, sample_from(11)));
    EXPECT_EQ(executor_.run_ready(), 1u);
    ASSERT_EQ(script->triggers, std::vector<Trigger>{Trigger::inputs});
    EXPECT_EQ(script->seen_ports[0], (std::vector<std::int64_t>{10, 11}));
    // The second sample from a waits for the next one from b.
    EXPECT_EQ(executor_.run_ready(), 0u);
    EXPECT_TRUE(executor_.post(fusion, sample_from(11, 2)));
    EXPECT_EQ(executor_.run_ready(), 1u);
    EXPECT_FALSE(executor_.post(fusion, sample_from(99)));  // not an input of fusion
    EXPECT_EQ(executor_.stats(fusion).by_inputs, 2u);
}

// Of the tasks ready at once, the mission's highest priority runs first, and among equals
// the one made ready first; the dispatch hook sees each execution's task before it runs.
TEST_F(ExecutorTest, ReadyTasksRunHighestPriorityFirstThenInTheOrderMadeReady) {
    std::vector<std::string> order;
    int after = 0;
    executor_.set_dispatch_hook([&](const TaskSpec* spec) {
        if (spec == nullptr) {
            ++after;
        } else {
            EXPECT_EQ(after, static_cast<int>(order.size()));  // the last execution is over
            order.push_back(spec->name);
        }
    });
    const std::vector<std::pair<const char*, std::optional<std::int64_t>>> tasks{
        {"low", 0}, {"high", 5}, {"middle", 2}, {"high_too", 5}, {"unstated", std::nullopt}};
    PortNumber port = 10;
    for (const auto& [name, priority] : tasks) {
        mission::Task task = make_task(name, port++, "x", {}, 20);
        task.priority = priority;
        add_active(task, make_passthrough());
    }
    EXPECT_EQ(executor_.run_ready(), 5u);
    EXPECT_EQ(order, (std::vector<std::string>{"high", "high_too", "middle", "low", "unstated"}));
    EXPECT_EQ(after, 5);
}

TEST_F(ExecutorTest, TimerTriggeredTaskRunsOncePerPeriodAndCountsMissedPeriods) {
    TaskId id = 0;
    auto script = scripted(make_task("camera", 10, "x", {}, 20), &id);
    EXPECT_EQ(executor_.run_ready(), 1u);  // first period at activation
    EXPECT_EQ(executor_.run_ready(), 0u);
    clock_.advance_ms(19);
    EXPECT_EQ(executor_.run_ready(), 0u);
    clock_.advance_ms(1);
    EXPECT_EQ(executor_.run_ready(), 1u);
    clock_.advance_ms(20 * 3 + 5);  // three periods pass; one execution, two missed
    EXPECT_EQ(executor_.run_ready(), 1u);
    EXPECT_EQ(executor_.run_ready(), 0u);
    clock_.advance_ms(15);  // the period grid holds: next due at +100 from the start
    EXPECT_EQ(executor_.run_ready(), 1u);
    const TaskStats stats = executor_.stats(id);
    EXPECT_EQ(stats.by_timer, 4u);
    EXPECT_EQ(stats.periods_missed, 2u);
    EXPECT_EQ(script->triggers.size(), 4u);
}

TEST_F(ExecutorTest, NoExecutionStartsPastTheRunUntilDeadline) {
    // The node's lease as the deadline: a process resumed past it runs nothing until its
    // loop sets a later one.
    TaskId id = 0;
    auto script = scripted(make_task("camera", 10, "x", {}, 20), &id);
    executor_.set_run_until(clock_.now_ns() + 30'000'000);
    EXPECT_EQ(executor_.run_ready(), 1u);
    clock_.advance_ms(20);
    EXPECT_EQ(executor_.run_ready(), 1u);
    clock_.advance_ms(20);  // due again, but past the deadline
    EXPECT_EQ(executor_.run_ready(), 0u);
    EXPECT_EQ(executor_.executions_gated(), 1u);
    executor_.set_run_until(clock_.now_ns() + 1);
    EXPECT_EQ(executor_.run_ready(), 1u);
    EXPECT_EQ(script->triggers.size(), 3u);
}

TEST_F(ExecutorTest, EventTriggeredTaskRunsOncePerEventUpToItsBound) {
    TaskId id = 0;
    auto script = scripted(make_task("command", 30, "x"), &id);
    EXPECT_EQ(executor_.run_ready(), 0u);
    EXPECT_TRUE(executor_.raise_event(id));
    EXPECT_TRUE(executor_.raise_event(id));
    EXPECT_EQ(executor_.run_ready(), 2u);
    EXPECT_EQ(script->triggers, (std::vector<Trigger>{Trigger::event, Trigger::event}));
    // One event becomes the queued execution; 64 more may wait behind it.
    for (int count = 0; count < 65; ++count) EXPECT_TRUE(executor_.raise_event(id));
    EXPECT_FALSE(executor_.raise_event(id));
    EXPECT_EQ(executor_.stats(id).events_dropped, 1u);
    EXPECT_EQ(executor_.run_ready(), 65u);  // within the default bound of 73
}

TEST_F(ExecutorTest, TimerAndEventTriggersConsumeTheInputsThatAreThere) {
    add(make_task("a", 10, "x"), make_passthrough());
    add(make_task("b", 11, "x"), make_passthrough());
    TaskId id = 0;
    auto script = scripted(make_task("sampler", 20, "x", {"a", "b"}, 50), &id);
    executor_.post(id, sample_from(11));
    EXPECT_EQ(executor_.run_ready(), 1u);
    EXPECT_EQ(script->triggers.back(), Trigger::timer);
    EXPECT_EQ(script->seen_ports.back(), (std::vector<std::int64_t>{11}));
    executor_.raise_event(id);
    EXPECT_EQ(executor_.run_ready(), 1u);
    EXPECT_EQ(script->triggers.back(), Trigger::event);
    EXPECT_TRUE(script->seen_ports.back().empty());  // consumed by the timer execution
}

TEST_F(ExecutorTest, FullInputQueueDropsTheOldestAndCountsIt) {
    add(make_task("a", 10, "x"), make_passthrough());
    struct Recorder final : Component {
        std::vector<std::uint64_t>* sequences;
        explicit Recorder(std::vector<std::uint64_t>* out) : sequences(out) {}
        LifecycleResult configure(const ComponentContext&) override { return {}; }
        LifecycleResult activate(const std::optional<Snapshot>&) override { return {}; }
        ExecutionResult execute(const Inputs& inputs, Outputs&) override {
            sequences->push_back(inputs.get(0)->sequence);
            return {};
        }
        Snapshot deactivate() override { return {}; }
        Snapshot snapshot() const override { return {}; }
    };
    std::vector<std::uint64_t> sequences;
    const TaskId id =
        add_active(make_task("slow", 20, "x", {"a"}), std::make_unique<Recorder>(&sequences));
    for (std::uint64_t sequence = 1; sequence <= 11; ++sequence) {
        executor_.post(id, sample_from(10, sequence));
    }
    EXPECT_EQ(executor_.run_ready(), 8u);  // the queue holds 8
    EXPECT_EQ(sequences, (std::vector<std::uint64_t>{4, 5, 6, 7, 8, 9, 10, 11}));
    const TaskStats stats = executor_.stats(id);
    EXPECT_EQ(stats.inputs_received, 11u);
    EXPECT_EQ(stats.inputs_dropped, 3u);
}

TEST_F(ExecutorTest, OutputsReachLocalConsumersWithoutCopyAndTheSink) {
    struct Sink final : OutputSink {
        std::mutex mutex;
        std::vector<std::pair<std::string, Sample>> published;
        void publish(const TaskSpec& producer, const Sample& sample) override {
            std::lock_guard lock(mutex);
            published.emplace_back(producer.name, sample);
        }
    } sink;
    executor_.set_output_sink(&sink);
    const TaskId source = add_active(make_task("source", 10, "x"), make_passthrough());
    (void)source;
    const TaskId relay = add_active(make_task("relay", 11, "x", {"source"}), make_passthrough());
    const TaskId first = add_active(make_task("first", 12, "x", {"relay"}), make_consumer());
    const TaskId second = add_active(make_task("second", 13, "x", {"relay"}), make_consumer());

    Sample scene;
    scene.type_id = counter_type_id;
    scene.source_port = 10;
    scene.payload = make_payload(counter_payload(5, 16 * 1024 * 1024));
    EXPECT_EQ(executor_.deliver(scene), 1u);
    EXPECT_EQ(executor_.run_ready(), 3u);  // relay, then both consumers
    ASSERT_EQ(sink.published.size(), 3u);
    EXPECT_EQ(sink.published[0].first, "relay");
    EXPECT_EQ(sink.published[0].second.payload.get(), scene.payload.get());  // not copied
    EXPECT_EQ(sink.published[0].second.source_port, 11);
    EXPECT_EQ(executor_.stats(first).last_control_value, 5.0);
    EXPECT_EQ(executor_.stats(second).last_control_value, 5.0);
    EXPECT_EQ(executor_.stats(relay).outputs, 1u);
    executor_.set_output_sink(nullptr);
}

TEST_F(ExecutorTest, ProducerConsumerChainAsInPrototype3) {
    const TaskId producer =
        add_active(make_task("taskA", 100, "producer", {}, 20), make_producer());
    const TaskId consumer =
        add_active(make_task("taskB", 101, "consumer", {"taskA"}), make_consumer());
    for (int period = 0; period < 5; ++period) {
        executor_.run_ready();
        clock_.advance_ms(20);
    }
    EXPECT_EQ(executor_.stats(producer).executions, 5u);
    EXPECT_EQ(executor_.stats(consumer).executions, 5u);
    EXPECT_EQ(executor_.stats(consumer).last_control_value, 5.0);  // counter 1..5
    const std::optional<Snapshot> final_state = executor_.deactivate(consumer);
    ASSERT_TRUE(final_state.has_value());
    EXPECT_EQ(final_state->task, "taskB");
    EXPECT_EQ(final_state->sequence, 5u);
}

TEST_F(ExecutorTest, ConfigureFailureRefusesTheTask) {
    auto script = std::make_shared<Script>();
    script->configure_result = LifecycleResult::failed("gain out of range");
    tasks_.push_back(make_task("bad", 40, "x"));
    Executor::AddResult added = executor_.add(
        {testing::spec_of(tasks_.back(), tasks_), std::make_unique<Scripted>(script)});
    EXPECT_FALSE(added.id.has_value());
    EXPECT_EQ(added.result.outcome, Outcome::failure);
    EXPECT_EQ(added.result.message, "gain out of range");
    EXPECT_EQ(executor_.size(), 0u);
    EXPECT_FALSE(executor_.find("bad").has_value());
}

TEST_F(ExecutorTest, DuplicateNamesAndPortsAreRefused) {
    add(make_task("a", 10, "x"), make_passthrough());
    tasks_.push_back(make_task("a", 11, "x"));
    EXPECT_FALSE(executor_.add({testing::spec_of(tasks_.back(), tasks_), make_passthrough()}).id);
    tasks_.push_back(make_task("b", 10, "x"));
    EXPECT_FALSE(executor_.add({testing::spec_of(tasks_.back(), tasks_), make_passthrough()}).id);
    EXPECT_EQ(executor_.size(), 1u);
}

TEST_F(ExecutorTest, ActivationFailureLeavesTheTaskConfiguredAndIdle) {
    auto script = std::make_shared<Script>();
    script->activate_result = LifecycleResult::broken("sensor missing");
    const TaskId id = add(make_task("cam", 10, "x", {}, 10), std::make_unique<Scripted>(script));
    const LifecycleResult result = executor_.activate(id);
    EXPECT_EQ(result.outcome, Outcome::error);
    EXPECT_EQ(executor_.stats(id).lifecycle, TaskLifecycle::configured);
    EXPECT_EQ(executor_.stats(id).last_error, "sensor missing");
    EXPECT_EQ(executor_.run_ready(), 0u);
    EXPECT_FALSE(executor_.raise_event(id));
    // Fixed, it activates.
    script->activate_result = LifecycleResult::ok();
    EXPECT_TRUE(executor_.activate(id).succeeded());
    EXPECT_EQ(executor_.activate(id).outcome, Outcome::failure);  // already active
    EXPECT_EQ(executor_.run_ready(), 1u);
}

TEST_F(ExecutorTest, ACheckpointTheComponentRefusesStartsTheTaskFresh) {
    auto script = std::make_shared<Script>();
    script->snapshot_result = LifecycleResult::failed("format 9 is not one this component reads");
    const TaskId id = add(make_task("cam", 10, "x", {}, 10), std::make_unique<Scripted>(script));
    Snapshot refused;
    refused.task = "cam";
    refused.sequence = 41;
    const Executor::Activation activation = executor_.activate_or_fresh(id, refused);
    EXPECT_TRUE(activation.result.succeeded());
    ASSERT_TRUE(activation.refused.has_value());
    EXPECT_EQ(*activation.refused, "format 9 is not one this component reads");
    EXPECT_EQ(script->calls, (std::vector<std::string>{"configure", "activate+snapshot", "activate"}));
    EXPECT_EQ(executor_.stats(id).lifecycle, TaskLifecycle::active);
    EXPECT_EQ(executor_.stats(id).executions, 0u);  // fresh, not at the refused state's count
    EXPECT_EQ(executor_.run_ready(), 1u);
    // A state it reads: no second activation, nothing refused.
    executor_.deactivate(id);
    script->snapshot_result.reset();
    script->calls.clear();
    const Executor::Activation restored = executor_.activate_or_fresh(id, refused);
    EXPECT_TRUE(restored.result.succeeded());
    EXPECT_FALSE(restored.refused.has_value());
    EXPECT_EQ(script->calls, (std::vector<std::string>{"activate+snapshot"}));
    // A component that cannot start at all: both fail, the task stays inactive, and the
    // caller is told (the node treats it as the task's error).
    executor_.deactivate(id);
    script->activate_result = LifecycleResult::broken("sensor missing");
    script->snapshot_result = LifecycleResult::broken("sensor missing");
    const Executor::Activation broken = executor_.activate_or_fresh(id, refused);
    EXPECT_FALSE(broken.result.succeeded());
    EXPECT_EQ(executor_.stats(id).lifecycle, TaskLifecycle::configured);
    // Already active: not activated twice.
    script->activate_result = LifecycleResult::ok();
    script->snapshot_result.reset();
    ASSERT_TRUE(executor_.activate(id).succeeded());
    script->calls.clear();
    const Executor::Activation twice = executor_.activate_or_fresh(id, refused);
    EXPECT_EQ(twice.result.outcome, Outcome::failure);
    EXPECT_FALSE(twice.refused.has_value());
    EXPECT_TRUE(script->calls.empty());
}

TEST_F(ExecutorTest, DeactivatedTasksStopAndReconfigureWithNewPhaseParameters) {
    const TaskId id = add_active(make_task("taskA", 100, "producer", {}, 20), make_producer());
    executor_.run_ready();
    const auto state = executor_.deactivate(id);
    ASSERT_TRUE(state.has_value());
    EXPECT_FALSE(executor_.deactivate(id).has_value());
    clock_.advance_ms(100);
    EXPECT_EQ(executor_.run_ready(), 0u);

    TaskSpec science = testing::spec_of(tasks_[0], tasks_);
    science.phase = "science";
    science.params = {{"step", std::int64_t{10}}};
    EXPECT_TRUE(executor_.configure(id, science).succeeded());
    ASSERT_TRUE(executor_.activate(id, state).succeeded());
    EXPECT_EQ(executor_.run_ready(), 1u);
    EXPECT_EQ(executor_.stats(id).last_control_value, 11.0);  // 1 restored, + step 10
    EXPECT_EQ(executor_.stats(id).executions, 2u);            // continues from the snapshot
    EXPECT_EQ(executor_.configure(id, science).outcome, Outcome::failure);  // active
}

TEST_F(ExecutorTest, SnapshotRoundTripMovesATaskToAnotherExecutor) {
    const TaskId producer =
        add_active(make_task("taskA", 100, "producer", {}, 20), make_producer());
    const TaskId consumer =
        add_active(make_task("taskB", 101, "consumer", {"taskA"}), make_consumer());
    for (int period = 0; period < 3; ++period) {
        executor_.run_ready();
        clock_.advance_ms(20);
    }
    (void)producer;
    const std::optional<Snapshot> moved = executor_.remove(consumer);
    ASSERT_TRUE(moved.has_value());
    EXPECT_EQ(executor_.size(), 1u);

    // The consumer restarts on another node from the snapshot; its total carries over.
    ManualClock other_clock;
    Executor other(other_clock);
    Executor::AddResult added = other.add({testing::spec_of(tasks_[1], tasks_), make_consumer()});
    ASSERT_TRUE(added.id);
    ASSERT_TRUE(other.activate(*added.id, moved).succeeded());
    Sample sample;
    sample.type_id = counter_type_id;
    sample.source_port = 100;
    sample.payload = make_payload(counter_payload(4));
    EXPECT_EQ(other.deliver(sample), 1u);
    EXPECT_EQ(other.run_ready(), 1u);
    const auto final_state = other.deactivate(*added.id);
    ASSERT_TRUE(final_state);
    EXPECT_EQ(final_state->sequence, 4u);
    ComponentPtr check = make_consumer();
    ComponentContext context;
    context.inputs = {"taskA"};
    ASSERT_TRUE(check->configure(context).succeeded());
    ASSERT_TRUE(check->activate(final_state).succeeded());
    // total 1+2+3+4 = 10, received 4, last 4.
    std::vector<std::uint8_t> expected;
    for (std::uint64_t word : {10ull, 4ull, 4ull}) {
        for (int shift = 0; shift < 64; shift += 8) {
            expected.push_back(static_cast<std::uint8_t>(word >> shift));
        }
    }
    EXPECT_EQ(check->snapshot().payload, expected);
}

TEST_F(ExecutorTest, CheckpointedTasksLeaveTheirLatestSnapshot) {
    mission::Task checkpointed = make_task("taskB", 101, "consumer", {"taskA"});
    checkpointed.checkpoint = true;
    add_active(make_task("taskA", 100, "producer", {}, 20), make_producer());
    const TaskId consumer = add_active(checkpointed, make_consumer());
    executor_.run_ready();
    clock_.advance_ms(20);
    executor_.run_ready();
    std::vector<Snapshot> taken = executor_.take_checkpoints();
    ASSERT_EQ(taken.size(), 1u);  // the producer has no checkpoint: only taskB
    EXPECT_EQ(taken[0].task, "taskB");
    EXPECT_EQ(taken[0].sequence, 2u);
    EXPECT_EQ(executor_.stats(consumer).checkpoints_superseded, 1u);
    EXPECT_TRUE(executor_.take_checkpoints().empty());
}

TEST_F(ExecutorTest, HealthEventsFromBoundsErrorsExceptionsAndSilence) {
    mission::Task watched = make_task("acca0", 20, "x");
    watched.health = mission::Health{0.0, 1.0, 100};
    TaskId id = 0;
    auto script = scripted(watched, &id);
    script->results = {{Outcome::success, 0.5}, {Outcome::success, 2.0}, {Outcome::error, 0.5}};
    for (int round = 0; round < 3; ++round) {
        executor_.raise_event(id);
        executor_.run_ready();
    }
    std::vector<HealthEvent> events = executor_.take_health_events();
    ASSERT_EQ(events.size(), 2u);
    EXPECT_EQ(events[0].kind, HealthEventKind::out_of_bounds);
    EXPECT_EQ(events[0].value, 2.0);
    EXPECT_EQ(events[1].kind, HealthEventKind::error);
    EXPECT_EQ(executor_.stats(id).errors, 1u);

    clock_.advance_ms(101);
    events = executor_.take_health_events();
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].kind, HealthEventKind::silent);
    EXPECT_EQ(events[0].task, "acca0");

    script->throw_on_execute = true;
    script->emit_per_execution = 1;  // emitted, then the execution throws
    executor_.raise_event(id);
    executor_.raise_event(id);
    EXPECT_EQ(executor_.run_ready(), 2u);
    EXPECT_EQ(executor_.stats(id).last_error, "execute or snapshot threw: scripted failure");
    EXPECT_EQ(executor_.stats(id).errors, 3u);
    EXPECT_EQ(executor_.stats(id).outputs, 0u);  // a throwing execution publishes nothing
    events = executor_.take_health_events();
    ASSERT_EQ(events.size(), 0u);  // still the same error episode: no success in between
}

TEST_F(ExecutorTest, DeactivatedTasksAreNotWatched) {
    mission::Task watched = make_task("acca0", 20, "x");
    watched.health = mission::Health{std::nullopt, std::nullopt, 50};
    TaskId id = 0;
    scripted(watched, &id);
    executor_.deactivate(id);
    clock_.advance_ms(1000);
    EXPECT_TRUE(executor_.take_health_events().empty());
}

TEST_F(ExecutorTest, RemovedTaskIdsAreReusedAndStaleWorkIsSkipped) {
    TaskId first = 0;
    auto old_script = scripted(make_task("old", 10, "x"), &first);
    executor_.raise_event(first);  // queued, never run
    executor_.remove(first);
    TaskId second = 0;
    auto new_script = scripted(make_task("new", 11, "x"), &second);
    EXPECT_EQ(second, first);
    EXPECT_EQ(executor_.run_ready(), 0u);
    EXPECT_TRUE(std::count(old_script->calls.begin(), old_script->calls.end(), "execute") == 0);
    EXPECT_TRUE(new_script->triggers.empty());
    EXPECT_FALSE(executor_.find("old"));
    EXPECT_EQ(executor_.find("new"), second);
    EXPECT_EQ(executor_.find_port(11), second);
}

TEST_F(ExecutorTest, PortTypesAreEnforcedAtInputsAndOutputs) {
    add_active(make_task("taskA", 100, "producer"), make_producer());
    const TaskId consumer =
        add_active(make_task("taskB", 101, "consumer", {"taskA"}), make_consumer());
    EXPECT_FALSE(executor_.post(consumer, sample_from(100)));  // type 7, not a counter
    EXPECT_EQ(executor_.deliver(sample_from(100)), 0u);
    EXPECT_EQ(executor_.run_ready(), 0u);
    EXPECT_EQ(executor_.stats(consumer).inputs_mistyped, 2u);
    EXPECT_EQ(executor_.stats(consumer).inputs_received, 0u);

    // A component that declares counter outputs and emits type 7 loses those samples.
    mission::Task liar_task = make_task("liar", 102, "x");
    TaskId liar = 0;
    auto script = std::make_shared<Script>();
    script->types.outputs = {counter_type_id};
    script->emit_per_execution = 2;
    liar = add_active(liar_task, std::make_unique<Scripted>(script));
    const TaskId listener =
        add_active(make_task("listener", 103, "x", {"liar"}), make_passthrough());
    executor_.raise_event(liar);
    EXPECT_EQ(executor_.run_ready(), 1u);
    EXPECT_EQ(executor_.stats(liar).outputs, 0u);
    EXPECT_EQ(executor_.stats(liar).outputs_mistyped, 2u);
    EXPECT_EQ(executor_.stats(listener).inputs_received, 0u);
}

TEST_F(ExecutorTest, ExcessOutputsAreDroppedAndCounted) {
    TaskId id = 0;
    auto script = scripted(make_task("chatty", 10, "x"), &id);
    script->emit_per_execution = 70;
    executor_.raise_event(id);
    executor_.run_ready();
    EXPECT_EQ(executor_.stats(id).outputs, 64u);
    EXPECT_EQ(executor_.stats(id).outputs_dropped, 6u);
}

TEST_F(ExecutorTest, RunReadyIsBoundedForCyclesOfTasks) {
    // ping and pong feed each other: without a bound this would never end.
    tasks_ = {make_task("ping", 10, "x", {"pong"}), make_task("pong", 11, "x", {"ping"})};
    std::vector<TaskId> ids;
    for (const mission::Task& task : tasks_) {
        ids.push_back(*executor_.add({testing::spec_of(task, tasks_), make_passthrough()}).id);
        ASSERT_TRUE(executor_.activate(ids.back()).succeeded());
    }
    EXPECT_TRUE(executor_.post(ids[0], sample_from(11)));
    EXPECT_EQ(executor_.run_ready(10), 10u);
    EXPECT_EQ(executor_.run_ready(), 2u * (64 + 8 + 1));  // the default bound
    EXPECT_EQ(executor_.stats(ids[0]).executions + executor_.stats(ids[1]).executions,
              10u + 2u * (64 + 8 + 1));
}

class SmallExecutorTest : public ExecutorTest {
  protected:
    SmallExecutorTest() : ExecutorTest(ExecutorLimits{.max_tasks = 2}) {}
};

TEST_F(SmallExecutorTest, MaxTasksIsEnforced) {
    add(make_task("a", 10, "x"), make_passthrough());
    add(make_task("b", 11, "x"), make_passthrough());
    tasks_.push_back(make_task("c", 12, "x"));
    const Executor::AddResult added =
        executor_.add({testing::spec_of(tasks_.back(), tasks_), make_passthrough()});
    EXPECT_FALSE(added.id);
    EXPECT_NE(added.result.message.find("maximum of 2"), std::string::npos);
}

}  // namespace
}  // namespace keel::tasking
