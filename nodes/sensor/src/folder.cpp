#include <algorithm>
#include <array>
#include <cctype>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>

#include "keel/eo/sensor.hpp"

namespace keel::eo::sensor {
namespace fs = std::filesystem;
namespace {

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

bool is_image(const fs::path& path) {
    const auto ext = lower(path.extension().string());
    return ext == ".png" || ext == ".tif" || ext == ".tiff";
}

// ETM+ band number a file holds, judged by its stem ending in "b<N>" or "band<N>"
// (after an optional separator), or 0 when it is not a band file.
int band_number(const fs::path& path) {
    const auto stem = lower(path.stem().string());
    if (stem.size() < 2 || !std::isdigit(static_cast<unsigned char>(stem.back()))) return 0;
    if (stem.size() >= 3 && std::isdigit(static_cast<unsigned char>(stem[stem.size() - 2])))
        return 0;  // e.g. B10
    const auto prefix = stem.substr(0, stem.size() - 1);
    const bool named = prefix.ends_with("band") || prefix == "b" || prefix.ends_with("_b") ||
                       prefix.ends_with("-b") || prefix.ends_with(".b");
    return named ? stem.back() - '0' : 0;
}

std::array<fs::path, kBandCount> find_bands(const fs::path& folder) {
    std::array<fs::path, kBandCount> found;
    for (const auto& entry : fs::directory_iterator(folder)) {
        if (!entry.is_regular_file() || !is_image(entry.path())) continue;
        const int number = band_number(entry.path());
        for (int band = 0; band < kBandCount; ++band) {
            if (number != kEtmBandNumber[band]) continue;
            auto& slot = found[static_cast<std::size_t>(band)];
            if (!slot.empty()) {
                throw std::runtime_error(folder.string() + ": two files for band " +
                                         std::to_string(number) + ": " + slot.filename().string() +
                                         ", " + entry.path().filename().string());
            }
            slot = entry.path();
        }
    }
    return found;
}

bool holds_bands(const fs::path& folder) {
    const auto bands = find_bands(folder);
    return std::all_of(bands.begin(), bands.end(), [](const fs::path& p) { return !p.empty(); });
}

cv::Mat read_plane(const fs::path& path) {
    cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
    if (image.empty()) throw std::runtime_error(path.string() + ": cannot be read as an image");
    if (image.type() != CV_8UC1) {
        throw std::runtime_error(path.string() + ": expected a single-channel 8-bit image, got " +
                                 std::to_string(image.channels()) + " channel(s) of depth code " +
                                 std::to_string(image.depth()));
    }
    return image;
}

}  // namespace

Scene read_band_folder(const fs::path& folder, std::uint64_t sequence, double reflectance_per_dn) {
    if (!fs::is_directory(folder)) throw std::runtime_error(folder.string() + ": not a folder");
    if (!(reflectance_per_dn > 0 && reflectance_per_dn < 1))
        throw std::runtime_error("reflectance_per_dn out of range");
    const auto paths = find_bands(folder);
    std::array<cv::Mat, kBandCount> planes;
    for (int band = 0; band < kBandCount; ++band) {
        const auto& path = paths[static_cast<std::size_t>(band)];
        if (path.empty()) {
            throw std::runtime_error(folder.string() + ": no image for ETM+ band " +
                                     std::to_string(kEtmBandNumber[band]) +
                                     " (expected a name ending in B" +
                                     std::to_string(kEtmBandNumber[band]) + " or band" +
                                     std::to_string(kEtmBandNumber[band]) + ")");
        }
        planes[static_cast<std::size_t>(band)] = read_plane(path);
        if (planes[static_cast<std::size_t>(band)].size() != planes[0].size()) {
            throw std::runtime_error(path.string() + ": size differs from band 2");
        }
    }
    if (planes[0].cols > static_cast<int>(kSceneSideMax) ||
        planes[0].rows > static_cast<int>(kSceneSideMax)) {
        throw std::runtime_error(folder.string() + ": image larger than " +
                                 std::to_string(kSceneSideMax) + " pixels a side");
    }
    Scene scene;
    scene.sequence = sequence;
    scene.seed = 0;
    scene.reflectance_per_dn = reflectance_per_dn;
    cv::merge(planes.data(), kBandCount, scene.bands);
    const auto truth_path = folder / "truth.png";
    if (fs::exists(truth_path)) {
        const cv::Mat truth = read_plane(truth_path);
        if (truth.size() != planes[0].size())
            throw std::runtime_error(truth_path.string() + ": size differs from bands");
        cv::compare(truth, 0, scene.truth_mask, cv::CMP_GT);
    }
    return scene;
}

void write_band_folder(const Scene& scene, const fs::path& folder) {
    fs::create_directories(folder);
    std::array<cv::Mat, kBandCount> planes;
    cv::split(scene.bands, planes.data());
    for (int band = 0; band < kBandCount; ++band) {
        const auto path = folder / ("band" + std::to_string(kEtmBandNumber[band]) + ".png");
        if (!cv::imwrite(path.string(), planes[static_cast<std::size_t>(band)])) {
            throw std::runtime_error(path.string() + ": cannot be written");
        }
    }
    if (scene.has_truth() && !cv::imwrite((folder / "truth.png").string(), scene.truth_mask)) {
        throw std::runtime_error((folder / "truth.png").string() + ": cannot be written");
    }
}

Sensor::Sensor(SensorConfig config) : config_(std::move(config)) {
    if (!config_.folder) return;
    const auto& folder = *config_.folder;
    if (!fs::is_directory(folder)) throw std::runtime_error(folder.string() + ": not a folder");
    if (holds_bands(folder)) {
        scene_folders_.push_back(folder);
    } else {
        for (const auto& entry : fs::directory_iterator(folder)) {
            if (entry.is_directory() && holds_bands(entry.path()))
                scene_folders_.push_back(entry.path());
        }
        std::sort(scene_folders_.begin(), scene_folders_.end());
    }
    if (scene_folders_.empty()) {
        throw std::runtime_error(folder.string() +
                                 ": no band images (B2..B5) in it or in its sub-folders");
    }
}

std::uint64_t Sensor::seed_for(std::uint64_t sequence) const {
    // SplitMix64 finaliser: consecutive sequence numbers give unrelated scenes.
    std::uint64_t z = config_.base_seed + 0x9E3779B97F4A7C15ULL * (sequence + 1);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

Scene Sensor::next() {
    const std::uint64_t sequence = sequence_++;
    if (scene_folders_.empty()) return generate_scene(seed_for(sequence), sequence, config_.spec);
    const auto& folder = scene_folders_[sequence % scene_folders_.size()];
    return read_band_folder(folder, sequence, config_.reflectance_per_dn);
}

}  // namespace keel::eo::sensor
