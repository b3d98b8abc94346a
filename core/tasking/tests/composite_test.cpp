#include "core/tasking/composite.hpp"

#include <gtest/gtest.h>

#include "core/tasking/builtin.hpp"
#include "core/tasking/executor.hpp"
#include "core/tasking/tests/support.hpp"

namespace keel::tasking {
namespace {

using testing::Script;
using testing::Scripted;

// gen (producer) -> sum (consumer); sum's outputs leave the task.
std::unique_ptr<CompositeComponent> generator_and_adder() {
    auto built = CompositeComponent::Builder()
                     .child("gen", make_producer())
                     .child("sum", make_consumer(), {"x"})
                     .connect("gen", "sum", "x")
                     .expose_output("sum")
                     .control_value_from("gen")
                     .build();
    EXPECT_EQ(built.error, "");
    return std::move(built.composite);
}

ComponentContext context_with(mission::Params params, std::vector<std::string> inputs = {}) {
    ComponentContext context;
    context.task = "pipeline";
    context.port = 50;
    context.inputs = std::move(inputs);
    context.params = std::move(params);
    return context;
}

struct Pass {
    std::vector<Sample> outputs;
    ExecutionResult result;
};

Pass execute(Component& component, Inputs inputs) {
    std::uint64_t sequence = 0;
    Outputs outputs(50, &sequence, 0, 8);
    Pass run;
    run.result = component.execute(inputs, outputs);
    run.outputs = outputs.samples();
    return run;
}

TEST(Composite, ChildrenRunInOrderWithPrefixedParameters) {
    auto composite = generator_and_adder();
    ASSERT_NE(composite, nullptr);
    ASSERT_TRUE(composite->configure(context_with({{"gen.step", std::int64_t{5}}})).succeeded());
    ASSERT_TRUE(composite->activate(std::nullopt).succeeded());
    const std::vector<std::string> none;
    std::int64_t expected_total = 0;
    for (std::int64_t round = 1; round <= 3; ++round) {
        Pass run = execute(*composite, Inputs(&none, Trigger::timer));
        expected_total += 5 * round;
        EXPECT_EQ(run.result.outcome, Outcome::success);
        // The control value comes from `gen`, as declared.
        EXPECT_EQ(run.result.control_value, static_cast<double>(5 * round));
        ASSERT_EQ(run.outputs.size(), 1u);
        EXPECT_EQ(read_counter(run.outputs[0]), expected_total);
        EXPECT_EQ(run.outputs[0].source_port, 50);  // outer port, not the internal one
    }
}

TEST(Composite, SnapshotRoundTripRestoresEveryChild) {
    auto first = generator_and_adder();
    const auto context = context_with({{"gen.step", std::int64_t{5}}});
    ASSERT_TRUE(first->configure(context).succeeded());
    ASSERT_TRUE(first->activate(std::nullopt).succeeded());
    const std::vector<std::string> none;
    for (int round = 0; round < 3; ++round) execute(*first, Inputs(&none, Trigger::timer));
    Snapshot saved = first->deactivate();  // gen at 15, sum at 30
    saved.task = "pipeline";
    EXPECT_EQ(saved.format_version, CompositeComponent::snapshot_format_version);

    auto second = generator_and_adder();
    ASSERT_TRUE(second->configure(context).succeeded());
    ASSERT_TRUE(second->activate(saved).succeeded());
    Pass run = execute(*second, Inputs(&none, Trigger::timer));
    EXPECT_EQ(run.result.control_value, 20.0);
    EXPECT_EQ(read_counter(run.outputs.at(0)), 50);

    Snapshot corrupt = saved;
    corrupt.payload.pop_back();
    auto third = generator_and_adder();
    ASSERT_TRUE(third->configure(context).succeeded());
    EXPECT_EQ(third->activate(corrupt).outcome, Outcome::failure);
}

TEST(Composite, OuterInputsReachChildrenWithoutCopies) {
    auto built = CompositeComponent::Builder()
                     .child("relay", make_passthrough(), {"in"})
                     .child("sum", make_consumer(), {"in"})
                     .expose_input("taskA", "relay", "in")
                     .connect("relay", "sum", "in")
                     .expose_output("relay")
                     .expose_output("sum")
                     .build();
    ASSERT_NE(built.composite, nullptr) << built.error;
    CompositeComponent& composite = *built.composite;
    ASSERT_TRUE(composite.configure(context_with({}, {"taskA"})).succeeded());
    ASSERT_TRUE(composite.activate(std::nullopt).succeeded());

    const std::vector<std::string> names = {"taskA"};
    Inputs inputs(&names, Trigger::inputs);
    Sample sample;
    sample.type_id = counter_type_id;
    sample.source_port = 10;
    sample.payload = make_payload(counter_payload(21));
    inputs.set(0, sample);
    Pass run = execute(composite, std::move(inputs));
    ASSERT_EQ(run.outputs.size(), 2u);
    EXPECT_EQ(run.outputs[0].payload.get(), sample.payload.get());  // relayed, not copied
    EXPECT_EQ(read_counter(run.outputs[1]), 21);
    EXPECT_EQ(run.result.control_value, 21.0);  // the last child that reported one

    // Without the input, the children that need it do not run.
    Pass idle = execute(composite, Inputs(&names, Trigger::timer));
    EXPECT_TRUE(idle.outputs.empty());
}

TEST(Composite, ChildrenOnlyReceiveTypesTheyAccept) {
    auto built = CompositeComponent::Builder()
                     .child("relay", make_passthrough(), {"in"})
                     .child("sum", make_consumer(), {"in"})
                     .expose_input("taskA", "relay", "in")
                     .connect("relay", "sum", "in")
                     .expose_output("relay")
                     .expose_output("sum")
                     .build();
    ASSERT_NE(built.composite, nullptr) << built.error;
    ASSERT_TRUE(built.composite->configure(context_with({}, {"taskA"})).succeeded());
    ASSERT_TRUE(built.composite->activate(std::nullopt).succeeded());
    const std::vector<std::string> names = {"taskA"};
    Inputs inputs(&names, Trigger::inputs);
    inputs.set(0, testing::sample_from(10));  // type 7: the consumer does not take it
    Pass pass = execute(*built.composite, std::move(inputs));
    EXPECT_EQ(pass.result.outcome, Outcome::success);  // sum did not run, so did not fail
    ASSERT_EQ(pass.outputs.size(), 1u);                // only relay's
    EXPECT_EQ(pass.outputs[0].type_id, 7u);
}

TEST(Composite, ChildErrorStopsThePassAndIsTheOutcome) {
    auto script = std::make_shared<Script>();
    script->results.push_back({Outcome::error, 3.0});
    auto built = CompositeComponent::Builder()
                     .child("broken", std::make_unique<Scripted>(script))
                     .child("after", make_producer())
                     .expose_output("after")
                     .build();
    ASSERT_NE(built.composite, nullptr) << built.error;
    ASSERT_TRUE(built.composite->configure(context_with({})).succeeded());
    ASSERT_TRUE(built.composite->activate(std::nullopt).succeeded());
    const std::vector<std::string> none;
    Pass run = execute(*built.composite, Inputs(&none, Trigger::event));
    EXPECT_EQ(run.result.outcome, Outcome::error);
    EXPECT_TRUE(run.outputs.empty());
    EXPECT_EQ(script->triggers, std::vector<Trigger>{Trigger::event});
}

TEST(Composite, FailedChildActivationUndoesTheOthers) {
    auto first = std::make_shared<Script>();
    auto second = std::make_shared<Script>();
    second->activate_result = LifecycleResult::failed("no camera");
    auto built = CompositeComponent::Builder()
                     .child("a", std::make_unique<Scripted>(first))
                     .child("b", std::make_unique<Scripted>(second))
                     .expose_output("b")
                     .build();
    ASSERT_NE(built.composite, nullptr);
    ASSERT_TRUE(built.composite->configure(context_with({})).succeeded());
    const LifecycleResult result = built.composite->activate(std::nullopt);
    EXPECT_EQ(result.outcome, Outcome::failure);
    EXPECT_EQ(result.message, "child 'b': no camera");
    EXPECT_EQ(first->calls, (std::vector<std::string>{"configure", "activate", "deactivate"}));
}

TEST(Composite, BuildRejectsBadWiring) {
    auto error_of = [](CompositeComponent::Builder builder) { return builder.build().error; };
    EXPECT_NE(error_of(CompositeComponent::Builder()), "");
    EXPECT_NE(error_of(std::move(CompositeComponent::Builder()
                                     .child("a", make_producer())
                                     .child("a", make_producer())
                                     .expose_output("a"))),
              "");
    // Backwards connection: children run in order.
    EXPECT_NE(error_of(std::move(CompositeComponent::Builder()
                                     .child("sum", make_consumer(), {"x"})
                                     .child("gen", make_producer())
                                     .connect("gen", "sum", "x")
                                     .expose_output("sum")))
                  .find("backwards"),
              std::string::npos);
    // An input fed by nothing.
    EXPECT_NE(error_of(std::move(CompositeComponent::Builder()
                                     .child("sum", make_consumer(), {"x"})
                                     .expose_output("sum")))
                  .find("fed 0 times"),
              std::string::npos);
    // An input fed twice.
    EXPECT_NE(error_of(std::move(CompositeComponent::Builder()
                                     .child("gen", make_producer())
                                     .child("sum", make_consumer(), {"x"})
                                     .connect("gen", "sum", "x")
                                     .expose_input("outer", "sum", "x")
                                     .expose_output("sum")))
                  .find("fed 2 times"),
              std::string::npos);
    EXPECT_NE(error_of(std::move(CompositeComponent::Builder()
                                     .child("gen", make_producer())
                                     .connect("gen", "nobody", "x")
                                     .expose_output("gen"))),
              "");
    EXPECT_NE(error_of(std::move(CompositeComponent::Builder().child("gen", make_producer()))), "");
}

TEST(Composite, ConfigureChecksTheTaskInputsAgainstTheExposedOnes) {
    auto make = [] {
        return std::move(CompositeComponent::Builder()
                             .child("relay", make_passthrough(), {"in"})
                             .expose_input("taskA", "relay", "in")
                             .expose_output("relay")
                             .build()
                             .composite);
    };
    EXPECT_EQ(make()->configure(context_with({}, {})).outcome, Outcome::error);
    EXPECT_EQ(make()->configure(context_with({}, {"taskA", "taskZ"})).outcome, Outcome::error);
    EXPECT_TRUE(make()->configure(context_with({}, {"taskA"})).succeeded());
}

}  // namespace
}  // namespace keel::tasking

namespace keel::tasking {
namespace {

// A composite registered like any component, instantiated from a mission and driven by the
// executor: taskA (producer) -> pipeline{relay -> sum}.
TEST(Composite, RunsAsAMissionTaskInTheExecutor) {
    ComponentRegistry registry;
    ASSERT_TRUE(register_builtin_components(registry));
    ASSERT_TRUE(registry.add("pipeline", [&registry]() -> ComponentPtr {
        return std::move(CompositeComponent::Builder()
                             .child("relay", registry.create("passthrough"), {"in"})
                             .child("sum", registry.create("consumer"), {"in"})
                             .expose_input("taskA", "relay", "in")
                             .connect("relay", "sum", "in")
                             .expose_output("sum")
                             .build()
                             .composite);
    }));
    mission::Mission mission;
    mission.path = "composite.yaml";
    mission.tasks = {testing::make_task("taskA", 100, "producer", {}, 10),
                     testing::make_task("taskP", 200, "pipeline", {"taskA"}),
                     testing::make_task("taskC", 300, "consumer", {"taskP"})};
    mission.tasks[1].checkpoint = true;
    ManualClock clock;
    Executor executor(clock);
    for (InstantiateResult& instance : registry.instantiate_all(mission, "")) {
        ASSERT_TRUE(instance.ok()) << instance.error;
        const auto added = executor.add(std::move(*instance.instance));
        ASSERT_TRUE(added.id) << added.result.message;
        ASSERT_TRUE(executor.activate(*added.id).succeeded());
    }
    for (int period = 0; period < 4; ++period) {
        EXPECT_EQ(executor.run_ready(), 3u);
        clock.advance_ms(10);
    }
    // The pipeline sums 1..4 = 10 and the downstream consumer sees each running total.
    const TaskId pipeline = *executor.find("taskP");
    const TaskId downstream = *executor.find("taskC");
    EXPECT_EQ(executor.stats(pipeline).last_control_value, 4.0);
    EXPECT_EQ(executor.stats(downstream).last_control_value, 10.0);
    const std::vector<Snapshot> checkpoints = executor.take_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].task, "taskP");
    EXPECT_EQ(checkpoints[0].format_version, CompositeComponent::snapshot_format_version);
}

}  // namespace
}  // namespace keel::tasking
