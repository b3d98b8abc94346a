#include "keel/eo/sink.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "keel/eo/sensor.hpp"

namespace keel::eo::sink {
namespace {
namespace fs = std::filesystem;

fs::path temp_folder(const std::string& name) {
    const auto path =
        fs::temp_directory_path() / ("keel-sink-test-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(path);
    return path;
}

Scene small_scene(std::uint64_t seed, std::uint64_t sequence) {
    sensor::SceneSpec spec;
    spec.width_px = spec.height_px = 64;
    return sensor::generate_scene(seed, sequence, spec);
}

std::vector<std::string> lines_of(const fs::path& path) {
    std::ifstream in(path);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

TEST(SinkCompareMasks, CountsEachCell) {
    const cv::Mat predicted = (cv::Mat_<std::uint8_t>(1, 6) << 255, 255, 0, 0, 0, 255);
    const cv::Mat truth = (cv::Mat_<std::uint8_t>(1, 6) << 255, 0, 255, 0, 0, 255);
    const Confusion c = compare_masks(predicted, truth);
    EXPECT_EQ(c.true_positive, 2U);
    EXPECT_EQ(c.false_positive, 1U);
    EXPECT_EQ(c.false_negative, 1U);
    EXPECT_EQ(c.true_negative, 2U);
    EXPECT_DOUBLE_EQ(c.accuracy(), 4.0 / 6.0);
    EXPECT_DOUBLE_EQ(c.precision(), 2.0 / 3.0);
    EXPECT_DOUBLE_EQ(c.recall(), 2.0 / 3.0);
    EXPECT_THROW(compare_masks(predicted, cv::Mat(1, 5, CV_8UC1)), std::invalid_argument);
}

TEST(SinkCompareMasks, ClearSceneClassifiedClearIsPerfect) {
    const cv::Mat none = cv::Mat::zeros(4, 4, CV_8UC1);
    const Confusion c = compare_masks(none, none);
    EXPECT_DOUBLE_EQ(c.accuracy(), 1.0);
    EXPECT_DOUBLE_EQ(c.precision(), 1.0);
    EXPECT_DOUBLE_EQ(c.recall(), 1.0);
}

TEST(SinkOverlay, TintsAgreementFalseAlarmsAndMisses) {
    Scene scene;
    scene.bands = cv::Mat(1, 4, CV_8UC4, cv::Scalar(10, 20, 30, 40));
    const cv::Mat mask = (cv::Mat_<std::uint8_t>(1, 4) << 255, 255, 0, 0);
    const cv::Mat truth = (cv::Mat_<std::uint8_t>(1, 4) << 255, 0, 255, 0);
    const cv::Mat overlay = make_overlay(scene, mask, &truth);
    ASSERT_EQ(overlay.type(), CV_8UC3);
    EXPECT_EQ(overlay.at<cv::Vec3b>(0, 3),
              cv::Vec3b(10, 20, 30));  // clear: band 2, 3, 4 as B, G, R
    EXPECT_EQ(overlay.at<cv::Vec3b>(0, 0),
              cv::Vec3b(132, 138, 15));  // cyan: agreement (OpenCV rounds half to even)
    EXPECT_EQ(overlay.at<cv::Vec3b>(0, 1), cv::Vec3b(5, 138, 142));   // yellow: false alarm
    EXPECT_EQ(overlay.at<cv::Vec3b>(0, 2), cv::Vec3b(132, 10, 142));  // magenta: missed
    const cv::Mat plain = make_overlay(scene, mask);
    EXPECT_EQ(plain.at<cv::Vec3b>(0, 1), cv::Vec3b(132, 138, 15));
    EXPECT_EQ(
        make_overlay(small_scene(1, 0), cv::Mat::zeros(64, 64, CV_8UC1), nullptr, 0.25).size(),
        cv::Size(16, 16));
}

TEST(SinkRecorder, WritesOverlayAndAStatsLinePerImage) {
    const auto dir = temp_folder("write");
    const Scene scene = small_scene(3, 7);
    const acca::Result result = acca::classify(scene);
    {
        Sink sink(SinkConfig{.out_dir = dir});
        const ImageStats stats = sink.consume(scene, result);
        ASSERT_TRUE(stats.versus_truth.has_value());
        EXPECT_EQ(stats.versus_truth->total(), 64U * 64U);
        EXPECT_EQ(sink.images_recorded(), 1U);
    }
    EXPECT_FALSE(cv::imread((dir / "overlay-7.png").string()).empty());
    const auto lines = lines_of(dir / "stats.ndjson");
    ASSERT_EQ(lines.size(), 1U);
    EXPECT_EQ(lines[0].front(), '{');
    EXPECT_EQ(lines[0].back(), '}');
    for (const char* key : {"\"sequence\":7", "\"accuracy\":", "\"precision\":", "\"recall\":",
                            "\"too_cloudy\":", "\"compute_ms\":", "\"cloud_fraction\":"}) {
        EXPECT_NE(lines[0].find(key), std::string::npos) << key << " in " << lines[0];
    }
    fs::remove_all(dir);
}

TEST(SinkRecorder, PairsScenesAndResultsArrivingInAnyOrder) {
    const auto dir = temp_folder("pair");
    Sink sink(SinkConfig{.out_dir = dir, .write_overlays = false, .pending_max = 2});
    const Scene s0 = small_scene(1, 0);
    const Scene s1 = small_scene(2, 1);
    EXPECT_FALSE(sink.offer_result(acca::classify(s1)).has_value());
    EXPECT_FALSE(sink.offer_scene(s0).has_value());
    const auto first = sink.offer_scene(s1);
    ASSERT_TRUE(first.has_value());
    EXPECT_EQ(first->sequence, 1U);
    const auto second = sink.offer_result(acca::classify(s0));
    ASSERT_TRUE(second.has_value());
    EXPECT_EQ(second->sequence, 0U);
    // Three scenes without results: the oldest is dropped once two are waiting.
    for (std::uint64_t sequence = 10; sequence < 13; ++sequence)
        (void)sink.offer_scene(small_scene(sequence, sequence));
    EXPECT_EQ(sink.dropped(), 1U);
    EXPECT_FALSE(sink.offer_result(acca::classify(small_scene(10, 10))).has_value());
    EXPECT_TRUE(sink.offer_result(acca::classify(small_scene(12, 12))).has_value());
    EXPECT_EQ(lines_of(dir / "stats.ndjson").size(), 3U);
    fs::remove_all(dir);
}

TEST(SinkRecorder, RejectsAResultOfAnotherScene) {
    const auto dir = temp_folder("mismatch");
    Sink sink(SinkConfig{.out_dir = dir, .write_overlays = false});
    EXPECT_THROW(sink.consume(small_scene(1, 0), acca::classify(small_scene(1, 1))),
                 std::invalid_argument);
    fs::remove_all(dir);
}

// The mission's chain without the runtime: the sensor's scenes go through the wire format
// to two ACCA instances that take alternate images (as AccaTask0/1 in the paper), their
// masks through the wire format to the sink, arriving in a different order than the
// scenes. Every image must be recorded once, with the scene it belongs to.
TEST(EoChain, SensorToTwoAccaTasksToSink) {
    const auto dir = temp_folder("chain");
    sensor::SensorConfig sensor_config;
    sensor_config.base_seed = 31;
    sensor_config.spec.width_px = sensor_config.spec.height_px = 96;
    sensor::Sensor camera(sensor_config);
    Sink sink(SinkConfig{.out_dir = dir});
    constexpr int kImages = 6;
    std::vector<std::vector<std::uint8_t>> masks_in_flight;
    int recorded = 0;
    for (int i = 0; i < kImages; ++i) {
        const auto scene_bytes = serialise(camera.next());
        // Both ACCA tasks receive every scene; each classifies the images of its parity.
        const Scene at_acca = deserialise_scene(scene_bytes);
        masks_in_flight.push_back(acca::serialise(acca::classify(at_acca)));
        recorded += sink.offer_scene(deserialise_scene(scene_bytes)).has_value() ? 1 : 0;
    }
    // The second ACCA task's masks arrive first, in reverse.
    for (int i = kImages - 1; i >= 0; i -= 2) {
        recorded += sink.offer_result(acca::deserialise_result(masks_in_flight[i])).has_value();
    }
    for (int i = 0; i < kImages; i += 2) {
        recorded += sink.offer_result(acca::deserialise_result(masks_in_flight[i])).has_value();
    }
    EXPECT_EQ(recorded, kImages);
    EXPECT_EQ(sink.images_recorded(), static_cast<std::uint64_t>(kImages));
    EXPECT_EQ(sink.dropped(), 0U);
    const auto lines = lines_of(dir / "stats.ndjson");
    ASSERT_EQ(lines.size(), static_cast<std::size_t>(kImages));
    for (int i = 0; i < kImages; ++i) {
        EXPECT_TRUE(fs::exists(dir / ("overlay-" + std::to_string(i) + ".png"))) << i;
        // Each line's accuracy is measured against its own scene's truth.
        const auto at = lines[static_cast<std::size_t>(i)].find("\"accuracy\":");
        ASSERT_NE(at, std::string::npos);
        EXPECT_GT(std::stod(lines[static_cast<std::size_t>(i)].substr(at + 11)), 0.8)
            << lines[static_cast<std::size_t>(i)];
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace keel::eo::sink
