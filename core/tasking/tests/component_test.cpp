#include "core/tasking/component.hpp"

#include <gtest/gtest.h>

#include "core/tasking/builtin.hpp"

namespace keel::tasking {
namespace {

TEST(Outcome, WorstOrdersErrorAboveFailureAboveSuccess) {
    EXPECT_EQ(worst(Outcome::success, Outcome::success), Outcome::success);
    EXPECT_EQ(worst(Outcome::success, Outcome::failure), Outcome::failure);
    EXPECT_EQ(worst(Outcome::error, Outcome::failure), Outcome::error);
    EXPECT_EQ(worst(Outcome::failure, Outcome::error), Outcome::error);
    EXPECT_EQ(to_string(Outcome::failure), "failure");
}

TEST(ComponentContext, LaterParametersWinAndTypesAreChecked) {
    ComponentContext context;
    context.params = {{"gain", std::int64_t{2}},
                      {"mode", std::string("fast")},
                      {"gain", std::int64_t{5}},  // a phase parameter overriding the task's
                      {"ratio", 0.5},
                      {"on", true}};
    EXPECT_EQ(context.int_param("gain", 0), 5);
    EXPECT_EQ(context.int_param("missing", 9), 9);
    EXPECT_EQ(context.int_param("mode", 0), std::nullopt);
    EXPECT_EQ(context.double_param("ratio", 0.0), 0.5);
    EXPECT_EQ(context.double_param("gain", 0.0), 5.0);  // integers serve as doubles
    EXPECT_EQ(context.string_param("mode", ""), "fast");
    EXPECT_EQ(context.string_param("on", ""), std::nullopt);
    EXPECT_EQ(context.bool_param("on", false), true);
    EXPECT_EQ(context.bool_param("ratio", false), std::nullopt);
}

TEST(Outputs, StampsSamplesAndDropsBeyondCapacity) {
    std::uint64_t sequence = 10;
    Outputs outputs(42, &sequence, 1234, 2);
    outputs.emit(3, std::vector<std::uint8_t>{1});
    outputs.emit(3, std::vector<std::uint8_t>{2});
    outputs.emit(3, std::vector<std::uint8_t>{3});
    ASSERT_EQ(outputs.samples().size(), 2u);
    EXPECT_EQ(outputs.dropped(), 1u);
    EXPECT_EQ(outputs.samples()[0].sequence, 11u);
    EXPECT_EQ(outputs.samples()[1].sequence, 12u);
    EXPECT_EQ(outputs.samples()[1].source_port, 42);
    EXPECT_EQ(outputs.samples()[1].timestamp_ns, 1234);
    EXPECT_EQ(sequence, 12u);
}

TEST(Inputs, LooksUpByNameAndIndex) {
    const std::vector<std::string> names = {"camera", "clock"};
    Inputs inputs(&names, Trigger::timer);
    Sample sample;
    sample.source_port = 10;
    inputs.set(1, sample);
    EXPECT_EQ(inputs.get("camera"), nullptr);
    ASSERT_NE(inputs.get("clock"), nullptr);
    EXPECT_EQ(inputs.get("clock")->source_port, 10);
    EXPECT_EQ(inputs.get("nothing"), nullptr);
    EXPECT_EQ(inputs.present(), 1u);
    EXPECT_EQ(inputs.name(0), "camera");
    EXPECT_EQ(inputs.trigger(), Trigger::timer);
}

TEST(Builtin, ProducerCountsAndRestoresFromSnapshot) {
    ComponentPtr producer = make_producer();
    ComponentContext context;
    context.task = "taskA";
    context.params = {{"start", std::int64_t{100}}, {"step", std::int64_t{3}}};
    ASSERT_TRUE(producer->configure(context).succeeded());
    ASSERT_TRUE(producer->activate(std::nullopt).succeeded());
    const std::vector<std::string> no_inputs;
    std::uint64_t sequence = 0;
    Outputs outputs(100, &sequence, 0, 4);
    const ExecutionResult first = producer->execute(Inputs(&no_inputs, Trigger::timer), outputs);
    EXPECT_EQ(first.control_value, 103.0);
    const ExecutionResult second = producer->execute(Inputs(&no_inputs, Trigger::timer), outputs);
    EXPECT_EQ(second.control_value, 106.0);
    ASSERT_EQ(outputs.samples().size(), 2u);
    EXPECT_EQ(read_counter(outputs.samples()[1]), 106);

    const Snapshot saved = producer->deactivate();
    ComponentPtr restored = make_producer();
    ASSERT_TRUE(restored->configure(context).succeeded());
    ASSERT_TRUE(restored->activate(saved).succeeded());
    const ExecutionResult third = restored->execute(Inputs(&no_inputs, Trigger::timer), outputs);
    EXPECT_EQ(third.control_value, 109.0);
}

TEST(Builtin, ProducerRejectsBadParametersAndCorruptSnapshots) {
    ComponentPtr producer = make_producer();
    ComponentContext context;
    context.params = {{"step", std::string("one")}};
    EXPECT_EQ(producer->configure(context).outcome, Outcome::failure);
    context.params = {{"payload_bytes", std::int64_t{4}}};
    EXPECT_EQ(producer->configure(context).outcome, Outcome::failure);
    context.params = {};
    ASSERT_TRUE(producer->configure(context).succeeded());
    Snapshot corrupt;
    corrupt.payload = {1, 2, 3};
    EXPECT_EQ(producer->activate(corrupt).outcome, Outcome::failure);
    Snapshot future;
    future.format_version = 2;
    future.payload = std::vector<std::uint8_t>(8, 0);
    EXPECT_EQ(producer->activate(future).outcome, Outcome::failure);
}

TEST(Builtin, ConsumerAddsAndFailsOnForeignSamples) {
    ComponentPtr consumer = make_consumer();
    ComponentContext context;
    context.task = "taskB";
    context.inputs = {"taskA"};
    ASSERT_TRUE(consumer->configure(context).succeeded());
    ASSERT_TRUE(consumer->activate(std::nullopt).succeeded());
    const std::vector<std::string> names = {"taskA"};
    std::uint64_t sequence = 0;
    Outputs outputs(101, &sequence, 0, 4);
    for (std::int64_t value : {5, 7}) {
        Inputs inputs(&names, Trigger::inputs);
        Sample sample;
        sample.type_id = counter_type_id;
        sample.payload = make_payload(counter_payload(value));
        inputs.set(0, sample);
        EXPECT_EQ(consumer->execute(inputs, outputs).control_value, static_cast<double>(value));
    }
    ASSERT_EQ(outputs.samples().size(), 2u);
    EXPECT_EQ(read_counter(outputs.samples()[1]), 12);

    Inputs foreign(&names, Trigger::inputs);
    Sample sample;
    sample.type_id = 99;
    sample.payload = make_payload({1});
    foreign.set(0, sample);
    EXPECT_EQ(consumer->execute(foreign, outputs).outcome, Outcome::failure);

    const Snapshot saved = consumer->snapshot();
    ComponentPtr restored = make_consumer();
    ASSERT_TRUE(restored->configure(context).succeeded());
    ASSERT_TRUE(restored->activate(saved).succeeded());
    EXPECT_EQ(restored->snapshot(), saved);
}

TEST(Builtin, ConsumerNeedsAnInput) {
    ComponentPtr consumer = make_consumer();
    ComponentContext context;
    context.task = "lonely";
    EXPECT_EQ(consumer->configure(context).outcome, Outcome::failure);
}

TEST(Builtin, RegistersItsThreeComponentsOnce) {
    ComponentRegistry registry;
    EXPECT_TRUE(register_builtin_components(registry));
    EXPECT_EQ(registry.names(), (std::vector<std::string>{"consumer", "passthrough", "producer"}));
    EXPECT_FALSE(register_builtin_components(registry));
}

}  // namespace
}  // namespace keel::tasking
