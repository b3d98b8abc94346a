// ACCA pass one (Irish 2000; Irish et al. 2006) on the four reflective bands, as the
// OBC-NG earth-observation demonstration used it: classifies every pixel of a scene as
// cloud or not, and flags scenes too cloudy to be worth downlinking.
//
// The pass-one filters, in order (reflectance = DN * scene.reflectance_per_dn):
//   1 brightness   band 3 > 0.08, else clear (dark: water, shadow, vegetation)
//   2 NDSI         (b2 - b5) / (b2 + b5) < 0.7, else clear (snow)
//   3 temperature  band 6 < 300 K                 -- dropped: no thermal band
//   4 b5/b6 comp.  (1 - b5) * b6 < 225            -- dropped: no thermal band
//   5 b4/b3 ratio  < 2.0, else ambiguous (growing vegetation)
//   6 b4/b2 ratio  < 2.16248, else ambiguous (senescing vegetation)
//   7 b4/b5 ratio  > 1.0, else ambiguous (rocks, desert, bare soil)
//   8 warm / cold  (1 - b5) * b6 split            -- dropped: no thermal band
// A pixel passing 1, 2, 5, 6 and 7 is cloud. DESIGN.md gives the sources and discusses
// what dropping the thermal tests costs.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

#include "keel/eo/scene.hpp"

namespace keel::eo::acca {

struct Thresholds {
    double band3_reflectance_min = 0.08;    // filter 1
    double ndsi_max = 0.7;                  // filter 2
    double band4_over_band3_max = 2.0;      // filter 5
    double band4_over_band2_max = 2.16248;  // filter 6
    double band4_over_band5_min = 1.0;      // filter 7
    // Snow tally of pass one (not a cloud test): NDSI > 0.8 and band 4 > 0.11.
    double snow_ndsi_min = 0.8;
    double snow_band4_reflectance_min = 0.11;
};

struct Config {
    Thresholds thresholds{};
    // The paper does not give its threshold; half the scene under cloud is where most
    // acquisition planners stop calling an image usable. Configurable per mission.
    double too_cloudy_fraction = 0.5;
    // Rows processed together: keeps the intermediate planes in cache (see DESIGN.md).
    int strip_rows = 32;
};

struct Result {
    std::uint64_t sequence = 0;      // of the scene classified
    cv::Mat cloud_mask;              // CV_8UC1: 255 cloud, 0 not cloud
    std::uint64_t valid_pixels = 0;  // pixels with data (not zero in all bands)
    std::uint64_t cloud_pixels = 0;
    std::uint64_t ambiguous_pixels = 0;  // bright, not snow, failed a ratio test
    std::uint64_t snow_pixels = 0;
    double cloud_fraction = 0;  // cloud_pixels / valid_pixels
    bool too_cloudy = false;    // cloud_fraction > Config::too_cloudy_fraction
    double compute_ms = 0;      // wall time of classify()
};

// Throws std::invalid_argument for a scene that is not 4-band 8-bit.
Result classify(const Scene& scene, const Config& config = {});

// Wire format of a result, for shipping masks to the sink: little-endian
//   u32 magic 'KMSK' | u16 version (1) | u16 flags (bit 0 too_cloudy) | u32 width | u32 height
//   u64 sequence | u64 valid, cloud, ambiguous, snow pixels | f64 cloud_fraction | f64 compute_ms
//   mask bit-packed, 8 pixels a byte, most significant bit first, rows padded to bytes
//   u32 CRC-32 of everything before it
inline constexpr std::uint32_t kResultMagic = 0x4B534D4BU;  // "KMSK"
inline constexpr std::uint16_t kResultVersion = 1;
std::vector<std::uint8_t> serialise(const Result& result);
// Throws keel::eo::DecodeError for malformed, truncated or corrupt buffers.
Result deserialise_result(std::span<const std::uint8_t> bytes);

}  // namespace keel::eo::acca
