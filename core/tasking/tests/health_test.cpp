#include "core/tasking/health.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace keel::tasking {
namespace {

ExecutionResult value(double control_value) {
    return {Outcome::success, control_value};
}

mission::Health bounds(std::optional<double> min, std::optional<double> max,
                       std::optional<std::int64_t> deadline_ms = std::nullopt) {
    return mission::Health{min, max, deadline_ms};
}

TEST(TaskHealth, ValuesOnTheBoundsAreInside) {
    TaskHealthMonitor monitor;
    ASSERT_TRUE(monitor.watch("acca0", bounds(0.0, 1.0), 0));
    EXPECT_FALSE(monitor.report("acca0", value(0.0), 1));
    EXPECT_FALSE(monitor.report("acca0", value(1.0), 2));
    EXPECT_FALSE(monitor.report("acca0", value(0.5), 3));
    EXPECT_FALSE(monitor.report("acca0", {Outcome::success, std::nullopt}, 4));
}

TEST(TaskHealth, OutOfBoundsIsRaisedOncePerEpisode) {
    TaskHealthMonitor monitor;
    monitor.watch("acca0", bounds(0.0, 1.0), 0);
    const auto above = monitor.report("acca0", value(1.5), 10);
    ASSERT_TRUE(above.has_value());
    EXPECT_EQ(above->kind, HealthEventKind::out_of_bounds);
    EXPECT_EQ(above->value, 1.5);
    EXPECT_EQ(above->at_ms, 10);
    EXPECT_EQ(above->task, "acca0");
    EXPECT_EQ(above->detail, "control value 1.5 above max 1");
    EXPECT_FALSE(monitor.report("acca0", value(2.0), 11));  // same episode
    EXPECT_FALSE(monitor.report("acca0", value(0.5), 12));  // back in: re-armed
    const auto below = monitor.report("acca0", value(-1.0), 13);
    ASSERT_TRUE(below.has_value());
    EXPECT_EQ(below->detail, "control value -1 below min 0");
}

TEST(TaskHealth, OneSidedBoundsAndNaN) {
    TaskHealthMonitor monitor;
    monitor.watch("low", bounds(std::nullopt, 10.0), 0);
    EXPECT_FALSE(monitor.report("low", value(-1e9), 1));
    EXPECT_TRUE(monitor.report("low", value(10.5), 2));
    monitor.watch("nan", bounds(0.0, std::nullopt), 0);
    const auto event = monitor.report("nan", value(std::nan("")), 1);
    ASSERT_TRUE(event.has_value());
    EXPECT_EQ(event->detail, "control value is NaN");
    // Without bounds, any value is fine.
    monitor.watch("free", std::nullopt, 0);
    EXPECT_FALSE(monitor.report("free", value(std::nan("")), 1));
}

TEST(TaskHealth, SilencePastTheDeadlineIsRaisedOnceUntilTheNextReport) {
    TaskHealthMonitor monitor;
    monitor.watch("camera", bounds(std::nullopt, std::nullopt, 100), 1000);
    EXPECT_TRUE(monitor.tick(1100).empty());  // exactly at the deadline: not yet past
    const auto events = monitor.tick(1101);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].kind, HealthEventKind::silent);
    EXPECT_EQ(events[0].detail, "no execution for 101 ms (deadline 100 ms)");
    EXPECT_TRUE(monitor.tick(5000).empty());
    EXPECT_FALSE(monitor.report("camera", value(1.0), 5001));
    EXPECT_TRUE(monitor.tick(5100).empty());
    EXPECT_EQ(monitor.tick(5102).size(), 1u);
}

TEST(TaskHealth, TasksWithoutDeadlineAreNeverSilent) {
    TaskHealthMonitor monitor;
    monitor.watch("a", bounds(0.0, 1.0), 0);
    monitor.watch("b", std::nullopt, 0);
    EXPECT_TRUE(monitor.tick(1'000'000).empty());
}

TEST(TaskHealth, ErrorOutcomeAndRepeatedFailuresAreErrors) {
    TaskHealthMonitor monitor(HealthLimits{16, 2});
    monitor.watch("t", std::nullopt, 0);
    const auto error = monitor.report("t", {Outcome::error, std::nullopt}, 1);
    ASSERT_TRUE(error.has_value());
    EXPECT_EQ(error->kind, HealthEventKind::error);
    EXPECT_FALSE(monitor.report("t", {Outcome::error, std::nullopt}, 2));  // same episode
    EXPECT_FALSE(monitor.report("t", value(1.0), 3));                      // re-armed
    EXPECT_FALSE(monitor.report("t", {Outcome::failure, std::nullopt}, 4));
    const auto failures = monitor.report("t", {Outcome::failure, std::nullopt}, 5);
    ASSERT_TRUE(failures.has_value());
    EXPECT_EQ(failures->detail, "2 consecutive failures");
    // A success in between resets the count.
    EXPECT_FALSE(monitor.report("t", value(1.0), 6));
    EXPECT_FALSE(monitor.report("t", {Outcome::failure, std::nullopt}, 7));
    EXPECT_FALSE(monitor.report("t", value(1.0), 8));
    EXPECT_FALSE(monitor.report("t", {Outcome::failure, std::nullopt}, 9));
}

TEST(TaskHealth, UnwatchedTasksAreIgnoredAndTheTableIsBounded) {
    TaskHealthMonitor monitor(HealthLimits{2, 3});
    EXPECT_FALSE(monitor.report("ghost", {Outcome::error, std::nullopt}, 1));
    EXPECT_TRUE(monitor.watch("a", bounds(0.0, 1.0, 10), 0));
    EXPECT_TRUE(monitor.watch("b", std::nullopt, 0));
    EXPECT_FALSE(monitor.watch("c", std::nullopt, 0));
    EXPECT_TRUE(monitor.watch("a", bounds(0.0, 1.0, 10), 5));  // re-watch resets, no growth
    monitor.unwatch("a");
    EXPECT_FALSE(monitor.watching("a"));
    EXPECT_TRUE(monitor.tick(1000).empty());
    EXPECT_TRUE(monitor.watch("c", std::nullopt, 0));
    EXPECT_EQ(monitor.size(), 2u);
}

}  // namespace
}  // namespace keel::tasking
