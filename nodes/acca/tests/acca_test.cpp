#include "keel/eo/acca.hpp"

#include <gtest/gtest.h>

#include "keel/eo/codec.hpp"
#include "keel/eo/sensor.hpp"

namespace keel::eo::acca {
namespace {

// A one-row scene whose pixels have the given reflectances in bands 2, 3, 4, 5.
Scene scene_of(const std::vector<cv::Vec4d>& pixels) {
    Scene scene;
    scene.reflectance_per_dn = 1.0 / 255.0;
    scene.bands.create(1, static_cast<int>(pixels.size()), CV_8UC4);
    for (std::size_t i = 0; i < pixels.size(); ++i) {
        cv::Vec4b& dn = scene.bands.at<cv::Vec4b>(0, static_cast<int>(i));
        for (int band = 0; band < kBandCount; ++band)
            dn[band] = cv::saturate_cast<std::uint8_t>(pixels[i][band] * 255.0);
    }
    return scene;
}

bool is_cloud(const cv::Vec4d& reflectance) {
    return classify(scene_of({reflectance})).cloud_mask.at<std::uint8_t>(0, 0) == 255;
}

// Per-pixel transcription of the pass-one rules with real divisions: the reference the
// vectorised implementation must match exactly.
bool reference_cloud(const cv::Vec4b& dn, double gain) {
    const double b2 = dn[0] * gain, b3 = dn[1] * gain, b4 = dn[2] * gain, b5 = dn[3] * gain;
    if (!(b3 > 0.08)) return false;
    if (b2 + b5 > 0 && (b2 - b5) / (b2 + b5) >= 0.7) return false;
    if (b2 + b5 == 0) return false;
    if (b3 == 0 || b4 / b3 >= 2.0) return false;
    if (b2 == 0 || b4 / b2 >= 2.16248) return false;
    return b5 == 0 ? b4 > 0 : b4 / b5 > 1.0;
}

TEST(AccaPassOne, ClassifiesTheTypicalSurfaces) {
    EXPECT_TRUE(is_cloud({0.74, 0.72, 0.70, 0.45}));      // thick cloud
    EXPECT_FALSE(is_cloud({0.07, 0.045, 0.025, 0.012}));  // water: too dark (filter 1)
    EXPECT_FALSE(is_cloud({0.80, 0.78, 0.68, 0.09}));     // snow: NDSI 0.80 (filter 2)
    EXPECT_FALSE(is_cloud({0.15, 0.12, 0.45, 0.22}));  // bright vegetation: b4/b3 3.75 (filter 5)
    EXPECT_FALSE(is_cloud({0.26, 0.33, 0.39, 0.46}));  // desert sand: b4/b5 0.85 (filter 7)
}

TEST(AccaPassOne, EachFilterDecidesAtItsThreshold) {
    // Start from a cloud pixel and move one quantity across one threshold at a time.
    EXPECT_TRUE(is_cloud({0.10, 0.090, 0.09, 0.08}));
    EXPECT_FALSE(is_cloud({0.10, 0.075, 0.09, 0.08}));  // filter 1: b3 below 0.08
    EXPECT_TRUE(is_cloud({0.60, 0.60, 0.30, 0.13}));    // NDSI 0.64
    EXPECT_FALSE(is_cloud({0.60, 0.60, 0.30, 0.10}));   // NDSI 0.71: filter 2
    EXPECT_TRUE(is_cloud({0.40, 0.20, 0.38, 0.30}));    // b4/b3 1.9
    EXPECT_FALSE(is_cloud({0.40, 0.20, 0.42, 0.30}));   // b4/b3 2.1: filter 5
    EXPECT_TRUE(is_cloud({0.20, 0.30, 0.42, 0.30}));    // b4/b2 2.1
    EXPECT_FALSE(is_cloud({0.20, 0.30, 0.45, 0.30}));   // b4/b2 2.25: filter 6
    EXPECT_TRUE(is_cloud({0.30, 0.30, 0.33, 0.30}));    // b4/b5 1.1
    EXPECT_FALSE(is_cloud({0.30, 0.30, 0.28, 0.30}));   // b4/b5 0.93: filter 7
}

TEST(AccaPassOne, MatchesAPerPixelReferenceOnASyntheticScene) {
    sensor::SceneSpec spec;
    spec.width_px = spec.height_px = 200;
    const Scene scene = sensor::generate_scene(21, 0, spec);
    const Result result = classify(scene);
    int mismatches = 0;
    for (int y = 0; y < scene.bands.rows; ++y) {
        for (int x = 0; x < scene.bands.cols; ++x) {
            const bool expected =
                reference_cloud(scene.bands.at<cv::Vec4b>(y, x), scene.reflectance_per_dn);
            mismatches += expected != (result.cloud_mask.at<std::uint8_t>(y, x) == 255);
        }
    }
    EXPECT_EQ(mismatches, 0);
    EXPECT_EQ(result.cloud_pixels, static_cast<std::uint64_t>(cv::countNonZero(result.cloud_mask)));
}

TEST(AccaPassOne, StripHeightDoesNotChangeTheResult) {
    sensor::SceneSpec spec;
    spec.width_px = 150;
    spec.height_px = 97;
    const Scene scene = sensor::generate_scene(8, 0, spec);
    const Result whole = classify(scene, Config{.strip_rows = 1000});
    for (int strip_rows : {1, 7, 32}) {
        Config config;
        config.strip_rows = strip_rows;
        const Result stripped = classify(scene, config);
        EXPECT_EQ(cv::norm(whole.cloud_mask, stripped.cloud_mask, cv::NORM_INF), 0.0) << strip_rows;
        EXPECT_EQ(whole.ambiguous_pixels, stripped.ambiguous_pixels);
        EXPECT_EQ(whole.snow_pixels, stripped.snow_pixels);
    }
}

TEST(AccaPassOne, AgreesWithGroundTruthOnSyntheticScenes) {
    // The benchmark reports accuracy on full-size scenes; here a floor on small ones so a
    // broken filter or generator shows up as a failing test.
    sensor::SceneSpec spec;
    spec.width_px = spec.height_px = 256;
    double accuracy_sum = 0;
    constexpr int kScenes = 8;
    for (int seed = 1; seed <= kScenes; ++seed) {
        const Scene scene = sensor::generate_scene(static_cast<std::uint64_t>(seed), 0, spec);
        const Result result = classify(scene);
        cv::Mat disagree;
        cv::compare(result.cloud_mask, scene.truth_mask, disagree, cv::CMP_NE);
        const double accuracy =
            1.0 - cv::countNonZero(disagree) / static_cast<double>(scene.truth_mask.total());
        EXPECT_GT(accuracy, 0.85) << "seed " << seed;
        accuracy_sum += accuracy;
    }
    EXPECT_GT(accuracy_sum / kScenes, 0.93);
}

TEST(AccaPassOne, FlagsTooCloudyScenesAndIgnoresFill) {
    std::vector<cv::Vec4d> pixels(10, cv::Vec4d{0.74, 0.72, 0.70, 0.45});
    for (int i = 0; i < 4; ++i) pixels[static_cast<std::size_t>(i)] = {0.07, 0.045, 0.025, 0.012};
    pixels[9] = {0, 0, 0, 0};  // fill
    const Result result = classify(scene_of(pixels));
    EXPECT_EQ(result.valid_pixels, 9U);
    EXPECT_EQ(result.cloud_pixels, 5U);
    EXPECT_NEAR(result.cloud_fraction, 5.0 / 9.0, 1e-12);
    EXPECT_TRUE(result.too_cloudy);
    Config lenient;
    lenient.too_cloudy_fraction = 0.6;
    EXPECT_FALSE(classify(scene_of(pixels), lenient).too_cloudy);
}

TEST(AccaPassOne, CountsSnowAndAmbiguousPixels) {
    const Result result = classify(
        scene_of({{0.85, 0.80, 0.70, 0.06}, {0.26, 0.33, 0.39, 0.46}, {0.74, 0.72, 0.70, 0.45}}));
    EXPECT_EQ(result.snow_pixels, 1U);
    EXPECT_EQ(result.ambiguous_pixels, 1U);  // the sand
    EXPECT_EQ(result.cloud_pixels, 1U);
}

TEST(AccaPassOne, RejectsScenesThatAreNotFourBandEightBit) {
    Scene scene;
    scene.bands = cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(1));
    EXPECT_THROW(classify(scene), std::invalid_argument);
}

TEST(AccaResultCodec, RoundTripsAndRejectsCorruption) {
    sensor::SceneSpec spec;
    spec.width_px = 61;  // not a multiple of 8: exercises the row padding
    spec.height_px = 40;
    const Result result = classify(sensor::generate_scene(4, 9, spec));
    const auto bytes = serialise(result);
    const Result back = deserialise_result(bytes);
    EXPECT_EQ(back.sequence, 9U);
    EXPECT_EQ(back.cloud_pixels, result.cloud_pixels);
    EXPECT_EQ(back.too_cloudy, result.too_cloudy);
    EXPECT_DOUBLE_EQ(back.cloud_fraction, result.cloud_fraction);
    EXPECT_EQ(cv::norm(back.cloud_mask, result.cloud_mask, cv::NORM_INF), 0.0);

    for (std::size_t length : {std::size_t{0}, std::size_t{2}, std::size_t{30}, bytes.size() - 1}) {
        EXPECT_THROW(deserialise_result(std::span(bytes).first(length)), DecodeError) << length;
    }
    auto flipped = bytes;
    flipped[bytes.size() - 10] ^= 0x01;
    EXPECT_THROW(deserialise_result(flipped), DecodeError);
    auto wrong_magic = bytes;
    wrong_magic[1] ^= 0x01;
    EXPECT_THROW(deserialise_result(wrong_magic), DecodeError);
}

TEST(AccaResultCodec, RejectsEverySingleByteCorruption) {
    sensor::SceneSpec spec;
    spec.width_px = 20;
    spec.height_px = 16;
    const auto good = serialise(classify(sensor::generate_scene(6, 3, spec)));
    for (std::size_t position = 0; position < good.size(); ++position) {
        auto bad = good;
        bad[position] ^= 0x21;
        EXPECT_THROW(deserialise_result(bad), DecodeError) << "byte " << position;
    }
}

}  // namespace
}  // namespace keel::eo::acca
