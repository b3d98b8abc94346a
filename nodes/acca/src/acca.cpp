#include "keel/eo/acca.hpp"

#include <array>
#include <cassert>
#include <chrono>
#include <stdexcept>
#include <string>

#include "keel/eo/codec.hpp"

namespace keel::eo::acca {
namespace {

// Working planes of one strip, allocated once per call and reused for every strip.
struct Strip {
    std::array<cv::Mat, kBandCount> dn8;
    std::array<cv::Mat, kBandCount> reflectance;
    cv::Mat scaled;
    cv::Mat test;
    cv::Mat passed;  // filters 1 and 2 passed: bright and not snow
    cv::Mat ratios;  // filters 5, 6 and 7 passed
    cv::Mat valid;
    cv::Mat snow;
};

// a < k * b, element-wise, into out (0 / 255). Written as a product so no division by a
// zero band ever happens; the ratio tests are equivalent because reflectances are >= 0.
void less_than_scaled(const cv::Mat& a, double k, const cv::Mat& b, cv::Mat& scaled, cv::Mat& out) {
    b.convertTo(scaled, CV_32F, k);
    cv::compare(a, scaled, out, cv::CMP_LT);
}

}  // namespace

Result classify(const Scene& scene, const Config& config) {
    const auto start = std::chrono::steady_clock::now();
    if (scene.bands.type() != CV_8UC4)
        throw std::invalid_argument("ACCA needs a CV_8UC4 scene (bands 2, 3, 4, 5)");
    if (scene.bands.empty()) throw std::invalid_argument("ACCA needs a non-empty scene");
    if (!(scene.reflectance_per_dn > 0))
        throw std::invalid_argument("scene calibration must be positive");
    assert(config.strip_rows > 0);
    const Thresholds& limits = config.thresholds;
    const double gain = scene.reflectance_per_dn;

    Result result;
    result.sequence = scene.sequence;
    result.cloud_mask.create(scene.bands.size(), CV_8UC1);
    Strip work;
    for (int row = 0; row < scene.bands.rows; row += config.strip_rows) {
        const cv::Range rows(row, std::min(row + config.strip_rows, scene.bands.rows));
        cv::split(scene.bands.rowRange(rows), work.dn8.data());
        for (int band = 0; band < kBandCount; ++band) {
            work.dn8[band].convertTo(work.reflectance[band], CV_32F, gain);
        }
        const cv::Mat& b2 = work.reflectance[kGreen];
        const cv::Mat& b3 = work.reflectance[kRed];
        const cv::Mat& b4 = work.reflectance[kNir];
        const cv::Mat& b5 = work.reflectance[kSwir];

        // Filter 1: brightness in band 3.
        cv::compare(b3, limits.band3_reflectance_min, work.passed, cv::CMP_GT);
        // Filter 2: NDSI < max  <=>  (1 - max) * b2 < (1 + max) * b5.
        b2.convertTo(work.scaled, CV_32F, (1.0 - limits.ndsi_max) / (1.0 + limits.ndsi_max));
        cv::compare(work.scaled, b5, work.test, cv::CMP_LT);
        cv::bitwise_and(work.passed, work.test, work.passed);
        // Filters 5, 6, 7: the vegetation and soil ratios.
        less_than_scaled(b4, limits.band4_over_band3_max, b3, work.scaled, work.ratios);
        less_than_scaled(b4, limits.band4_over_band2_max, b2, work.scaled, work.test);
        cv::bitwise_and(work.ratios, work.test, work.ratios);
        b5.convertTo(work.scaled, CV_32F, limits.band4_over_band5_min);
        cv::compare(b4, work.scaled, work.test, cv::CMP_GT);
        cv::bitwise_and(work.ratios, work.test, work.ratios);

        cv::Mat cloud = result.cloud_mask.rowRange(rows);
        cv::bitwise_and(work.passed, work.ratios, cloud);
        const int cloud_count = cv::countNonZero(cloud);
        result.cloud_pixels += static_cast<std::uint64_t>(cloud_count);
        result.ambiguous_pixels +=
            static_cast<std::uint64_t>(cv::countNonZero(work.passed) - cloud_count);

        // Snow tally: NDSI > snow_min  <=>  (1 - min) * b2 > (1 + min) * b5, and bright band 4.
        b2.convertTo(work.scaled, CV_32F,
                     (1.0 - limits.snow_ndsi_min) / (1.0 + limits.snow_ndsi_min));
        cv::compare(work.scaled, b5, work.snow, cv::CMP_GT);
        cv::compare(b4, limits.snow_band4_reflectance_min, work.test, cv::CMP_GT);
        cv::bitwise_and(work.snow, work.test, work.snow);
        result.snow_pixels += static_cast<std::uint64_t>(cv::countNonZero(work.snow));

        // Pixels zero in every band are fill outside the imaged swath, as in Landsat scenes.
        cv::bitwise_or(work.dn8[0], work.dn8[1], work.valid);
        cv::bitwise_or(work.valid, work.dn8[2], work.valid);
        cv::bitwise_or(work.valid, work.dn8[3], work.valid);
        result.valid_pixels += static_cast<std::uint64_t>(cv::countNonZero(work.valid));
    }
    result.cloud_fraction = result.valid_pixels == 0 ? 0.0
                                                     : static_cast<double>(result.cloud_pixels) /
                                                           static_cast<double>(result.valid_pixels);
    result.too_cloudy = result.cloud_fraction > config.too_cloudy_fraction;
    result.compute_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    assert(result.cloud_pixels <= result.valid_pixels);
    return result;
}

std::vector<std::uint8_t> serialise(const Result& result) {
    assert(result.cloud_mask.type() == CV_8UC1);
    const int width = result.cloud_mask.cols;
    const int height = result.cloud_mask.rows;
    const auto row_bytes = static_cast<std::size_t>((width + 7) / 8);
    std::vector<std::uint8_t> out;
    out.reserve(80 + row_bytes * static_cast<std::size_t>(height));
    ByteWriter writer(out);
    writer.u32(kResultMagic);
    writer.u16(kResultVersion);
    writer.u16(result.too_cloudy ? 1 : 0);
    writer.u32(static_cast<std::uint32_t>(width));
    writer.u32(static_cast<std::uint32_t>(height));
    writer.u64(result.sequence);
    writer.u64(result.valid_pixels);
    writer.u64(result.cloud_pixels);
    writer.u64(result.ambiguous_pixels);
    writer.u64(result.snow_pixels);
    writer.f64(result.cloud_fraction);
    writer.f64(result.compute_ms);
    // Bit-packing makes a 2048x2048 mask 512 KiB instead of 4 MiB on the wire.
    std::vector<std::uint8_t> packed(row_bytes);
    for (int y = 0; y < height; ++y) {
        std::fill(packed.begin(), packed.end(), 0);
        const auto* mask = result.cloud_mask.ptr<std::uint8_t>(y);
        for (int x = 0; x < width; ++x) {
            if (mask[x] != 0)
                packed[static_cast<std::size_t>(x / 8)] |=
                    static_cast<std::uint8_t>(0x80U >> (x % 8));
        }
        writer.bytes(packed);
    }
    writer.u32(crc32(out));
    return out;
}

Result deserialise_result(std::span<const std::uint8_t> bytes) {
    if (bytes.size() < 4) throw DecodeError("truncated buffer: shorter than a checksum");
    ByteReader reader(bytes);
    if (reader.u32("magic") != kResultMagic)
        throw DecodeError("not a cloud-mask buffer: bad magic");
    const auto version = reader.u16("version");
    if (version != kResultVersion)
        throw DecodeError("unsupported cloud-mask version " + std::to_string(version));
    const auto flags = reader.u16("flags");
    if ((flags & ~1U) != 0) throw DecodeError("unknown cloud-mask flags " + std::to_string(flags));
    const auto width = reader.u32("width");
    const auto height = reader.u32("height");
    if (width == 0 || height == 0 || width > kSceneSideMax || height > kSceneSideMax) {
        throw DecodeError("cloud-mask dimensions out of range: " + std::to_string(width) + "x" +
                          std::to_string(height));
    }
    Result result;
    result.too_cloudy = (flags & 1U) != 0;
    result.sequence = reader.u64("sequence");
    result.valid_pixels = reader.u64("valid_pixels");
    result.cloud_pixels = reader.u64("cloud_pixels");
    result.ambiguous_pixels = reader.u64("ambiguous_pixels");
    result.snow_pixels = reader.u64("snow_pixels");
    result.cloud_fraction = reader.f64("cloud_fraction");
    result.compute_ms = reader.f64("compute_ms");
    const auto row_bytes = static_cast<std::size_t>((width + 7) / 8);
    const auto expected = reader.offset() + row_bytes * height + 4;
    if (bytes.size() != expected) {
        throw DecodeError("cloud-mask buffer is " + std::to_string(bytes.size()) +
                          " bytes, header implies " + std::to_string(expected));
    }
    const auto stored_crc = static_cast<std::uint32_t>(bytes[expected - 4]) |
                            (static_cast<std::uint32_t>(bytes[expected - 3]) << 8) |
                            (static_cast<std::uint32_t>(bytes[expected - 2]) << 16) |
                            (static_cast<std::uint32_t>(bytes[expected - 1]) << 24);
    if (crc32(bytes.first(expected - 4)) != stored_crc)
        throw DecodeError("cloud-mask checksum mismatch (corrupt buffer)");
    const auto pixels = static_cast<std::uint64_t>(width) * height;
    if (result.valid_pixels > pixels || result.cloud_pixels > result.valid_pixels ||
        !(result.cloud_fraction >= 0 && result.cloud_fraction <= 1)) {
        throw DecodeError("cloud-mask counts inconsistent with its size");
    }
    result.cloud_mask.create(static_cast<int>(height), static_cast<int>(width), CV_8UC1);
    for (int y = 0; y < static_cast<int>(height); ++y) {
        const auto packed = reader.bytes(row_bytes, "mask row");
        auto* mask = result.cloud_mask.ptr<std::uint8_t>(y);
        for (int x = 0; x < static_cast<int>(width); ++x) {
            mask[x] = (packed[static_cast<std::size_t>(x / 8)] & (0x80U >> (x % 8))) != 0 ? 255 : 0;
        }
    }
    return result;
}

}  // namespace keel::eo::acca
