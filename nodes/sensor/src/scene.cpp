#include "keel/eo/scene.hpp"

#include <cassert>
#include <cstring>
#include <string>

#include "keel/eo/codec.hpp"

namespace keel::eo {

namespace {
constexpr std::uint16_t kFlagTruth = 1;
}

std::vector<std::uint8_t> serialise(const Scene& scene) {
    assert(scene.bands.type() == CV_8UC4 && "scene bands must be CV_8UC4");
    assert((scene.truth_mask.empty() || (scene.truth_mask.type() == CV_8UC1 &&
                                         scene.truth_mask.size() == scene.bands.size())) &&
           "truth mask must be CV_8UC1 of the scene's size");
    const auto pixels =
        static_cast<std::size_t>(scene.width()) * static_cast<std::size_t>(scene.height());
    std::vector<std::uint8_t> out;
    out.reserve(kSceneHeaderBytes + pixels * (kBandCount + (scene.has_truth() ? 1 : 0)) + 4);
    ByteWriter writer(out);
    writer.u32(kSceneMagic);
    writer.u16(kSceneVersion);
    writer.u16(scene.has_truth() ? kFlagTruth : 0);
    writer.u32(static_cast<std::uint32_t>(scene.width()));
    writer.u32(static_cast<std::uint32_t>(scene.height()));
    writer.u8(kBandCount);
    for (int i = 0; i < 7; ++i) writer.u8(0);
    writer.u64(scene.sequence);
    writer.u64(scene.seed);
    writer.f64(scene.reflectance_per_dn);
    assert(writer.size() == kSceneHeaderBytes);
    auto append_plane = [&](const cv::Mat& mat) {
        // Rows are copied one by one so views into larger images (non-continuous) work too.
        const auto row_bytes = static_cast<std::size_t>(mat.cols) * mat.elemSize();
        for (int row = 0; row < mat.rows; ++row)
            writer.bytes({mat.ptr<std::uint8_t>(row), row_bytes});
    };
    append_plane(scene.bands);
    if (scene.has_truth()) append_plane(scene.truth_mask);
    writer.u32(crc32(out));
    return out;
}

Scene deserialise_scene(std::span<const std::uint8_t> bytes) {
    ByteReader reader(bytes);
    if (reader.u32("magic") != kSceneMagic) throw DecodeError("not a scene buffer: bad magic");
    const auto version = reader.u16("version");
    if (version != kSceneVersion)
        throw DecodeError("unsupported scene version " + std::to_string(version));
    const auto flags = reader.u16("flags");
    if ((flags & ~kFlagTruth) != 0)
        throw DecodeError("unknown scene flags " + std::to_string(flags));
    const auto width = reader.u32("width");
    const auto height = reader.u32("height");
    if (width == 0 || height == 0 || width > kSceneSideMax || height > kSceneSideMax) {
        throw DecodeError("scene dimensions out of range: " + std::to_string(width) + "x" +
                          std::to_string(height));
    }
    const auto band_count = reader.u8("bands");
    if (band_count != kBandCount)
        throw DecodeError("scene has " + std::to_string(band_count) + " bands, expected 4");
    (void)reader.bytes(7, "reserved");
    Scene scene;
    scene.sequence = reader.u64("sequence");
    scene.seed = reader.u64("seed");
    scene.reflectance_per_dn = reader.f64("reflectance_per_dn");
    if (!(scene.reflectance_per_dn > 0.0 && scene.reflectance_per_dn < 1.0)) {
        throw DecodeError("reflectance_per_dn out of range");
    }
    const bool has_truth = (flags & kFlagTruth) != 0;
    const auto pixels = static_cast<std::size_t>(width) * height;
    // Check the total length before allocating, so a truncated buffer is rejected cheaply.
    const auto expected = kSceneHeaderBytes + pixels * kBandCount + (has_truth ? pixels : 0) + 4;
    if (bytes.size() != expected) {
        throw DecodeError("scene buffer is " + std::to_string(bytes.size()) +
                          " bytes, header implies " + std::to_string(expected));
    }
    const auto stored_crc = static_cast<std::uint32_t>(bytes[expected - 4]) |
                            (static_cast<std::uint32_t>(bytes[expected - 3]) << 8) |
                            (static_cast<std::uint32_t>(bytes[expected - 2]) << 16) |
                            (static_cast<std::uint32_t>(bytes[expected - 1]) << 24);
    if (crc32(bytes.first(expected - 4)) != stored_crc)
        throw DecodeError("scene checksum mismatch (corrupt buffer)");
    const auto pixel_bytes = reader.bytes(pixels * kBandCount, "pixels");
    scene.bands.create(static_cast<int>(height), static_cast<int>(width), CV_8UC4);
    std::memcpy(scene.bands.data, pixel_bytes.data(), pixel_bytes.size());
    if (has_truth) {
        const auto mask_bytes = reader.bytes(pixels, "truth mask");
        scene.truth_mask.create(static_cast<int>(height), static_cast<int>(width), CV_8UC1);
        std::memcpy(scene.truth_mask.data, mask_bytes.data(), mask_bytes.size());
    }
    return scene;
}

}  // namespace keel::eo
