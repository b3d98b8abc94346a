// Synthetic scene generator. Every field is built with whole-image OpenCV operations:
// fractal noise from bicubically enlarged random grids, combined per band. The spectral
// signatures are representative top-of-atmosphere reflectances for ETM+ bands 2, 3, 4, 5
// (see DESIGN.md for their sources and how they relate to the ACCA tests).
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "keel/eo/sensor.hpp"

namespace keel::eo::sensor {
namespace {

using Signature = std::array<float, kBandCount>;  // reflectance in bands 2, 3, 4, 5

// Representative TOA reflectances (sun high, mid-latitude summer). DESIGN.md cites them.
constexpr Signature kClearWater = {0.070F, 0.045F, 0.025F, 0.012F};
constexpr Signature kTurbidWater = {0.085F, 0.065F, 0.040F, 0.020F};
constexpr Signature kVegetation = {0.080F, 0.050F, 0.320F, 0.160F};
constexpr Signature kDarkSoil = {0.090F, 0.110F, 0.170F, 0.230F};
constexpr Signature kBrightSand = {0.260F, 0.330F, 0.390F, 0.460F};
constexpr Signature kFreshSnow = {0.800F, 0.780F, 0.680F, 0.090F};
constexpr Signature kGlacierIce = {0.550F, 0.500F, 0.380F, 0.040F};
constexpr Signature kCloud = {0.740F, 0.720F, 0.700F, 0.450F};

constexpr float kSensorNoiseDn = 0.7F;  // read noise, standard deviation in DN
// Calibration of synthetic scenes: DN 255 is reflectance 1, so snow and cloud tops fit.
constexpr double kReflectancePerDn = 1.0 / 255.0;

// Deterministic uniform numbers from a 64-bit Mersenne twister, converted by hand so the
// scene does not depend on the standard library's distribution implementation.
class Random {
  public:
    explicit Random(std::uint64_t seed) : engine_(seed) {}
    double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
    double uniform(double low, double high) { return low + (high - low) * uniform(); }
    std::uint64_t bits() { return engine_(); }

  private:
    std::mt19937_64 engine_;
};

// Sum of octaves of value noise, normalised to [0, 1].
cv::Mat fractal(Random& random, cv::Size size, int base_cells, int octaves, double persistence) {
    assert(base_cells > 0 && octaves > 0);
    cv::Mat sum = cv::Mat::zeros(size, CV_32F);
    double amplitude = 1.0;
    for (int octave = 0; octave < octaves; ++octave) {
        const int cells = base_cells << octave;
        const int cells_x = std::min(cells, size.width);
        const int cells_y = std::min(cells, size.height);
        cv::Mat grid(cells_y + 1, cells_x + 1, CV_32F);
        for (int y = 0; y < grid.rows; ++y) {
            auto* row = grid.ptr<float>(y);
            for (int x = 0; x < grid.cols; ++x)
                row[x] = static_cast<float>(random.uniform(-1.0, 1.0));
        }
        cv::Mat layer;
        cv::resize(grid, layer, size, 0, 0, cv::INTER_CUBIC);
        cv::scaleAdd(layer, amplitude, sum, sum);
        amplitude *= persistence;
    }
    double low = 0;
    double high = 0;
    cv::minMaxLoc(sum, &low, &high);
    sum.convertTo(sum, CV_32F, 1.0 / std::max(high - low, 1e-9), -low / std::max(high - low, 1e-9));
    return sum;
}

// Value below which the given fraction of the field's pixels lie (field in [0, 1]).
float quantile(const cv::Mat& field, double fraction) {
    constexpr int kBins = 1024;
    const int channels[] = {0};
    const int bins[] = {kBins};
    const float range[] = {0.0F, 1.0F + 1e-6F};
    const float* ranges[] = {range};
    cv::Mat histogram;
    cv::calcHist(&field, 1, channels, cv::Mat(), histogram, 1, bins, ranges);
    const double target = fraction * static_cast<double>(field.total());
    double count = 0;
    for (int bin = 0; bin < kBins; ++bin) {
        count += histogram.at<float>(bin);
        if (count >= target) return static_cast<float>(bin + 1) / kBins;
    }
    return 1.0F;
}

// Hermite smoothstep of the field between edge0 and edge1, element-wise.
cv::Mat smoothstep(const cv::Mat& field, float edge0, float edge1) {
    assert(edge1 > edge0);
    cv::Mat t;
    field.convertTo(t, CV_32F, 1.0 / (edge1 - edge0), -edge0 / (edge1 - edge0));
    t = cv::max(cv::min(t, 1.0), 0.0);
    cv::Mat result = t.mul(t).mul(3.0 - 2.0 * t);
    return result;
}

cv::Mat lerp_band(const cv::Mat& weight, float from, float to) {
    cv::Mat out;
    weight.convertTo(out, CV_32F, to - from, from);
    return out;
}

// Rows [first_row, first_row + rows) of the low-resolution field enlarged bilinearly to
// `size`, sampled at an offset of (dx, dy) full-resolution pixels: value at (x, y) is the
// enlarged field at (x - dx, y - dy). Same pixel-centre mapping as cv::resize, so the
// scene can be produced strip by strip without ever holding full-size float planes.
void enlarge_rows(const cv::Mat& low, cv::Size size, int first_row, int rows, double dx, double dy,
                  cv::Mat& out) {
    const double scale_x = static_cast<double>(low.cols) / size.width;
    const double scale_y = static_cast<double>(low.rows) / size.height;
    const cv::Matx23d to_source(scale_x, 0, scale_x * (0.5 - dx) - 0.5, 0, scale_y,
                                scale_y * (first_row - dy + 0.5) - 0.5);
    cv::warpAffine(low, out, to_source, cv::Size(size.width, rows),
                   cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
}

// Rows of full-resolution work at a time: a strip's ~30 float planes stay in cache, and
// generating a 2048x2048 scene needs a few MB of working memory instead of hundreds.
constexpr int kStripRows = 32;

}  // namespace

Scene generate_scene(std::uint64_t seed, std::uint64_t sequence, const SceneSpec& spec,
                     SceneComposition* composition) {
    assert(spec.width_px >= 16 && spec.height_px >= 16 && "scene too small to synthesise");
    assert(spec.width_px <= static_cast<int>(kSceneSideMax) &&
           spec.height_px <= static_cast<int>(kSceneSideMax));
    assert(spec.cloud_cover_min >= 0 && spec.cloud_cover_max <= 1 &&
           spec.cloud_cover_min <= spec.cloud_cover_max);
    Random random(seed);
    const cv::Size size(spec.width_px, spec.height_px);
    // Large-scale structure is built at a quarter of the resolution and enlarged: it is
    // smooth at that scale anyway.
    const cv::Size low(std::max(16, size.width / 4), std::max(16, size.height / 4));

    // Scene-wide parameters drawn from the seed.
    const double water_fraction = random.uniform(0.05, 0.40);
    const double snow_fraction = random.uniform() < 0.5 ? random.uniform(0.02, 0.15) : 0.0;
    const double vegetation_share = random.uniform(0.25, 0.75);
    const double cover = random.uniform(spec.cloud_cover_min, spec.cloud_cover_max);
    const double haze_opacity_max = random.uniform(0.05, 0.45);
    const double haze_fraction = random.uniform(0.0, 0.5);
    const int shadow_dx = static_cast<int>(random.uniform(0.005, 0.02) * size.width);
    const int shadow_dy = static_cast<int>(random.uniform(0.005, 0.02) * size.height);
    const std::uint64_t noise_seed = random.bits();

    const cv::Mat elevation_low = fractal(random, low, 3, 6, 0.5);
    const cv::Mat moisture_low = fractal(random, low, 5, 5, 0.55);
    const cv::Mat soil_low = fractal(random, low, 4, 5, 0.5);
    const cv::Mat cumulus_low = fractal(random, low, 4, 6, 0.6);
    const cv::Mat haze_low = fractal(random, low, 2, 4, 0.5);

    // Levels that give each cover its drawn share of the scene.
    const float water_level = quantile(elevation_low, water_fraction);
    const float snow_level =
        snow_fraction > 0 ? quantile(elevation_low, 1.0 - snow_fraction) : 2.0F;
    const float vegetation_level = quantile(moisture_low, 1.0 - vegetation_share);
    const float cloud_level = quantile(cumulus_low, 1.0 - cover);
    const float haze_level = quantile(haze_low, 1.0 - haze_fraction);

    Scene scene;
    scene.sequence = sequence;
    scene.seed = seed;
    scene.reflectance_per_dn = kReflectancePerDn;
    scene.bands.create(size, CV_8UC4);
    scene.truth_mask.create(size, CV_8UC1);
    if (composition != nullptr) {
        composition->opacity.create(size, CV_32F);
        composition->dominant_cover.create(size, CV_8U);
    }
    double water_sum = 0, snow_sum = 0, vegetation_sum = 0;
    int hazy_count = 0;

    cv::RNG rng(noise_seed);
    cv::Mat elevation, moisture, soil, cumulus, haze, shadow_cumulus, texture, noise;
    std::array<cv::Mat, kBandCount> planes;
    for (int first_row = 0; first_row < size.height; first_row += kStripRows) {
        const int rows = std::min(kStripRows, size.height - first_row);
        const cv::Range strip(first_row, first_row + rows);
        enlarge_rows(elevation_low, size, first_row, rows, 0, 0, elevation);
        enlarge_rows(moisture_low, size, first_row, rows, 0, 0, moisture);
        enlarge_rows(soil_low, size, first_row, rows, 0, 0, soil);
        enlarge_rows(cumulus_low, size, first_row, rows, 0, 0, cumulus);
        enlarge_rows(haze_low, size, first_row, rows, 0, 0, haze);
        // Shadows: the cloud field displaced along the sun azimuth darkens the surface.
        enlarge_rows(cumulus_low, size, first_row, rows, shadow_dx, shadow_dy, shadow_cumulus);

        // Land cover weights; shorelines and snow lines blend over a narrow band of elevation.
        const cv::Mat water_weight =
            1.0 - smoothstep(elevation, water_level - 0.01F, water_level + 0.01F);
        const cv::Mat snow_weight =
            snow_fraction > 0 ? smoothstep(elevation, snow_level - 0.01F, snow_level + 0.01F)
                              : cv::Mat(cv::Mat::zeros(elevation.size(), CV_32F));
        const cv::Mat land_weight = cv::max(1.0 - water_weight - snow_weight, 0.0);
        const cv::Mat vegetation_weight =
            smoothstep(moisture, vegetation_level - 0.05F, vegetation_level + 0.05F);
        const cv::Mat ice_weight = smoothstep(soil, 0.55F, 0.75F);

        // Clouds: cumulus with soft edges over a thick core, plus a smooth cirrus-like haze.
        const cv::Mat thick_opacity = smoothstep(cumulus, cloud_level - 0.03F, cloud_level + 0.05F);
        const cv::Mat haze_opacity =
            smoothstep(haze, haze_level - 0.1F, haze_level + 0.15F) * haze_opacity_max;
        const cv::Mat opacity = 1.0 - (1.0 - thick_opacity).mul(1.0 - haze_opacity);
        // Thick cloud cores are brighter than their edges.
        const cv::Mat cloud_brightness =
            0.8 + 0.2 * smoothstep(cumulus, cloud_level, cloud_level + 0.2F);
        const cv::Mat shadow_factor =
            1.0 - 0.55 * smoothstep(shadow_cumulus, cloud_level - 0.03F, cloud_level + 0.05F);

        // Texture: land varies more than water or snow from pixel to pixel.
        texture.create(elevation.size(), CV_32F);
        rng.fill(texture, cv::RNG::NORMAL, 0.0, 1.0);
        const cv::Mat texture_sigma = 0.02 * water_weight + 0.03 * snow_weight + 0.08 * land_weight;
        const cv::Mat texture_factor = (1.0 + texture.mul(texture_sigma)).mul(shadow_factor);

        noise.create(elevation.size(), CV_32F);
        for (int band = 0; band < kBandCount; ++band) {
            const cv::Mat water = lerp_band(soil, kClearWater[band], kTurbidWater[band]);
            const cv::Mat bare = lerp_band(soil, kDarkSoil[band], kBrightSand[band]);
            const cv::Mat snow = lerp_band(ice_weight, kFreshSnow[band], kGlacierIce[band]);
            const cv::Mat land =
                vegetation_weight * kVegetation[band] + (1.0 - vegetation_weight).mul(bare);
            const cv::Mat surface =
                (water_weight.mul(water) + snow_weight.mul(snow) + land_weight.mul(land))
                    .mul(texture_factor);
            const cv::Mat reflectance =
                opacity.mul(cloud_brightness * kCloud[band]) + (1.0 - opacity).mul(surface);
            rng.fill(noise, cv::RNG::NORMAL, 0.0, kSensorNoiseDn);
            const cv::Mat dn = reflectance * (1.0 / kReflectancePerDn) + noise;
            dn.convertTo(planes[static_cast<std::size_t>(band)], CV_8U);  // rounds and saturates
        }
        cv::Mat bands_strip = scene.bands.rowRange(strip);
        cv::merge(planes.data(), kBandCount, bands_strip);
        cv::Mat truth_strip = scene.truth_mask.rowRange(strip);
        cv::compare(opacity, spec.truth_opacity_min, truth_strip, cv::CMP_GE);
        assert(bands_strip.data == scene.bands.ptr(first_row) && "strips are written in place");

        if (composition != nullptr) {
            water_sum += cv::sum(water_weight)[0];
            snow_sum += cv::sum(snow_weight)[0];
            const cv::Mat vegetation = land_weight.mul(vegetation_weight);
            vegetation_sum += cv::sum(vegetation)[0];
            cv::Mat hazy;
            cv::compare(opacity, 0.02, hazy, cv::CMP_GT);
            hazy_count += cv::countNonZero(hazy);
            opacity.copyTo(composition->opacity.rowRange(strip));
            // Dominant cover: the largest of the four weights; ties go to the later one.
            const cv::Mat soil_cover = land_weight.mul(1.0 - vegetation_weight);
            const std::array<const cv::Mat*, 4> weights = {&water_weight, &vegetation, &soil_cover,
                                                           &snow_weight};
            cv::Mat best = water_weight.clone();
            cv::Mat dominant = composition->dominant_cover.rowRange(strip);
            dominant.setTo(0);
            cv::Mat larger;
            for (std::uint8_t cover_index = 1; cover_index < 4; ++cover_index) {
                cv::compare(*weights[cover_index], best, larger, cv::CMP_GE);
                dominant.setTo(cover_index, larger);
                best = cv::max(best, *weights[cover_index]);
            }
        }
    }

    if (composition != nullptr) {
        const double pixels = static_cast<double>(size.area());
        composition->water_fraction = water_sum / pixels;
        composition->snow_fraction = snow_sum / pixels;
        composition->vegetation_fraction = vegetation_sum / pixels;
        composition->truth_cloud_fraction = cv::countNonZero(scene.truth_mask) / pixels;
        composition->thin_cloud_fraction =
            (hazy_count - cv::countNonZero(scene.truth_mask)) / pixels;
    }
    return scene;
}

}  // namespace keel::eo::sensor
