// Unit tests of the limit checker: the component alone (lifecycle, alarms, checkpoint and
// restore, bad parameters), its parameters per phase of mission.yaml, and the component
// run by Keel's executor next to the mission's telemetry task, as a node runs it.
#include "limit_checker.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/mission/image.hpp"
#include "core/mission/mission.hpp"
#include "core/tasking/builtin.hpp"
#include "core/tasking/clock.hpp"
#include "core/tasking/executor.hpp"

namespace limit_checker {
namespace {

namespace tasking = keel::tasking;
namespace mission = keel::mission;

// What configure() gets for the mission's `limits` task, here written by hand.
tasking::ComponentContext context(std::int64_t low, std::int64_t high, std::int64_t persistence,
                                  std::string phase = "cruise") {
    tasking::ComponentContext context;
    context.task = "limits";
    context.component = "limit_checker";
    context.port = 101;
    context.phase = std::move(phase);
    context.inputs = {"telemetry"};
    context.params = {{"low", low}, {"high", high}, {"persistence", persistence}};
    return context;
}

// Drives one component by hand: one counter sample per execution, as the executor would.
class Driver {
  public:
    explicit Driver(tasking::Component& component) : component_(component) {}

    tasking::ExecutionResult check(std::int64_t value) {
        tasking::Sample sample;
        sample.type_id = tasking::counter_type_id;
        sample.sequence = ++sent_;
        sample.source_port = 100;
        sample.payload = tasking::make_payload(tasking::counter_payload(value));
        tasking::Inputs inputs(&names_, tasking::Trigger::inputs);
        inputs.set(0, sample);
        tasking::Outputs outputs(101, &sequence_, 0, 4);
        const tasking::ExecutionResult result = component_.execute(inputs, outputs);
        last_.reset();
        if (outputs.samples().size() == 1) {
            EXPECT_EQ(outputs.samples().front().type_id, status_type_id);
            last_ = decode_status(*outputs.samples().front().payload);
        }
        return result;
    }
    // The status sample of the last execution, if it emitted one.
    const std::optional<LimitStatus>& status() const { return last_; }

  private:
    tasking::Component& component_;
    std::vector<std::string> names_ = {"telemetry"};
    std::uint64_t sent_ = 0;
    std::uint64_t sequence_ = 0;
    std::optional<LimitStatus> last_;
};

TEST(LimitChecker, RaisesAnAlarmAfterPersistenceSamplesOutOfLimitsAndClearsIt) {
    const tasking::ComponentPtr checker = make_limit_checker();
    ASSERT_TRUE(checker->configure(context(0, 5, 3)).succeeded());
    ASSERT_TRUE(checker->activate(std::nullopt).succeeded());
    Driver driver(*checker);

    const tasking::ExecutionResult within = driver.check(5);
    EXPECT_EQ(within.outcome, tasking::Outcome::success);
    EXPECT_EQ(within.control_value, 5.0);  // the control value is the value checked
    EXPECT_EQ(driver.status(), (LimitStatus{5, Verdict::within, 0, 0, false}));

    driver.check(6);
    driver.check(7);
    EXPECT_EQ(driver.status(), (LimitStatus{7, Verdict::above, 2, 0, false}));
    driver.check(8);  // the third in a row: the alarm
    EXPECT_EQ(driver.status(), (LimitStatus{8, Verdict::above, 3, 1, true}));
    driver.check(9);  // still raised, not raised again
    EXPECT_EQ(driver.status(), (LimitStatus{9, Verdict::above, 4, 1, true}));
    driver.check(-1);  // below: out of limits on the other side, the same episode
    EXPECT_EQ(driver.status(), (LimitStatus{-1, Verdict::below, 5, 1, true}));
    driver.check(0);  // back within: cleared
    EXPECT_EQ(driver.status(), (LimitStatus{0, Verdict::within, 0, 1, false}));
}

TEST(LimitChecker, GoesOnFromItsCheckpoint) {
    const tasking::ComponentPtr before = make_limit_checker();
    ASSERT_TRUE(before->configure(context(0, 5, 2)).succeeded());
    ASSERT_TRUE(before->activate(std::nullopt).succeeded());
    Driver first(*before);
    for (const std::int64_t value : {1, 9, 9, 9}) first.check(value);
    ASSERT_EQ(first.status(), (LimitStatus{9, Verdict::above, 3, 1, true}));
    const tasking::Snapshot checkpoint = before->deactivate();
    EXPECT_EQ(checkpoint.format_version, 1u);

    // Another instance (on another node) restores it: the episode goes on, no second alarm.
    const tasking::ComponentPtr after = make_limit_checker();
    ASSERT_TRUE(after->configure(context(0, 5, 2)).succeeded());
    ASSERT_TRUE(after->activate(checkpoint).succeeded());
    Driver second(*after);
    second.check(10);
    EXPECT_EQ(second.status(), (LimitStatus{10, Verdict::above, 4, 1, true}));
    EXPECT_EQ(after->snapshot().payload.size(), checkpoint.payload.size());

    // A checkpoint of another format, or cut short, is refused (the node starts it fresh).
    tasking::Snapshot other = checkpoint;
    other.format_version = 2;
    EXPECT_EQ(make_limit_checker()->activate(other).outcome, tasking::Outcome::failure);
    tasking::Snapshot cut = checkpoint;
    cut.payload.pop_back();
    const tasking::ComponentPtr third = make_limit_checker();
    ASSERT_TRUE(third->configure(context(0, 5, 2)).succeeded());
    EXPECT_EQ(third->activate(cut).outcome, tasking::Outcome::failure);
}

TEST(LimitChecker, RefusesParametersItCannotUse) {
    EXPECT_FALSE(make_limit_checker()->configure(context(10, 5, 1)).succeeded());  // low > high
    EXPECT_FALSE(make_limit_checker()->configure(context(0, 5, 0)).succeeded());   // persistence
    tasking::ComponentContext text = context(0, 5, 1);
    text.params.emplace_back("high", std::string("warm"));  // later entries win: a string
    EXPECT_FALSE(make_limit_checker()->configure(text).succeeded());
    tasking::ComponentContext two_inputs = context(0, 5, 1);
    two_inputs.inputs.push_back("other");
    EXPECT_FALSE(make_limit_checker()->configure(two_inputs).succeeded());
}

TEST(LimitChecker, StatusSamplesDecodeOnlyWhenWhole) {
    const LimitStatus status{-3, Verdict::below, 2, 7, true};
    const std::vector<std::uint8_t> bytes = encode(status);
    EXPECT_EQ(bytes.size(), 36u);
    EXPECT_EQ(decode_status(bytes), status);
    EXPECT_EQ(decode_status(std::span(bytes).first(35)), std::nullopt);
    std::vector<std::uint8_t> verdict = bytes;
    verdict[12] = 3;  // no such verdict
    EXPECT_EQ(decode_status(verdict), std::nullopt);
}

// The mission (its image, as a node flies it): the task's parameters merged with each phase's, as a node configures it.
TEST(LimitChecker, TakesItsLimitsFromTheMissionPhase) {
    const mission::LoadResult loaded = mission::load_mission_image(MISSION_IMAGE);
    ASSERT_TRUE(loaded.ok()) << (loaded.errors.empty() ? "" : loaded.errors.front().to_string());
    tasking::ComponentRegistry registry;
    ASSERT_TRUE(register_components(registry));
    for (const auto& [phase, high] : {std::pair{"cruise", 5}, std::pair{"science", 1000}}) {
        tasking::InstantiateResult limits = registry.instantiate(*loaded.mission, "limits", phase);
        ASSERT_TRUE(limits.ok()) << limits.error;
        const tasking::ComponentContext configured = limits.instance->spec.context();
        EXPECT_EQ(configured.int_param("high", 0), high) << phase;
        EXPECT_EQ(configured.int_param("low", -1), 0) << phase;
        EXPECT_EQ(configured.int_param("persistence", 0), 3) << phase;
        EXPECT_TRUE(limits.instance->spec.checkpoint);
        tasking::Component& checker = *limits.instance->component;
        ASSERT_TRUE(checker.configure(configured).succeeded());
        ASSERT_TRUE(checker.activate(std::nullopt).succeeded());
        Driver driver(checker);
        for (int sample = 0; sample < 3; ++sample) driver.check(50);
        EXPECT_EQ(driver.status()->alarm, high < 50) << phase;
    }
}

// The executor runs the mission's two tasks as a node does: the telemetry task every
// 100 ms, the checker whenever a sample arrives, a checkpoint after each execution.
TEST(LimitChecker, RunsUnderTheExecutorWithTheMissionsTelemetry) {
    const mission::LoadResult loaded = mission::load_mission_image(MISSION_IMAGE);
    ASSERT_TRUE(loaded.ok());
    tasking::ComponentRegistry registry;
    ASSERT_TRUE(tasking::register_builtin_components(registry));  // `producer`
    ASSERT_TRUE(register_components(registry));
    tasking::ManualClock clock;
    tasking::Executor executor(clock);
    std::vector<tasking::TaskId> ids;
    for (tasking::InstantiateResult& task : registry.instantiate_all(*loaded.mission, "cruise")) {
        ASSERT_TRUE(task.ok()) << task.error;
        const tasking::Executor::AddResult added = executor.add(std::move(*task.instance));
        ASSERT_TRUE(added.id) << added.result.message;
        ids.push_back(*added.id);
    }
    for (const tasking::TaskId id : ids) ASSERT_TRUE(executor.activate(id).succeeded());
    const tasking::TaskId limits = *executor.find("limits");
    for (int period = 0; period < 10; ++period) {
        executor.run_ready();
        clock.advance_ms(100);
    }
    executor.run_ready();
    const tasking::TaskStats stats = executor.stats(limits);
    EXPECT_EQ(stats.executions, 11u);  // telemetry 1..11, one check each
    EXPECT_EQ(stats.failures + stats.errors + stats.inputs_mistyped, 0u);
    EXPECT_EQ(stats.last_control_value, 11.0);
    const std::vector<tasking::Snapshot> checkpoints = executor.take_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);  // the latest of the one checkpointed task
    EXPECT_EQ(checkpoints.front().task, "limits");
    const tasking::ComponentPtr restored = make_limit_checker();
    ASSERT_TRUE(restored->configure(context(0, 5, 3)).succeeded());
    ASSERT_TRUE(restored->activate(checkpoints.front()).succeeded());
    Driver driver(*restored);
    driver.check(12);
    // 11 checked; above 5 from 6 on: six in a row, the alarm raised once, now the seventh.
    EXPECT_EQ(driver.status(), (LimitStatus{12, Verdict::above, 7, 1, true}));
}

}  // namespace
}  // namespace limit_checker
