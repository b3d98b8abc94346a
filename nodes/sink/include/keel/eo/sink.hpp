// The sink component: receives scenes and their cloud masks, writes overlay images
// (PNG) and one line of statistics per image (NDJSON), including the accuracy of the
// mask against the ground truth when the scene carries one.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "keel/eo/acca.hpp"
#include "keel/eo/scene.hpp"

namespace keel::eo::sink {

// Pixel counts of a predicted cloud mask against the truth (cloud = positive).
struct Confusion {
    std::uint64_t true_positive = 0;
    std::uint64_t false_positive = 0;
    std::uint64_t false_negative = 0;
    std::uint64_t true_negative = 0;

    std::uint64_t total() const {
        return true_positive + false_positive + false_negative + true_negative;
    }
    double accuracy() const;
    // Precision and recall are 1 when undefined (nothing predicted / nothing to find):
    // a clear scene classified as clear is not an error.
    double precision() const;
    double recall() const;
};

// Both masks CV_8UC1 of the same size, nonzero = cloud; throws std::invalid_argument otherwise.
Confusion compare_masks(const cv::Mat& predicted, const cv::Mat& truth);

// False-colour composite (band 4 as red, 3 as green, 2 as blue: vegetation shows red)
// with cloud pixels tinted. Without truth, detected cloud is cyan; with truth, agreement
// is cyan, false alarms yellow and missed cloud magenta. Returns BGR CV_8UC3, scaled by
// `scale` (0 < scale <= 1) to keep quick-look files small.
cv::Mat make_overlay(const Scene& scene, const cv::Mat& cloud_mask, const cv::Mat* truth = nullptr,
                     double scale = 1.0);

struct ImageStats {
    std::uint64_t sequence = 0;
    std::uint64_t seed = 0;
    int width = 0;
    int height = 0;
    double cloud_fraction = 0;
    bool too_cloudy = false;
    std::uint64_t ambiguous_pixels = 0;
    std::uint64_t snow_pixels = 0;
    double compute_ms = 0;
    std::optional<double> truth_cloud_fraction;
    std::optional<Confusion> versus_truth;
};

ImageStats make_stats(const Scene& scene, const acca::Result& result);
// One JSON object on one line, no trailing newline.
std::string to_json_line(const ImageStats& stats);

struct SinkConfig {
    std::filesystem::path out_dir = "eo-out";
    bool write_overlays = true;
    // Quick-looks: a 2048² scene gives a 512² overlay (~0.3 MB, ~40 ms to encode)
    // instead of 4.5 MB and ~130 ms at full size.
    double overlay_scale = 0.25;
    std::string stats_file = "stats.ndjson";
    // Scenes or results waiting for their partner (see offer_*); the oldest is dropped
    // beyond this, so a lost message cannot grow the sink without bound.
    std::size_t pending_max = 8;
};

class Sink {
  public:
    // Creates out_dir; throws std::runtime_error if it or the stats file cannot be opened.
    explicit Sink(SinkConfig config);

    // Records one classified scene: overlay-<sequence>.png and a stats line. Throws
    // std::invalid_argument when the result does not belong to the scene (sequence or size).
    ImageStats consume(const Scene& scene, const acca::Result& result);

    // The runtime delivers scenes (from the sensor) and results (from an ACCA task) on
    // separate ports, in any order; these pair them by sequence number and consume each
    // pair once both halves have arrived.
    std::optional<ImageStats> offer_scene(Scene scene);
    std::optional<ImageStats> offer_result(acca::Result result);

    std::uint64_t images_recorded() const { return images_recorded_; }
    std::uint64_t dropped() const { return dropped_; }

  private:
    template <typename T>
    void park(std::deque<T>& queue, T item);

    SinkConfig config_;
    std::ofstream stats_;
    std::deque<Scene> waiting_scenes_;
    std::deque<acca::Result> waiting_results_;
    std::uint64_t images_recorded_ = 0;
    std::uint64_t dropped_ = 0;
};

}  // namespace keel::eo::sink
