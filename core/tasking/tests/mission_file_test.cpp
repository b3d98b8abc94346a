// The prototype3 mission file, loaded by the mission loader, drives the built-in components.
#include <gtest/gtest.h>

#include <cstdlib>

#include "core/mission/image.hpp"
#include "core/mission/mission.hpp"
#include "core/tasking/builtin.hpp"
#include "core/tasking/executor.hpp"

namespace keel::tasking {
namespace {

std::string root() {
    const char* from_env = std::getenv("KEEL_ROOT");
    return from_env != nullptr ? from_env : ".";
}

TEST(MissionFile, Prototype3TasksRunFromTheMissionFile) {
    const mission::LoadResult loaded =
        mission::load_mission_image(root() + "/tests/missions/images/good/prototype3.json");
    ASSERT_TRUE(loaded.ok()) << (loaded.errors.empty() ? "" : loaded.errors[0].to_string());
    const mission::Mission& mission = *loaded.mission;
    ComponentRegistry registry;
    ASSERT_TRUE(register_builtin_components(registry));
    ManualClock clock;
    Executor executor(clock);
    for (const char* task : {"taskA", "taskB"}) {
        InstantiateResult instance = registry.instantiate(mission, task, "nominal");
        ASSERT_TRUE(instance.ok()) << instance.error;
        const Executor::AddResult added = executor.add(std::move(*instance.instance));
        ASSERT_TRUE(added.id) << added.result.message;
        ASSERT_TRUE(executor.activate(*added.id).succeeded());
    }
    for (int period = 0; period < 10; ++period) {
        executor.run_ready();
        clock.advance_ms(20);  // taskA's period_ms in the file
    }
    const TaskId consumer = *executor.find("taskB");
    EXPECT_EQ(executor.stats(consumer).executions, 10u);
    EXPECT_EQ(executor.stats(consumer).last_control_value, 10.0);
    // taskB is checkpointed in the file: its snapshot waits for the checkpoint store.
    const std::vector<Snapshot> checkpoints = executor.take_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].task, "taskB");
}

TEST(MissionFile, UnknownComponentNamesTheMissionAndTheTask) {
    const std::string path = root() + "/tests/missions/images/good/prototype3.json";
    mission::LoadResult loaded = mission::load_mission_image(path);
    ASSERT_TRUE(loaded.ok()) << (loaded.errors.empty() ? "" : loaded.errors[0].to_string());
    for (mission::Task& task : loaded.mission->tasks) {
        if (task.name == "taskB") task.component = "kalman";
    }
    ComponentRegistry registry;
    register_builtin_components(registry);
    const InstantiateResult result = registry.instantiate(*loaded.mission, "taskB", "nominal");
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.error.rfind(path + ": task 'taskB': unknown component 'kalman'", 0), 0u)
        << result.error;
}

}  // namespace
}  // namespace keel::tasking
