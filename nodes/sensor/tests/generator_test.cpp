#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "keel/eo/sensor.hpp"

namespace keel::eo::sensor {
namespace {
namespace fs = std::filesystem;

SceneSpec spec_px(int side_px) {
    SceneSpec spec;
    spec.width_px = side_px;
    spec.height_px = side_px;
    return spec;
}

fs::path temp_folder(const std::string& name) {
    const auto path =
        fs::temp_directory_path() / ("keel-sensor-test-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
    return path;
}

TEST(SceneGenerator, IsDeterministicPerSeed) {
    const Scene a = generate_scene(42, 0, spec_px(128));
    const Scene b = generate_scene(42, 0, spec_px(128));
    const Scene c = generate_scene(43, 0, spec_px(128));
    EXPECT_EQ(cv::norm(a.bands, b.bands, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.truth_mask, b.truth_mask, cv::NORM_INF), 0.0);
    EXPECT_GT(cv::norm(a.bands, c.bands, cv::NORM_L1), 0.0);
    EXPECT_EQ(a.bands.type(), CV_8UC4);
    EXPECT_EQ(a.truth_mask.type(), CV_8UC1);
}

TEST(SceneGenerator, CloudCoverFollowsTheRequestedRange) {
    SceneSpec clear = spec_px(160);
    clear.cloud_cover_min = clear.cloud_cover_max = 0.0;
    SceneSpec overcast = spec_px(160);
    overcast.cloud_cover_min = overcast.cloud_cover_max = 0.8;
    SceneComposition clear_mix;
    SceneComposition overcast_mix;
    (void)generate_scene(3, 0, clear, &clear_mix);
    (void)generate_scene(3, 0, overcast, &overcast_mix);
    // Haze may still push a few pixels over the truth threshold in a cloud-free sky.
    EXPECT_LT(clear_mix.truth_cloud_fraction, 0.35);
    EXPECT_GT(overcast_mix.truth_cloud_fraction, 0.75);
    EXPECT_GT(overcast_mix.truth_cloud_fraction, clear_mix.truth_cloud_fraction);
}

TEST(SceneGenerator, SpectralSignaturesSeparateCloudFromSurface) {
    SceneSpec spec = spec_px(192);
    spec.cloud_cover_min = spec.cloud_cover_max = 0.4;
    SceneComposition mix;
    const Scene scene = generate_scene(9, 0, spec, &mix);
    EXPECT_GT(mix.water_fraction, 0.03);
    EXPECT_GT(mix.vegetation_fraction, 0.05);
    cv::Mat clear;
    cv::bitwise_not(scene.truth_mask, clear);
    const cv::Scalar cloud_mean = cv::mean(scene.bands, scene.truth_mask);
    const cv::Scalar clear_mean = cv::mean(scene.bands, clear);
    // Clouds are bright in the visible and brighter in band 4 than in band 5.
    EXPECT_GT(cloud_mean[kRed], clear_mean[kRed] + 50);
    EXPECT_GT(cloud_mean[kNir], cloud_mean[kSwir]);
}

TEST(SceneGenerator, SnowIsBrightInTheVisibleAndDarkInTheShortWaveInfrared) {
    // Search a few seeds for a scene with snow; half of them carry some by design.
    for (std::uint64_t seed = 1; seed < 20; ++seed) {
        SceneSpec spec = spec_px(128);
        spec.cloud_cover_min = spec.cloud_cover_max = 0.0;
        SceneComposition mix;
        const Scene scene = generate_scene(seed, 0, spec, &mix);
        if (mix.snow_fraction < 0.03) continue;
        std::vector<cv::Mat> planes;
        cv::split(scene.bands, planes);
        cv::Mat snowy;
        cv::compare(planes[kGreen], 150, snowy, cv::CMP_GT);
        ASSERT_GT(cv::countNonZero(snowy), 0);
        EXPECT_LT(cv::mean(planes[kSwir], snowy)[0], 40.0);
        return;
    }
    FAIL() << "no seed in 1..19 produced snow";
}

TEST(BandFolder, WritesAndReadsBackAScene) {
    const auto folder = temp_folder("roundtrip");
    const Scene scene = generate_scene(5, 2, spec_px(64));
    write_band_folder(scene, folder);
    const Scene back = read_band_folder(folder, 2);
    EXPECT_EQ(cv::norm(back.bands, scene.bands, cv::NORM_INF), 0.0);
    ASSERT_TRUE(back.has_truth());
    EXPECT_EQ(cv::norm(back.truth_mask, scene.truth_mask, cv::NORM_INF), 0.0);
    fs::remove_all(folder);
}

TEST(BandFolder, ReadsLandsatStyleNamesAndReportsAMissingBand) {
    const auto folder = temp_folder("landsat");
    const Scene scene = generate_scene(6, 0, spec_px(48));
    std::vector<cv::Mat> planes;
    cv::split(scene.bands, planes);
    for (int band = 0; band < 3; ++band) {
        cv::imwrite((folder / ("LE07_L1TP_TEST_B" + std::to_string(kEtmBandNumber[band]) + ".TIF"))
                        .string(),
                    planes[band]);
    }
    try {
        (void)read_band_folder(folder);
        FAIL() << "folder without band 5 accepted";
    } catch (const std::runtime_error& error) {
        EXPECT_NE(std::string(error.what()).find("band 5"), std::string::npos) << error.what();
    }
    cv::imwrite((folder / "LE07_L1TP_TEST_B5.TIF").string(), planes[3]);
    const Scene back = read_band_folder(folder);
    EXPECT_EQ(cv::norm(back.bands, scene.bands, cv::NORM_INF), 0.0);
    EXPECT_FALSE(back.has_truth());
    fs::remove_all(folder);
}

TEST(BandFolder, RejectsColourImagesAndSizeMismatch) {
    const auto folder = temp_folder("bad");
    const cv::Mat plane(32, 32, CV_8UC1, cv::Scalar(10));
    for (int number : {2, 3, 4})
        cv::imwrite((folder / ("band" + std::to_string(number) + ".png")).string(), plane);
    cv::imwrite((folder / "band5.png").string(), cv::Mat(32, 32, CV_8UC3, cv::Scalar(1, 2, 3)));
    EXPECT_THROW(read_band_folder(folder), std::runtime_error);
    cv::imwrite((folder / "band5.png").string(), cv::Mat(16, 32, CV_8UC1, cv::Scalar(1)));
    EXPECT_THROW(read_band_folder(folder), std::runtime_error);
    fs::remove_all(folder);
}

TEST(SensorStream, StreamsDistinctScenesAndCyclesAFolder) {
    SensorConfig config;
    config.base_seed = 77;
    config.spec = spec_px(64);
    Sensor sensor(config);
    const Scene first = sensor.next();
    const Scene second = sensor.next();
    EXPECT_EQ(first.sequence, 0U);
    EXPECT_EQ(second.sequence, 1U);
    EXPECT_NE(first.seed, second.seed);
    EXPECT_EQ(first.seed, sensor.seed_for(0));

    const auto root = temp_folder("stream");
    write_band_folder(first, root / "a");
    write_band_folder(second, root / "b");
    config.folder = root;
    Sensor from_files(config);
    EXPECT_EQ(cv::norm(from_files.next().bands, first.bands, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(from_files.next().bands, second.bands, cv::NORM_INF), 0.0);
    const Scene third = from_files.next();
    EXPECT_EQ(third.sequence, 2U);
    EXPECT_EQ(cv::norm(third.bands, first.bands, cv::NORM_INF), 0.0);
    fs::remove_all(root);
}

}  // namespace
}  // namespace keel::eo::sensor
