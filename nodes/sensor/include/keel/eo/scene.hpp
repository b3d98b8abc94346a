// A multispectral scene as the sensor component publishes it, and its wire format.
//
// Band layout follows the four reflective Landsat ETM+ bands that ACCA pass one uses
// (Irish 2000): channel 0 = band 2 (green, 0.52-0.60 um), 1 = band 3 (red, 0.63-0.69 um),
// 2 = band 4 (near infrared, 0.76-0.90 um), 3 = band 5 (short-wave infrared, 1.55-1.75 um).
// Pixels are 8-bit digital numbers; top-of-atmosphere reflectance = DN * reflectance_per_dn.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

namespace keel::eo {

inline constexpr int kBandCount = 4;
inline constexpr int kGreen = 0;  // ETM+ band 2
inline constexpr int kRed = 1;    // ETM+ band 3
inline constexpr int kNir = 2;    // ETM+ band 4
inline constexpr int kSwir = 3;   // ETM+ band 5
inline constexpr int kEtmBandNumber[kBandCount] = {2, 3, 4, 5};

// Largest side accepted from the wire; bounds the allocation a header can request.
inline constexpr std::uint32_t kSceneSideMax = 16384;

struct Scene {
    std::uint64_t sequence = 0;               // position in the sensor's output stream
    std::uint64_t seed = 0;                   // generator seed; 0 for scenes read from files
    double reflectance_per_dn = 1.0 / 255.0;  // radiometric calibration, same for all bands
    cv::Mat bands;                            // CV_8UC4, channel order as above
    cv::Mat truth_mask;                       // CV_8UC1 with 0 / 255 (cloud), empty when unknown

    int width() const { return bands.cols; }
    int height() const { return bands.rows; }
    bool has_truth() const { return !truth_mask.empty(); }
};

// Wire format, little-endian:
//   u32 magic 'KSCN' | u16 version (1) | u16 flags (bit 0: truth mask present)
//   u32 width | u32 height | u8 bands (4) | u8[7] reserved (zero)
//   u64 sequence | u64 seed | f64 reflectance_per_dn
//   u8[width*height*4] pixels (row-major, interleaved) | [u8[width*height] truth mask]
//   u32 CRC-32 of everything before it
inline constexpr std::uint32_t kSceneMagic = 0x4E43534BU;  // "KSCN" read as little-endian
inline constexpr std::uint16_t kSceneVersion = 1;
inline constexpr std::size_t kSceneHeaderBytes = 48;

std::vector<std::uint8_t> serialise(const Scene& scene);

// Throws keel::eo::DecodeError (codec.hpp) for a wrong magic or version, bad
// dimensions, a length that does not match the header, or a checksum mismatch.
Scene deserialise_scene(std::span<const std::uint8_t> bytes);

}  // namespace keel::eo
