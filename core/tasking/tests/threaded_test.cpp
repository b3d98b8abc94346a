// The executor's worker pool: many components at once, no re-entrancy, clean deactivation.
// Run it under ThreadSanitizer too (configure with -DCMAKE_CXX_FLAGS=-fsanitize=thread).
#include <gtest/gtest.h>

#include <atomic>
#include <limits>
#include <thread>

#include "core/tasking/builtin.hpp"
#include "core/tasking/bytes.hpp"
#include "core/tasking/executor.hpp"
#include "core/tasking/tests/support.hpp"

namespace keel::tasking {
namespace {

using testing::make_task;

// Counts overlapping executions of one component instance; there must never be any.
struct Exclusive final : Component {
    std::atomic<int> in_flight{0};
    std::atomic<int> overlaps{0};
    std::atomic<int> executions{0};
    std::atomic<bool> started{false};
    std::atomic<bool> release{true};
    std::atomic<bool> finished{false};
    std::uint64_t unsynchronised_state = 0;  // data race if the executor ever re-entered

    LifecycleResult configure(const ComponentContext&) override { return {}; }
    LifecycleResult activate(const std::optional<Snapshot>&) override { return {}; }
    ExecutionResult execute(const Inputs&, Outputs& outputs) override {
        if (in_flight.fetch_add(1) != 0) overlaps.fetch_add(1);
        started = true;
        while (!release.load()) std::this_thread::yield();
        ++unsynchronised_state;
        outputs.emit(counter_type_id,
                     counter_payload(static_cast<std::int64_t>(unsynchronised_state)));
        executions.fetch_add(1);
        in_flight.fetch_sub(1);
        finished = true;
        return {Outcome::success, static_cast<double>(unsynchronised_state)};
    }
    Snapshot deactivate() override { return snapshot(); }
    Snapshot snapshot() const override {
        Snapshot state;
        put_u64(state.payload, unsynchronised_state);
        return state;
    }
};

bool wait_until(const std::function<bool()>& condition) {
    for (int attempt = 0; attempt < 10'000; ++attempt) {
        if (condition()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return condition();
}

TEST(ThreadedExecutor, ManyProducerConsumerPairsLoseNothing) {
    constexpr int pairs = 128;
    constexpr int rounds = 20;
    SteadyClock clock;
    Executor executor(clock, ExecutorLimits{.threads = 4, .input_queue_capacity = 1024});
    std::vector<mission::Task> tasks;
    std::vector<TaskId> producers;
    std::vector<TaskId> consumers;
    for (int pair = 0; pair < pairs; ++pair) {
        tasks.push_back(make_task("p" + std::to_string(pair), 1000 + pair, "producer"));
        tasks.push_back(
            make_task("c" + std::to_string(pair), 5000 + pair, "consumer", {tasks.back().name}));
    }
    for (std::size_t index = 0; index < tasks.size(); ++index) {
        const bool is_producer = index % 2 == 0;
        auto added = executor.add({testing::spec_of(tasks[index], tasks),
                                   is_producer ? make_producer() : make_consumer()});
        ASSERT_TRUE(added.id) << added.result.message;
        ASSERT_TRUE(executor.activate(*added.id).succeeded());
        (is_producer ? producers : consumers).push_back(*added.id);
    }
    executor.start();
    EXPECT_EQ(executor.thread_count(), 4u);
    // Events are raised from two threads at once while the pool runs.
    auto raise = [&](int first, int step) {
        for (int round = 0; round < rounds; ++round) {
            for (int pair = first; pair < pairs; pair += step) {
                while (!executor.raise_event(producers[pair])) std::this_thread::yield();
            }
        }
    };
    std::thread even(raise, 0, 2);
    std::thread odd(raise, 1, 2);
    even.join();
    odd.join();
    ASSERT_TRUE(wait_until([&] { return executor.wait_idle(10); }));
    executor.stop();

    for (int pair = 0; pair < pairs; ++pair) {
        EXPECT_EQ(executor.stats(producers[pair]).executions, rounds);
        const TaskStats consumer = executor.stats(consumers[pair]);
        EXPECT_EQ(consumer.executions, rounds);
        EXPECT_EQ(consumer.inputs_dropped, 0u);
        EXPECT_EQ(consumer.last_control_value, static_cast<double>(rounds));
        const auto state = executor.deactivate(consumers[pair]);
        ASSERT_TRUE(state);
        ByteReader reader(state->payload);
        EXPECT_EQ(reader.i64(), rounds * (rounds + 1) / 2);  // every counter value, in order
    }
}

TEST(ThreadedExecutor, ATaskIsNeverReEntered) {
    SteadyClock clock;
    Executor executor(clock, ExecutorLimits{.threads = 4, .input_queue_capacity = 4096});
    std::vector<mission::Task> tasks = {make_task("hot", 10, "x"),
                                        make_task("sink", 11, "x", {"hot"})};
    auto hot = std::make_unique<Exclusive>();
    Exclusive* hot_view = hot.get();
    auto hot_id = executor.add({testing::spec_of(tasks[0], tasks), std::move(hot)}).id;
    auto sink = std::make_unique<Exclusive>();
    Exclusive* sink_view = sink.get();
    auto sink_id = executor.add({testing::spec_of(tasks[1], tasks), std::move(sink)}).id;
    ASSERT_TRUE(hot_id && sink_id);
    ASSERT_TRUE(executor.activate(*hot_id).succeeded());
    ASSERT_TRUE(executor.activate(*sink_id).succeeded());
    executor.start();
    std::atomic<int> accepted{0};
    std::vector<std::thread> raisers;
    for (int thread = 0; thread < 4; ++thread) {
        raisers.emplace_back([&] {
            for (int count = 0; count < 500; ++count) {
                if (executor.raise_event(*hot_id)) accepted.fetch_add(1);
            }
        });
    }
    for (std::thread& raiser : raisers) raiser.join();
    ASSERT_TRUE(wait_until([&] { return executor.wait_idle(10); }));
    executor.stop();
    EXPECT_EQ(hot_view->overlaps.load(), 0);
    EXPECT_EQ(sink_view->overlaps.load(), 0);
    EXPECT_EQ(hot_view->executions.load(), accepted.load());
    const TaskStats stats = executor.stats(*hot_id);
    EXPECT_EQ(stats.executions + stats.events_dropped, 2000u);
    // Every output of `hot` reached `sink` (the queue is large enough), one execution each.
    EXPECT_EQ(executor.stats(*sink_id).executions, stats.executions);
}

TEST(ThreadedExecutor, DeactivateWaitsForTheRunningExecution) {
    SteadyClock clock;
    Executor executor(clock, ExecutorLimits{.threads = 2});
    std::vector<mission::Task> tasks = {make_task("slow", 10, "x")};
    auto slow = std::make_unique<Exclusive>();
    Exclusive* view = slow.get();
    view->release = false;
    const auto id = executor.add({testing::spec_of(tasks[0], tasks), std::move(slow)}).id;
    ASSERT_TRUE(id);
    ASSERT_TRUE(executor.activate(*id).succeeded());
    executor.start();
    ASSERT_TRUE(executor.raise_event(*id));
    ASSERT_TRUE(executor.raise_event(*id));  // waits behind the running one
    ASSERT_TRUE(wait_until([&] { return view->started.load(); }));
    std::thread releaser([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        view->release = true;
    });
    const auto state = executor.deactivate(*id);
    // deactivate() returned: the execution that was running has finished, and the
    // pending event was dropped with the deactivation.
    EXPECT_TRUE(view->finished.load());
    releaser.join();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->sequence, 1u);
    EXPECT_EQ(view->executions.load(), 1);
    executor.stop();
}

TEST(ThreadedExecutor, TimersFireOnTheSteadyClockAndThePoolRestarts) {
    SteadyClock clock;
    Executor executor(clock, ExecutorLimits{.threads = 2});
    std::vector<mission::Task> tasks = {make_task("tick", 10, "producer", {}, 1)};
    const auto id = executor.add({testing::spec_of(tasks[0], tasks), make_producer()}).id;
    ASSERT_TRUE(id);
    ASSERT_TRUE(executor.activate(*id).succeeded());
    executor.start();
    EXPECT_TRUE(executor.started());
    ASSERT_TRUE(wait_until([&] { return executor.stats(*id).by_timer >= 3; }));
    executor.stop();
    EXPECT_FALSE(executor.started());
    const std::uint64_t after_stop = executor.stats(*id).executions;
    executor.start();
    ASSERT_TRUE(wait_until([&] { return executor.stats(*id).executions > after_stop; }));
    executor.stop();
}

TEST(ThreadedExecutor, ThePoolWaitsPastTheRunUntilDeadlineAndGoesOnWhenItMoves) {
    SteadyClock clock;
    Executor executor(clock, ExecutorLimits{.threads = 2});
    std::vector<mission::Task> tasks = {make_task("tick", 10, "producer", {}, 1)};
    const auto id = executor.add({testing::spec_of(tasks[0], tasks), make_producer()}).id;
    ASSERT_TRUE(id);
    executor.set_run_until(clock.now_ns());  // already past: nothing may start
    ASSERT_TRUE(executor.activate(*id).succeeded());
    executor.start();
    ASSERT_TRUE(wait_until([&] { return executor.executions_gated() >= 3; }));
    EXPECT_EQ(executor.stats(*id).executions, 0u);
    executor.set_run_until(std::numeric_limits<std::int64_t>::max());
    ASSERT_TRUE(wait_until([&] { return executor.stats(*id).executions >= 3; }));
    executor.stop();
}

}  // namespace
}  // namespace keel::tasking
