// The sensor component: produces 4-band scenes, either synthesised from a seed (with
// the ground-truth cloud mask) or read from band images on disk.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "keel/eo/scene.hpp"

namespace keel::eo::sensor {

struct SceneSpec {
    int width_px = 2048;
    int height_px = 2048;
    // A pixel is cloud in the ground truth when the cloud hides at least this fraction of
    // the surface signal (cloud opacity; 0 = clear, 1 = opaque). Chosen before measuring
    // ACCA against it: a quarter-opaque haze is plainly visible in the image.
    double truth_opacity_min = 0.25;
    // Range the scene's cloud cover is drawn from (fraction of pixels under thick cloud);
    // the spread makes some scenes clear and some too cloudy to downlink.
    double cloud_cover_min = 0.0;
    double cloud_cover_max = 0.85;
};

// What the generator put into the scene, for tests and statistics.
struct SceneComposition {
    double water_fraction = 0;
    double vegetation_fraction = 0;
    double snow_fraction = 0;
    double truth_cloud_fraction = 0;
    // Pixels under visible haze (opacity above 0.02) that the truth counts as clear.
    double thin_cloud_fraction = 0;
    // Per pixel, for analysing classification errors: cloud opacity (CV_32F, 0..1) and the
    // dominant surface under it (CV_8U, values of SurfaceCover).
    cv::Mat opacity;
    cv::Mat dominant_cover;
};

enum class SurfaceCover : std::uint8_t { water = 0, vegetation = 1, soil = 2, snow = 3 };
inline constexpr const char* kSurfaceCoverNames[] = {"water", "vegetation", "soil", "snow"};

// Synthesises one scene: terrain (water, soil from dark to desert-bright, vegetation,
// snow and ice at altitude), cumulus fields with soft edges, cirrus-like thin haze and
// cloud shadows, per-band spectral signatures, texture and sensor noise. Deterministic:
// the same seed and spec give the same bytes.
Scene generate_scene(std::uint64_t seed, std::uint64_t sequence, const SceneSpec& spec = {},
                     SceneComposition* composition = nullptr);

// Reads one scene from a folder of single-band 8-bit images (PNG or TIFF), one file per
// ETM+ band, recognised by a name ending in B2/B3/B4/B5 or band2..band5 before the
// extension (Landsat's own naming, e.g. LE07_..._B3.TIF). An optional truth.png
// (0 = clear, nonzero = cloud) becomes the ground-truth mask. Throws std::runtime_error
// naming the problem for a missing band, mismatched sizes or a non-8-bit image.
Scene read_band_folder(const std::filesystem::path& folder, std::uint64_t sequence = 0,
                       double reflectance_per_dn = 1.0 / 255.0);

// Writes the scene as band2.png..band5.png (+ truth.png), the layout read_band_folder reads.
void write_band_folder(const Scene& scene, const std::filesystem::path& folder);

// A stream of scenes, one per call to next(), as the sensor task emits them.
struct SensorConfig {
    std::uint64_t base_seed = 1;
    SceneSpec spec{};
    // When set, scenes come from this folder instead: either it holds band files itself
    // (one scene) or each sub-folder does (one scene each, in name order); the stream cycles.
    std::optional<std::filesystem::path> folder;
    double reflectance_per_dn = 1.0 / 255.0;  // calibration of images read from files
};

class Sensor {
  public:
    explicit Sensor(SensorConfig config);
    Scene next();
    std::uint64_t sequence() const { return sequence_; }
    // Seed of the synthetic scene with the given sequence number (exposed so a consumer
    // can regenerate the ground truth of a scene it only has the sequence number of).
    std::uint64_t seed_for(std::uint64_t sequence) const;

  private:
    SensorConfig config_;
    std::vector<std::filesystem::path> scene_folders_;
    std::uint64_t sequence_ = 0;
};

}  // namespace keel::eo::sensor
