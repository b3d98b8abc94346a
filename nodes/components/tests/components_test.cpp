// The earth-observation components driven directly through the Component interface, with
// small scenes: the chain sensor -> two ACCA workers -> sink -> sensor, the split of the
// stream, the resend of scenes the sink did not record, and the AOCS restore.
#include "keel/eo/components.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <thread>

#include "core/tasking/bytes.hpp"
#include "keel/eo/codec.hpp"
#include "keel/eo/sensor.hpp"

namespace keel::eo::components {
namespace {

using tasking::ComponentContext;
using tasking::Inputs;
using tasking::Outputs;
using tasking::Sample;
using tasking::Trigger;

constexpr std::int64_t kMs = 1'000'000;

// Files the components write without an out_dir parameter go to a scratch directory,
// never into the source tree the tests run in.
class ScratchOutput : public ::testing::Environment {
  public:
    void SetUp() override {
        const auto dir = std::filesystem::temp_directory_path() /
                         ("keel-eo-components-" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir);
        ::setenv("KEEL_EO_OUT_DIR", dir.c_str(), 1);
    }
};
const auto* const scratch_output = ::testing::AddGlobalTestEnvironment(new ScratchOutput);

std::filesystem::path fresh_dir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("keel-eo-components-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

ComponentContext context(const std::string& task, std::vector<std::string> inputs,
                         mission::Params params) {
    ComponentContext ctx;
    ctx.task = task;
    ctx.component = task;
    ctx.inputs = std::move(inputs);
    ctx.params = std::move(params);
    return ctx;
}

std::vector<std::string> read_lines(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

// Runs one execution and returns what it emitted.
std::vector<Sample> run(tasking::Component& component, const std::vector<std::string>& names,
                        Trigger trigger, const std::vector<Sample>& samples, std::int64_t now_ns,
                        tasking::ExecutionResult* result = nullptr) {
    Inputs inputs(&names, trigger);
    for (std::size_t i = 0; i < samples.size() && i < names.size(); ++i) inputs.set(i, samples[i]);
    static std::uint64_t sequence = 0;
    Outputs outputs(1, &sequence, now_ns, 64);
    const tasking::ExecutionResult outcome = component.execute(inputs, outputs);
    if (result != nullptr) *result = outcome;
    return outputs.samples();
}

// Executes the sensor on its timer until its background pool has a scene.
Sample first_scene(tasking::Component& sensor, std::int64_t& now_ns) {
    const std::vector<std::string> names = {"sink"};
    for (int attempt = 0; attempt < 2000; ++attempt) {
        now_ns += 100 * kMs;
        auto out = run(sensor, names, Trigger::timer, {}, now_ns);
        if (!out.empty()) return out.front();
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ADD_FAILURE() << "the sensor emitted nothing";
    return {};
}

// The first scene of a fresh sensor configured for `size_px` square scenes.
Sample scene_of_size(std::int64_t size_px) {
    auto sensor = make_sensor_component();
    EXPECT_TRUE(sensor
                    ->configure(context("camera", {"sink"},
                                        {{"scene_size_px", size_px}, {"pool_size", std::int64_t{1}}}))
                    .succeeded());
    EXPECT_TRUE(sensor->activate(std::nullopt).succeeded());
    std::int64_t now_ns = 0;
    return first_scene(*sensor, now_ns);
}

// A cloud classifier configured for the camera and activated.
tasking::ComponentPtr active_acca() {
    auto acca = make_acca_component();
    EXPECT_TRUE(acca->configure(context("acca0", {"camera"}, {})).succeeded());
    EXPECT_TRUE(acca->activate(std::nullopt).succeeded());
    return acca;
}

TEST(EoComponentMessages, RestampedSceneDecodesWithTheNewSequence) {
    sensor::SceneSpec spec;
    spec.width_px = spec.height_px = 64;
    const Scene scene = sensor::generate_scene(5, 0, spec);
    const std::vector<std::uint8_t> bytes = serialise(scene);
    const std::vector<std::uint8_t> restamped = restamp_scene(bytes, 77, scene_body_crc(bytes));
    const Scene decoded = deserialise_scene(restamped);
    EXPECT_EQ(decoded.sequence, 77u);
    EXPECT_EQ(peek_scene_sequence(restamped), 77u);
    Scene expected = scene;
    expected.sequence = 77;
    EXPECT_EQ(serialise(expected), restamped);
    EXPECT_FALSE(peek_scene_sequence(std::vector<std::uint8_t>(10, 0)).has_value());
}

TEST(EoComponentMessages, AccountingRoundTripsAndRejectsCorruption) {
    Accounting accounting{12, 15, 1, {14, 15, 17}};
    const auto bytes = serialise(accounting);
    const Accounting decoded = deserialise_accounting(bytes);
    EXPECT_EQ(decoded.watermark, 12u);
    EXPECT_EQ(decoded.recorded_above, (std::vector<std::uint64_t>{14, 15, 17}));
    EXPECT_TRUE(decoded.covers(3));
    EXPECT_TRUE(decoded.covers(17));
    EXPECT_FALSE(decoded.covers(13));
    auto corrupt = bytes;
    corrupt[10] ^= 1;
    EXPECT_THROW(deserialise_accounting(corrupt), DecodeError);
    EXPECT_THROW(deserialise_accounting(std::vector<std::uint8_t>(3, 0)), DecodeError);
}

TEST(EoComponentRegistry, RegisteredUnderTheMissionsNames) {
    tasking::ComponentRegistry registry;
    ASSERT_TRUE(register_eo_components(registry));
    EXPECT_EQ(registry.names(),
              (std::vector<std::string>{"acca", "aocs", "downlink", "sensor", "sink"}));
    EXPECT_FALSE(register_eo_components(registry));
}

TEST(EoComponentRegistry, ConfigurationErrorsAreFailuresWithReasons) {
    auto sensor = make_sensor_component();
    auto bad = sensor->configure(context("camera", {}, {{"scene_size_px", std::int64_t{4}}}));
    EXPECT_EQ(bad.outcome, tasking::Outcome::failure);
    EXPECT_NE(bad.message.find("scene_size_px"), std::string::npos);
    auto acca = make_acca_component();
    bad = acca->configure(
        context("acca0", {"camera"},
                {{"worker_index", std::int64_t{2}}, {"worker_count", std::int64_t{2}}}));
    EXPECT_EQ(bad.outcome, tasking::Outcome::failure);
    EXPECT_NE(bad.message.find("worker_index"), std::string::npos);
}

// The chain with two workers; scenes of one parity are lost on the way to their worker
// (its node failed) until the sensor's resend reaches the worker that took over.
TEST(EoComponentChain, EveryImageRecordedOnceAcrossALostWorker) {
    const auto dir = fresh_dir("chain");
    auto sensor = make_sensor_component();
    ASSERT_TRUE(sensor
                    ->configure(context("camera", {"sink"},
                                        {{"scene_size_px", std::int64_t{64}},
                                         {"pool_size", std::int64_t{3}},
                                         {"resend_after_ms", std::int64_t{500}}}))
                    .succeeded());
    ASSERT_TRUE(sensor->activate(std::nullopt).succeeded());
    std::vector<tasking::ComponentPtr> workers;
    for (std::int64_t index = 0; index < 2; ++index) {
        workers.push_back(make_acca_component());
        ASSERT_TRUE(
            workers.back()
                ->configure(context("acca" + std::to_string(index), {"camera"},
                                    {{"worker_index", index}, {"worker_count", std::int64_t{2}}}))
                .succeeded());
        ASSERT_TRUE(workers.back()->activate(std::nullopt).succeeded());
    }
    auto sink = make_sink_component();
    ASSERT_TRUE(sink->configure(context("sink", {"acca0", "acca1"}, {{"out_dir", dir.string()}}))
                    .succeeded());
    ASSERT_TRUE(sink->activate(std::nullopt).succeeded());

    const std::vector<std::string> camera_input = {"camera"};
    const std::vector<std::string> sink_inputs = {"acca0", "acca1"};
    const std::vector<std::string> sensor_inputs = {"sink"};
    std::int64_t now_ns = 0;
    std::vector<Sample> scenes = {first_scene(*sensor, now_ns)};
    bool worker1_dead = false;
    std::map<std::uint64_t, int> classified_by_sequence;
    for (int period = 0; period < 40; ++period) {
        // Worker 1's node fails at period 10; a new instance takes over at period 20.
        if (period == 10) worker1_dead = true;
        if (period == 20) {
            workers[1] = make_acca_component();
            ASSERT_TRUE(workers[1]
                            ->configure(context("acca1", {"camera"},
                                                {{"worker_index", std::int64_t{1}},
                                                 {"worker_count", std::int64_t{2}}}))
                            .succeeded());
            ASSERT_TRUE(workers[1]->activate(std::nullopt).succeeded());
            worker1_dead = false;
        }
        std::vector<Sample> results;
        for (const Sample& scene : scenes) {
            for (std::size_t w = 0; w < 2; ++w) {
                if (w == 1 && worker1_dead) continue;
                for (Sample& out :
                     run(*workers[w], camera_input, Trigger::inputs, {scene}, now_ns)) {
                    const ClassifiedImage image = deserialise_classified(*out.payload);
                    EXPECT_EQ(image.sequence % 2, w);
                    if (!image.resent) ++classified_by_sequence[image.sequence];
                    results.push_back(out);
                }
            }
        }
        std::vector<Sample> accounting;
        for (const Sample& result : results) {
            for (Sample& out : run(*sink, sink_inputs, Trigger::timer, {result}, now_ns))
                accounting.push_back(out);
        }
        now_ns += 100 * kMs;
        scenes.clear();
        for (const Sample& ack : accounting) {
            for (Sample& out : run(*sensor, sensor_inputs, Trigger::inputs, {ack}, now_ns))
                scenes.push_back(out);
        }
        for (Sample& out : run(*sensor, sensor_inputs, Trigger::timer, {}, now_ns))
            scenes.push_back(out);
    }
    const auto stats = read_lines(dir / "stats.ndjson");
    std::set<std::uint64_t> recorded;
    for (const std::string& line : stats) {
        const auto at = line.find("\"sequence\":") + 11;
        recorded.insert(std::stoull(line.substr(at)));
    }
    EXPECT_EQ(recorded.size(), stats.size()) << "an image was recorded twice";
    ASSERT_GE(recorded.size(), 30u);
    EXPECT_EQ(*recorded.begin(), 1u);
    EXPECT_EQ(*recorded.rbegin(), recorded.size()) << "a gap in the recorded sequence numbers";
    for (const auto& [sequence, count] : classified_by_sequence) {
        EXPECT_EQ(count, 1) << "image " << sequence << " classified " << count << " times";
    }
    EXPECT_TRUE(std::filesystem::exists(dir / "overlay-1.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "scene-1.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "mask-1.png"));
    EXPECT_NE(stats.front().find("\"accuracy\":"), std::string::npos);
    EXPECT_NE(stats.front().find("\"worker\":\"acca1\""), std::string::npos);
}

TEST(EoComponentAcca, SendsItsCachedResultForAResentSceneInsteadOfClassifyingAgain) {
    const Sample scene = scene_of_size(48);
    auto acca = active_acca();
    const std::vector<std::string> names = {"camera"};
    tasking::ExecutionResult result;
    const auto first = run(*acca, names, Trigger::inputs, {scene}, 0, &result);
    const auto second = run(*acca, names, Trigger::inputs, {scene}, 0);
    ASSERT_EQ(first.size(), 1u);
    ASSERT_EQ(second.size(), 1u);
    const ClassifiedImage a = deserialise_classified(*first[0].payload);
    const ClassifiedImage b = deserialise_classified(*second[0].payload);
    EXPECT_FALSE(a.resent);
    EXPECT_TRUE(b.resent);
    EXPECT_EQ(a.sequence, b.sequence);
    ASSERT_TRUE(a.versus_truth.has_value());
    EXPECT_GT(a.versus_truth->accuracy(), 0.5);
    ASSERT_TRUE(result.control_value.has_value());
    EXPECT_DOUBLE_EQ(*result.control_value, a.result.cloud_fraction);
    const tasking::Snapshot state = acca->snapshot();
    tasking::ByteReader reader(state.payload);
    EXPECT_EQ(reader.u64(), 1u) << "classified once";
}

TEST(EoComponentSink, CountsADuplicateAndKeepsTheFirstResult) {
    const auto dir = fresh_dir("sink");
    const Sample scene = scene_of_size(32);
    auto acca = active_acca();
    const std::vector<std::string> names = {"camera"};
    const Sample result = run(*acca, names, Trigger::inputs, {scene}, 0).at(0);
    auto sink = make_sink_component();
    ASSERT_TRUE(
        sink->configure(context("sink", {"acca0"}, {{"out_dir", dir.string()}})).succeeded());
    ASSERT_TRUE(sink->activate(std::nullopt).succeeded());
    const std::vector<std::string> sink_names = {"acca0"};
    const auto ack1 = run(*sink, sink_names, Trigger::inputs, {result}, 0);
    const auto ack2 = run(*sink, sink_names, Trigger::inputs, {result}, 0);
    ASSERT_EQ(ack2.size(), 1u);
    const Accounting accounting = deserialise_accounting(*ack2[0].payload);
    EXPECT_EQ(accounting.watermark, 1u);
    EXPECT_EQ(accounting.recorded, 1u);
    EXPECT_EQ(accounting.duplicates, 1u);
    EXPECT_EQ(read_lines(dir / "stats.ndjson").size(), 1u);
    const auto duplicates = read_lines(dir / "duplicates.ndjson");
    ASSERT_EQ(duplicates.size(), 1u);
    EXPECT_NE(duplicates[0].find("classified-again"), std::string::npos);
}

TEST(EoComponentSensor, ResendsOnlyWhatTheSinkHasNotRecorded) {
    auto sensor = make_sensor_component();
    ASSERT_TRUE(sensor
                    ->configure(context("camera", {"sink"},
                                        {{"scene_size_px", std::int64_t{32}},
                                         {"pool_size", std::int64_t{2}},
                                         {"resend_after_ms", std::int64_t{300}}}))
                    .succeeded());
    ASSERT_TRUE(sensor->activate(std::nullopt).succeeded());
    std::int64_t now_ns = 0;
    first_scene(*sensor, now_ns);  // sequence 1
    const std::vector<std::string> names = {"sink"};
    now_ns += 100 * kMs;
    ASSERT_EQ(run(*sensor, names, Trigger::timer, {}, now_ns).size(), 1u);  // sequence 2
    Sample ack;
    ack.type_id = accounting_type_id;
    ack.payload = tasking::make_payload(serialise(Accounting{1, 1, 0, {}}));
    EXPECT_TRUE(run(*sensor, names, Trigger::inputs, {ack}, now_ns).empty());
    now_ns += 400 * kMs;
    const auto resent = run(*sensor, names, Trigger::inputs, {ack}, now_ns);
    ASSERT_EQ(resent.size(), 1u);
    EXPECT_EQ(peek_scene_sequence(*resent[0].payload), 2u);
}

TEST(EoComponentAocs, ARestoredInstanceReplaysOntoTheSameTrajectory) {
    const auto dir = fresh_dir("aocs");
    const mission::Params params = {{"out_dir", dir.string()}, {"seed", std::int64_t{3}}};
    auto first = make_aocs_component();
    ASSERT_TRUE(first->configure(context("aocs", {}, params)).succeeded());
    ASSERT_TRUE(first->activate(std::nullopt).succeeded());
    const std::vector<std::string> none;
    tasking::ExecutionResult result;
    for (int i = 0; i < 3; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(60));
        run(*first, none, Trigger::timer, {}, 0, &result);
    }
    ASSERT_TRUE(result.control_value.has_value());
    EXPECT_LT(*result.control_value, 0.1);
    tasking::Snapshot checkpoint = first->snapshot();
    checkpoint.task = "aocs";
    std::this_thread::sleep_for(std::chrono::milliseconds(80));
    run(*first, none, Trigger::timer, {}, 0);  // the original goes on past the checkpoint
    first->deactivate();
    auto second = make_aocs_component();
    ASSERT_TRUE(second->configure(context("aocs", {}, params)).succeeded());
    ASSERT_TRUE(second->activate(checkpoint).succeeded());
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    run(*second, none, Trigger::timer, {}, 0);
    second->deactivate();
    // Steps both instances computed must agree exactly.
    std::map<std::uint64_t, std::string> original;
    std::size_t compared = 0;
    std::size_t replayed = 0;
    for (const std::string& line : read_lines(dir / "aocs.ndjson")) {
        const auto step = std::stoull(line.substr(line.find("\"step\":") + 7));
        const auto error_at = line.find("\"error_rad\":");
        const std::string error = line.substr(error_at, line.find(',', error_at) - error_at);
        const bool restored = line.find("\"restored\":true") != std::string::npos;
        if (!restored) {
            original[step] = error;
            continue;
        }
        if (line.find("\"mode\":\"replay\"") != std::string::npos) ++replayed;
        if (original.contains(step)) {
            EXPECT_EQ(original[step], error) << "step " << step;
            ++compared;
        }
    }
    EXPECT_GT(compared, 3u);
    EXPECT_GT(replayed, 3u);
}

TEST(EoComponentAocs, RejectsASnapshotOfAnotherSeed) {
    const auto dir = fresh_dir("aocs-seed");
    auto first = make_aocs_component();
    ASSERT_TRUE(
        first
            ->configure(context("aocs", {}, {{"out_dir", dir.string()}, {"seed", std::int64_t{3}}}))
            .succeeded());
    ASSERT_TRUE(first->activate(std::nullopt).succeeded());
    auto second = make_aocs_component();
    ASSERT_TRUE(
        second
            ->configure(context("aocs", {}, {{"out_dir", dir.string()}, {"seed", std::int64_t{4}}}))
            .succeeded());
    EXPECT_EQ(second->activate(first->snapshot()).outcome, tasking::Outcome::failure);
}

// Deactivation stops the scene generator without waiting for the scene under way (the
// node's loop must keep its heartbeats going); that scene is dropped, so a camera activated
// again at once still streams the pool from its first scene, once each.
TEST(EoComponentSensor, ADeactivationDuringGenerationLeavesThePoolInOrder) {
    const Sample expected = scene_of_size(512);
    auto sensor = make_sensor_component();
    ASSERT_TRUE(sensor
                    ->configure(context("camera", {"sink"},
                                        {{"scene_size_px", std::int64_t{512}}, {"pool_size", std::int64_t{2}}}))
                    .succeeded());
    for (int round = 0; round < 3; ++round) {
        ASSERT_TRUE(sensor->activate(std::nullopt).succeeded());
        sensor->deactivate();  // the first scene is most likely still under way
    }
    ASSERT_TRUE(sensor->activate(std::nullopt).succeeded());
    std::int64_t now_ns = 0;
    const Sample first = first_scene(*sensor, now_ns);
    ASSERT_TRUE(first.payload && expected.payload);
    const Scene a = deserialise_scene(*first.payload);
    const Scene b = deserialise_scene(*expected.payload);
    EXPECT_EQ(a.seed, b.seed);  // scene 0 of the pool, not a late one of a stopped generator
    EXPECT_EQ(a.sequence, b.sequence);
}

}  // namespace
}  // namespace keel::eo::components
