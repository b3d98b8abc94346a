// The loop's CPU budget (a duty-cycle limit) and the scheduling a node asks for under
// --realtime: the loop above its tasks, threads created in a TaskPriorityScope at the
// tasks' priority, and a fallback that says why.
#include "core/node/scheduling.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <cstring>
#include <thread>

namespace keel::node {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(LoopBudget, PassesWithinTheBudgetGoOn) {
    LoopBudget budget(10 * kMs, 50);
    budget.begin_pass(0, 0);
    EXPECT_EQ(budget.end_pass(1 * kMs, 1 * kMs), 0);
    budget.begin_pass(2 * kMs, 1 * kMs);  // the same window
    EXPECT_EQ(budget.end_pass(6 * kMs, 5 * kMs), 0);  // 5 ms of 10: at the budget
    EXPECT_EQ(budget.throttled(), 0U);
}

TEST(LoopBudget, JustOverTheBudgetItSleepsToTheWindowsEnd) {
    LoopBudget budget(10 * kMs, 50);
    budget.begin_pass(0, 0);
    EXPECT_EQ(budget.end_pass(2 * kMs, 2 * kMs), 0);
    budget.begin_pass(4 * kMs, 2 * kMs);
    // 1 ns past 5 ms: it sleeps to 2 ns past the window's end.
    EXPECT_EQ(budget.end_pass(7 * kMs, 5 * kMs + 1), 3 * kMs + 2);
    EXPECT_EQ(budget.throttled(), 1U);
    // The next window starts with the next pass.
    budget.begin_pass(10 * kMs, 5 * kMs);
    EXPECT_EQ(budget.end_pass(11 * kMs, 6 * kMs), 0);
}

TEST(LoopBudget, FarOverTheBudgetItSleepsUntilItsShareIsKept) {
    // 6 ms of CPU by 7 ms at 50 %: it sleeps until 12 ms, past the window's end.
    LoopBudget budget(10 * kMs, 50);
    budget.begin_pass(0, 0);
    EXPECT_EQ(budget.end_pass(7 * kMs, 6 * kMs), 5 * kMs);
}

TEST(LoopBudget, ItSleepsOneWindowAtMost) {
    // 30 ms of CPU in one pass at a 50 % budget would ask for 30 ms of sleep: a backlog
    // after a stall must not silence the node that long, so it sleeps one window.
    LoopBudget budget(10 * kMs, 50);
    budget.begin_pass(100 * kMs, 0);
    EXPECT_EQ(budget.end_pass(130 * kMs, 30 * kMs), 10 * kMs);
    EXPECT_EQ(budget.throttled(), 1U);
    // 1 ms at 1 %: 99 ms asked for, 10 ms slept.
    LoopBudget tight(10 * kMs, 1);
    tight.begin_pass(0, 0);
    EXPECT_EQ(tight.end_pass(kMs, kMs), 10 * kMs);
}

TEST(LoopBudget, AWindowEndsWithItsTime) {
    LoopBudget budget(10 * kMs, 10);
    budget.begin_pass(0, 0);
    EXPECT_EQ(budget.end_pass(kMs / 2, kMs / 2), 0);  // 0.5 ms of the 1 ms budget
    budget.begin_pass(20 * kMs, kMs / 2);               // a new window: the count restarts
    EXPECT_EQ(budget.end_pass(20 * kMs + kMs, kMs / 2 + kMs), 0);
    EXPECT_EQ(budget.throttled(), 0U);
}

TEST(LoopBudget, AHundredPercentIsNoBudget) {
    LoopBudget budget(10 * kMs, 100);
    EXPECT_FALSE(budget.enabled());
    budget.begin_pass(0, 0);
    EXPECT_EQ(budget.end_pass(10 * kMs, 10 * kMs), 0);
    EXPECT_EQ(budget.throttled(), 0U);
}

TEST(Scheduling, OptionsAreChecked) {
    SchedulingOptions options;
    EXPECT_EQ(options.task_priority, 0);  // tasks at normal scheduling unless asked
    EXPECT_EQ(validate(options), "");
    options.loop_priority = 100;
    EXPECT_NE(validate(options).find("--realtime-priority 100"), std::string::npos);
    options = {};
    options.task_priority = 40;
    EXPECT_EQ(validate(options), "");
    options.task_priority = 50;  // not below the loop's
    EXPECT_NE(validate(options).find("--task-priority 50"), std::string::npos);
    options = {};
    options.budget_percent = 0;
    EXPECT_NE(validate(options).find("--loop-budget 0"), std::string::npos);
}

TEST(Scheduling, NotAskedIsNormalScheduling) {
    const SchedulingReport report = enter_loop_scheduling({});
    EXPECT_FALSE(report.realtime);
    EXPECT_EQ(report.fallback, "not asked (--realtime)");
    EXPECT_NE(report.describe({}).find("normal scheduling"), std::string::npos);
}

TEST(Scheduling, TheKernelsThrottlingIsDescribedAsReadOrUnknown) {
    SchedulingReport report;
    report.realtime = true;
    report.loop_priority = 50;
    report.memory_locked = true;
    EXPECT_NE(report.describe({}).find("kernel real-time throttling unknown"), std::string::npos);
    report.rt_runtime_us = -1;
    report.rt_period_us = 1'000'000;
    EXPECT_NE(report.describe({}).find("kernel real-time throttling off"), std::string::npos);
    report.rt_runtime_us = 950'000;
    const std::string line = report.describe({});
    EXPECT_NE(line.find("protocol loop SCHED_FIFO 50, tasks normal scheduling, memory locked, loop budget "
                        "50% of every 10 ms, kernel real-time throttling 950000/1000000 us"),
              std::string::npos)
        << line;
}

struct Seen {
    int policy = -1;
    int priority = -1;
};

Seen scheduling_of_this_thread() {
    Seen seen;
    sched_param param{};
    pthread_getschedparam(pthread_self(), &seen.policy, &param);
    seen.priority = param.sched_priority;
    return seen;
}

TEST(Scheduling, TheLoopIsAboveTheThreadsItStartsForTasks) {
    // In a thread of its own: the test process keeps its scheduling. Memory locking is not
    // asked here (it would stay on for the whole test process).
    SchedulingReport report;
    Seen loop;
    Seen task;
    Seen restored;
    std::thread([&] {
        SchedulingOptions options;
        options.realtime = true;
        options.loop_priority = 20;
        options.task_priority = 10;
        sched_param param{};
        param.sched_priority = options.loop_priority;
        if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) != 0) {
            report = enter_loop_scheduling(options);  // the fallback, said
            return;
        }
        report.realtime = true;
        report.loop_priority = 20;
        report.task_priority = 10;
        loop = scheduling_of_this_thread();
        {
            TaskPriorityScope scope(report);
            std::thread([&] { task = scheduling_of_this_thread(); }).join();
        }
        restored = scheduling_of_this_thread();
    }).join();
    if (!report.realtime) {
        EXPECT_NE(report.fallback.find("SCHED_FIFO priority 20"), std::string::npos) << report.fallback;
        GTEST_SKIP() << "SCHED_FIFO not permitted here: " << report.fallback;
    }
    EXPECT_EQ(loop.policy, SCHED_FIFO);
    EXPECT_EQ(loop.priority, 20);
    EXPECT_EQ(task.policy, SCHED_FIFO);
    EXPECT_EQ(task.priority, 10);
    EXPECT_EQ(restored.priority, 20);
    EXPECT_EQ(report.problems, "");
}

// What enter_loop_scheduling reports when it got SCHED_FIFO `loop` for tasks at `task`.
SchedulingReport realtime_report(int loop, int task) {
    SchedulingReport report;
    report.realtime = true;
    report.loop_priority = loop;
    report.task_priority = task;
    return report;
}

TEST(Scheduling, AScopeThatCannotLowerSaysSo) {
    // A thread at normal scheduling cannot take SCHED_FIFO 10 without the privilege; as
    // root it can, and then nothing is to be said: the test checks whichever happened.
    SchedulingReport report = realtime_report(20, 10);
    Seen task;
    std::thread([&] {
        TaskPriorityScope scope(report);
        task = scheduling_of_this_thread();
    }).join();
    if (task.policy == SCHED_FIFO) {
        EXPECT_EQ(report.problems, "");
        EXPECT_EQ(task.priority, 10);
    } else {
        EXPECT_EQ(report.task_priority, 20);
        EXPECT_NE(report.problems.find("tasks at the loop's priority (lowering failed"), std::string::npos);
    }
}

TEST(Scheduling, ATaskPriorityOfZeroIsNormalScheduling) {
    SchedulingReport report = realtime_report(20, 0);
    Seen task;
    bool fifo = false;
    std::thread([&] {
        sched_param param{};
        param.sched_priority = 20;
        fifo = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
        TaskPriorityScope scope(report);
        std::thread([&] { task = scheduling_of_this_thread(); }).join();
    }).join();
    if (!fifo) GTEST_SKIP() << "SCHED_FIFO not permitted here";
    EXPECT_EQ(task.policy, SCHED_OTHER);
}

// The mission's task priorities, ranked below the tasks' real-time priority: the highest
// at it, each distinct one a step below, none below 1; equal priorities share a level.
TEST(Scheduling, TaskPrioritiesRankBelowTheTasksPriority) {
    const TaskPriorities priorities(40, {0, 10, 10, 500, 3});
    EXPECT_EQ(priorities.of(500), 40);
    EXPECT_EQ(priorities.of(10), 39);
    EXPECT_EQ(priorities.of(3), 38);
    EXPECT_EQ(priorities.of(0), 37);
    EXPECT_EQ(priorities.of(7), 38);  // not in the mission: where it would rank
    const TaskPriorities narrow(2, {0, 1, 2, 3});
    EXPECT_EQ(narrow.of(3), 2);
    EXPECT_EQ(narrow.of(2), 1);
    EXPECT_EQ(narrow.of(0), 1);  // past the band: the lowest
}

// An execution's thread is put at its task's level (the executor's dispatch hook).
TEST(Scheduling, AnExecutionRunsAtItsTasksLevel) {
    Seen seen;
    int result = -1;
    std::thread([&] {
        result = set_thread_fifo(12);
        seen = scheduling_of_this_thread();
        EXPECT_EQ(set_thread_fifo(12), 0);  // already there: nothing asked of the system
    }).join();
    if (result != 0) GTEST_SKIP() << "SCHED_FIFO not permitted here: " << std::strerror(result);
    EXPECT_EQ(seen.policy, SCHED_FIFO);
    EXPECT_EQ(seen.priority, 12);
}

}  // namespace
}  // namespace keel::node
