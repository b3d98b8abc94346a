#include "core/tasking/registry.hpp"

#include <gtest/gtest.h>

#include "core/tasking/builtin.hpp"
#include "core/tasking/tests/support.hpp"

namespace keel::tasking {
namespace {

mission::Mission two_task_mission() {
    mission::Mission mission;
    mission.name = "unit";
    mission.path = "config/unit.yaml";
    mission::Task producer = testing::make_task("taskA", 100, "producer", {}, 20);
    producer.params = {{"step", std::int64_t{2}}, {"start", std::int64_t{1}}};
    producer.line = 17;
    mission::Task consumer = testing::make_task("taskB", 101, "consumer", {"taskA"});
    consumer.line = 18;
    consumer.checkpoint = true;
    consumer.priority = 40;
    consumer.health = mission::Health{0.0, 100.0, 500};
    mission::Task unknown = testing::make_task("acca0", 20, "acca");
    unknown.line = 19;
    mission.tasks = {producer, consumer, unknown};
    mission::Phase science;
    science.name = "science";
    science.params = {{"taskA", {{"step", std::int64_t{7}}}}};
    mission::Phase nominal;
    nominal.name = "nominal";
    mission.phases = {nominal, science};
    return mission;
}

TEST(Registry, InstantiatesAMissionTaskWithItsSpec) {
    ComponentRegistry registry;
    ASSERT_TRUE(register_builtin_components(registry));
    const mission::Mission mission = two_task_mission();
    InstantiateResult result = registry.instantiate(mission, "taskB", "nominal");
    ASSERT_TRUE(result.ok()) << result.error;
    const TaskSpec& spec = result.instance->spec;
    EXPECT_EQ(spec.name, "taskB");
    EXPECT_EQ(spec.component, "consumer");
    EXPECT_EQ(spec.port, 101);
    EXPECT_EQ(spec.phase, "nominal");
    ASSERT_EQ(spec.inputs.size(), 1u);
    EXPECT_EQ(spec.inputs[0].task, "taskA");
    EXPECT_EQ(spec.inputs[0].port, 100);
    EXPECT_TRUE(spec.checkpoint);
    EXPECT_EQ(spec.priority, 40);
    ASSERT_TRUE(spec.health.has_value());
    EXPECT_EQ(spec.health->deadline_ms, 500);
    EXPECT_EQ(spec.line, 18);
    EXPECT_NE(result.instance->component, nullptr);
}

TEST(Registry, PhaseParametersFollowAndOverrideTaskParameters) {
    ComponentRegistry registry;
    register_builtin_components(registry);
    const mission::Mission mission = two_task_mission();
    InstantiateResult science = registry.instantiate(mission, "taskA", "science");
    ASSERT_TRUE(science.ok()) << science.error;
    const ComponentContext context = science.instance->spec.context();
    EXPECT_EQ(context.int_param("step", 0), 7);
    EXPECT_EQ(context.int_param("start", 0), 1);
    EXPECT_EQ(context.phase, "science");
    EXPECT_EQ(context.period_ms, 20);

    InstantiateResult nominal = registry.instantiate(mission, "taskA", "nominal");
    ASSERT_TRUE(nominal.ok());
    EXPECT_EQ(nominal.instance->spec.context().int_param("step", 0), 2);
    InstantiateResult no_phase = registry.instantiate(mission, "taskA");
    ASSERT_TRUE(no_phase.ok());
    EXPECT_EQ(no_phase.instance->spec.context().int_param("step", 0), 2);
}

TEST(Registry, UnknownComponentNamesTheMissionFileLine) {
    ComponentRegistry registry;
    register_builtin_components(registry);
    const InstantiateResult result = registry.instantiate(two_task_mission(), "acca0");
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.error,
              "config/unit.yaml:19: task 'acca0': unknown component 'acca' "
              "(registered: consumer, passthrough, producer)");
}

TEST(Registry, OtherErrorsAreSentencesToo) {
    ComponentRegistry registry;
    register_builtin_components(registry);
    const mission::Mission mission = two_task_mission();
    EXPECT_EQ(registry.instantiate(mission, "nobody").error,
              "config/unit.yaml: no task named 'nobody'");
    EXPECT_EQ(registry.instantiate(mission, "taskA", "eclipse").error,
              "config/unit.yaml:17: task 'taskA': no phase named 'eclipse'");
    ComponentRegistry empty;
    EXPECT_NE(empty.instantiate(mission, "taskA").error.find("(registered: none)"),
              std::string::npos);
}

TEST(Registry, RefusesDuplicateAndEmptyRegistrationsAndNullComponents) {
    ComponentRegistry registry;
    EXPECT_TRUE(registry.add("producer", make_producer));
    EXPECT_FALSE(registry.add("producer", make_consumer));
    EXPECT_FALSE(registry.add("", make_consumer));
    EXPECT_FALSE(registry.add("nothing", ComponentFactory{}));
    EXPECT_TRUE(registry.add("acca", [] { return ComponentPtr{}; }));
    EXPECT_EQ(registry.size(), 2u);
    EXPECT_EQ(registry.create("missing"), nullptr);
    EXPECT_NE(registry.create("producer"), nullptr);
    const InstantiateResult result = registry.instantiate(two_task_mission(), "acca0");
    EXPECT_EQ(result.error,
              "config/unit.yaml:19: task 'acca0': the factory of component 'acca' returned "
              "nothing");
}

TEST(Registry, MergesAnotherRegistryUnlessANameIsInBoth) {
    ComponentRegistry registry;
    ASSERT_TRUE(registry.add("producer", make_producer));
    ComponentRegistry clashing;
    ASSERT_TRUE(clashing.add("consumer", make_consumer));
    ASSERT_TRUE(clashing.add("producer", make_producer));
    // A name in both: that name, and nothing moves.
    EXPECT_EQ(registry.merge(std::move(clashing)), std::optional<std::string>("producer"));
    EXPECT_EQ(registry.names(), std::vector<std::string>({"producer"}));
    ComponentRegistry other;
    ASSERT_TRUE(other.add("consumer", make_consumer));
    ASSERT_TRUE(other.add("passthrough", make_passthrough));
    EXPECT_EQ(registry.merge(std::move(other)), std::nullopt);
    EXPECT_EQ(registry.names(), std::vector<std::string>({"consumer", "passthrough", "producer"}));
    EXPECT_NE(registry.create("passthrough"), nullptr);
}

TEST(Registry, ComponentDefaultsToTheTaskName) {
    mission::Mission mission = two_task_mission();
    mission.tasks[0].component.clear();
    mission.tasks[0].name = "producer";
    ComponentRegistry registry;
    register_builtin_components(registry);
    const InstantiateResult result = registry.instantiate(mission, "producer");
    ASSERT_TRUE(result.ok()) << result.error;
    EXPECT_EQ(result.instance->spec.component, "producer");
}

}  // namespace
}  // namespace keel::tasking
