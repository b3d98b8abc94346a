#include "keel/eo/scene.hpp"

#include <gtest/gtest.h>

#include "keel/eo/codec.hpp"
#include "keel/eo/sensor.hpp"

namespace keel::eo {
namespace {

Scene small_scene() {
    sensor::SceneSpec spec;
    spec.width_px = 96;
    spec.height_px = 64;
    return sensor::generate_scene(11, 5, spec);
}

TEST(EoCrc32, MatchesTheStandardCheckValue) {
    const std::string text = "123456789";
    EXPECT_EQ(crc32({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}),
              0xCBF43926U);
}

TEST(SceneCodec, RoundTripsPixelsTruthAndHeader) {
    const Scene scene = small_scene();
    const auto bytes = serialise(scene);
    EXPECT_EQ(bytes.size(), kSceneHeaderBytes + 96U * 64U * 5U + 4U);
    const Scene back = deserialise_scene(bytes);
    EXPECT_EQ(back.sequence, 5U);
    EXPECT_EQ(back.seed, 11U);
    EXPECT_DOUBLE_EQ(back.reflectance_per_dn, scene.reflectance_per_dn);
    ASSERT_EQ(back.bands.size(), scene.bands.size());
    EXPECT_EQ(cv::norm(back.bands, scene.bands, cv::NORM_INF), 0.0);
    ASSERT_TRUE(back.has_truth());
    EXPECT_EQ(cv::norm(back.truth_mask, scene.truth_mask, cv::NORM_INF), 0.0);
}

TEST(SceneCodec, RoundTripsWithoutTruthAndFromARegionOfInterest) {
    Scene scene = small_scene();
    scene.truth_mask.release();
    scene.bands = scene.bands(cv::Rect(8, 4, 40, 30));  // non-continuous view
    const Scene back = deserialise_scene(serialise(scene));
    EXPECT_FALSE(back.has_truth());
    EXPECT_EQ(cv::norm(back.bands, scene.bands, cv::NORM_INF), 0.0);
}

TEST(SceneCodec, RejectsTruncatedBuffersAtEveryLength) {
    const auto bytes = serialise(small_scene());
    for (std::size_t length : {std::size_t{0}, std::size_t{3}, std::size_t{20}, kSceneHeaderBytes,
                               bytes.size() / 2, bytes.size() - 1}) {
        EXPECT_THROW(deserialise_scene(std::span(bytes).first(length)), DecodeError)
            << "length " << length;
    }
}

TEST(SceneCodec, RejectsAFlippedPixelBit) {
    auto bytes = serialise(small_scene());
    bytes[kSceneHeaderBytes + 1234] ^= 0x10;
    try {
        (void)deserialise_scene(bytes);
        FAIL() << "corrupt buffer accepted";
    } catch (const DecodeError& error) {
        EXPECT_NE(std::string(error.what()).find("checksum"), std::string::npos) << error.what();
    }
}

TEST(SceneCodec, RejectsWrongMagicVersionAndDimensions) {
    const auto good = serialise(small_scene());
    auto bad_magic = good;
    bad_magic[0] ^= 0xFF;
    EXPECT_THROW(deserialise_scene(bad_magic), DecodeError);
    auto bad_version = good;
    bad_version[4] = 9;
    EXPECT_THROW(deserialise_scene(bad_version), DecodeError);
    auto huge = good;
    huge[8] = 0xFF;  // width low byte
    huge[9] = 0xFF;
    huge[10] = 0xFF;  // width now far beyond the limit
    EXPECT_THROW(deserialise_scene(huge), DecodeError);
    auto extra = good;
    extra.push_back(0);
    EXPECT_THROW(deserialise_scene(extra), DecodeError);
}

TEST(SceneCodec, RejectsEverySingleByteCorruptionAndRandomGarbage) {
    sensor::SceneSpec spec;
    spec.width_px = 24;
    spec.height_px = 16;
    const auto good = serialise(sensor::generate_scene(2, 1, spec));
    for (std::size_t position = 0; position < good.size(); ++position) {
        auto bad = good;
        bad[position] ^= 0x5A;
        EXPECT_THROW(deserialise_scene(bad), DecodeError) << "byte " << position;
    }
    std::uint64_t state = 12345;
    for (int trial = 0; trial < 200; ++trial) {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        std::vector<std::uint8_t> garbage((state >> 40) % 300);
        for (auto& byte : garbage) {
            state = state * 6364136223846793005ULL + 1442695040888963407ULL;
            byte = static_cast<std::uint8_t>(state >> 56);
        }
        if (garbage.size() >= 4) {  // half the trials start with a valid magic to get further in
            if (trial % 2 == 0) std::copy(good.begin(), good.begin() + 4, garbage.begin());
        }
        EXPECT_THROW(deserialise_scene(garbage), DecodeError);
    }
}

}  // namespace
}  // namespace keel::eo
