#include "keel/eo/sink.hpp"

#include <array>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace keel::eo::sink {
namespace {

std::string number(double value) {
    if (!std::isfinite(value)) return "null";
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value);
    return text;
}

void check_mask(const cv::Mat& mask, const char* name) {
    if (mask.type() != CV_8UC1) throw std::invalid_argument(std::string(name) + " must be CV_8UC1");
}

}  // namespace

double Confusion::accuracy() const {
    return total() == 0
               ? 1.0
               : static_cast<double>(true_positive + true_negative) / static_cast<double>(total());
}
double Confusion::precision() const {
    const auto predicted = true_positive + false_positive;
    return predicted == 0 ? 1.0
                          : static_cast<double>(true_positive) / static_cast<double>(predicted);
}
double Confusion::recall() const {
    const auto actual = true_positive + false_negative;
    return actual == 0 ? 1.0 : static_cast<double>(true_positive) / static_cast<double>(actual);
}

Confusion compare_masks(const cv::Mat& predicted, const cv::Mat& truth) {
    check_mask(predicted, "predicted mask");
    check_mask(truth, "truth mask");
    if (predicted.size() != truth.size()) throw std::invalid_argument("masks differ in size");
    cv::Mat predicted_cloud;
    cv::Mat truth_cloud;
    cv::Mat both;
    cv::compare(predicted, 0, predicted_cloud, cv::CMP_NE);
    cv::compare(truth, 0, truth_cloud, cv::CMP_NE);
    cv::bitwise_and(predicted_cloud, truth_cloud, both);
    const auto tp = static_cast<std::uint64_t>(cv::countNonZero(both));
    const auto predicted_count = static_cast<std::uint64_t>(cv::countNonZero(predicted_cloud));
    const auto truth_count = static_cast<std::uint64_t>(cv::countNonZero(truth_cloud));
    Confusion confusion;
    confusion.true_positive = tp;
    confusion.false_positive = predicted_count - tp;
    confusion.false_negative = truth_count - tp;
    confusion.true_negative = predicted.total() - predicted_count - truth_count + tp;
    assert(confusion.total() == predicted.total());
    return confusion;
}

cv::Mat make_overlay(const Scene& scene, const cv::Mat& cloud_mask, const cv::Mat* truth,
                     double scale) {
    if (scene.bands.type() != CV_8UC4) throw std::invalid_argument("overlay needs a CV_8UC4 scene");
    check_mask(cloud_mask, "cloud mask");
    if (cloud_mask.size() != scene.bands.size())
        throw std::invalid_argument("cloud mask differs in size from the scene");
    if (truth != nullptr && (truth->type() != CV_8UC1 || truth->size() != scene.bands.size())) {
        throw std::invalid_argument("truth mask must be CV_8UC1 of the scene's size");
    }
    if (!(scale > 0 && scale <= 1)) throw std::invalid_argument("overlay scale must be in (0, 1]");
    std::array<cv::Mat, kBandCount> planes;
    cv::split(scene.bands, planes.data());
    // BGR order for imwrite: blue <- band 2, green <- band 3, red <- band 4.
    const std::array<cv::Mat, 3> composite_planes = {planes[kGreen], planes[kRed], planes[kNir]};
    cv::Mat composite;
    cv::merge(composite_planes.data(), 3, composite);
    auto tint = [&](const cv::Mat& where, const cv::Scalar& colour) {
        cv::Mat tinted;
        cv::addWeighted(composite, 0.5, cv::Mat(composite.size(), CV_8UC3, colour), 0.5, 0.0,
                        tinted);
        tinted.copyTo(composite, where);
    };
    const cv::Scalar cyan(255, 255, 0);
    const cv::Scalar yellow(0, 255, 255);
    const cv::Scalar magenta(255, 0, 255);
    if (truth == nullptr) {
        tint(cloud_mask, cyan);
    } else {
        cv::Mat detected;
        cv::Mat actual;
        cv::Mat region;
        cv::compare(cloud_mask, 0, detected, cv::CMP_NE);
        cv::compare(*truth, 0, actual, cv::CMP_NE);
        cv::bitwise_and(detected, actual, region);
        tint(region, cyan);
        cv::bitwise_and(detected, ~actual, region);
        tint(region, yellow);
        cv::bitwise_and(~detected, actual, region);
        tint(region, magenta);
    }
    if (scale < 1) cv::resize(composite, composite, cv::Size(), scale, scale, cv::INTER_AREA);
    return composite;
}

ImageStats make_stats(const Scene& scene, const acca::Result& result) {
    ImageStats stats;
    stats.sequence = result.sequence;
    stats.seed = scene.seed;
    stats.width = result.cloud_mask.cols;
    stats.height = result.cloud_mask.rows;
    stats.cloud_fraction = result.cloud_fraction;
    stats.too_cloudy = result.too_cloudy;
    stats.ambiguous_pixels = result.ambiguous_pixels;
    stats.snow_pixels = result.snow_pixels;
    stats.compute_ms = result.compute_ms;
    if (scene.has_truth()) {
        stats.versus_truth = compare_masks(result.cloud_mask, scene.truth_mask);
        stats.truth_cloud_fraction = static_cast<double>(cv::countNonZero(scene.truth_mask)) /
                                     static_cast<double>(scene.truth_mask.total());
    }
    return stats;
}

std::string to_json_line(const ImageStats& stats) {
    std::string line = "{\"sequence\":" + std::to_string(stats.sequence) +
                       ",\"seed\":" + std::to_string(stats.seed) +
                       ",\"width\":" + std::to_string(stats.width) +
                       ",\"height\":" + std::to_string(stats.height) +
                       ",\"cloud_fraction\":" + number(stats.cloud_fraction) +
                       ",\"too_cloudy\":" + (stats.too_cloudy ? "true" : "false") +
                       ",\"ambiguous_pixels\":" + std::to_string(stats.ambiguous_pixels) +
                       ",\"snow_pixels\":" + std::to_string(stats.snow_pixels) +
                       ",\"compute_ms\":" + number(stats.compute_ms);
    if (stats.versus_truth) {
        const Confusion& confusion = *stats.versus_truth;
        line += ",\"truth_cloud_fraction\":" + number(stats.truth_cloud_fraction.value_or(NAN)) +
                ",\"accuracy\":" + number(confusion.accuracy()) +
                ",\"precision\":" + number(confusion.precision()) +
                ",\"recall\":" + number(confusion.recall()) +
                ",\"true_positive\":" + std::to_string(confusion.true_positive) +
                ",\"false_positive\":" + std::to_string(confusion.false_positive) +
                ",\"false_negative\":" + std::to_string(confusion.false_negative) +
                ",\"true_negative\":" + std::to_string(confusion.true_negative);
    }
    line += "}";
    return line;
}

Sink::Sink(SinkConfig config) : config_(std::move(config)) {
    assert(config_.pending_max > 0);
    std::filesystem::create_directories(config_.out_dir);
    const auto stats_path = config_.out_dir / config_.stats_file;
    stats_.open(stats_path, std::ios::app);
    if (!stats_) throw std::runtime_error(stats_path.string() + ": cannot be opened for writing");
}

ImageStats Sink::consume(const Scene& scene, const acca::Result& result) {
    if (scene.sequence != result.sequence) {
        throw std::invalid_argument("result " + std::to_string(result.sequence) +
                                    " paired with scene " + std::to_string(scene.sequence));
    }
    if (result.cloud_mask.size() != scene.bands.size())
        throw std::invalid_argument("mask size differs from the scene");
    const ImageStats stats = make_stats(scene, result);
    if (config_.write_overlays) {
        const cv::Mat overlay =
            make_overlay(scene, result.cloud_mask, scene.has_truth() ? &scene.truth_mask : nullptr,
                         config_.overlay_scale);
        const auto path = config_.out_dir / ("overlay-" + std::to_string(result.sequence) + ".png");
        if (!cv::imwrite(path.string(), overlay))
            throw std::runtime_error(path.string() + ": cannot be written");
    }
    stats_ << to_json_line(stats) << '\n';
    stats_.flush();  // a line per image survives the sink's node failing right after
    ++images_recorded_;
    return stats;
}

template <typename T>
void Sink::park(std::deque<T>& queue, T item) {
    if (queue.size() >= config_.pending_max) {
        queue.pop_front();
        ++dropped_;
    }
    queue.push_back(std::move(item));
}

std::optional<ImageStats> Sink::offer_scene(Scene scene) {
    for (auto it = waiting_results_.begin(); it != waiting_results_.end(); ++it) {
        if (it->sequence != scene.sequence) continue;
        const acca::Result result = std::move(*it);
        waiting_results_.erase(it);
        return consume(scene, result);
    }
    park(waiting_scenes_, std::move(scene));
    return std::nullopt;
}

std::optional<ImageStats> Sink::offer_result(acca::Result result) {
    for (auto it = waiting_scenes_.begin(); it != waiting_scenes_.end(); ++it) {
        if (it->sequence != result.sequence) continue;
        const Scene scene = std::move(*it);
        waiting_scenes_.erase(it);
        return consume(scene, result);
    }
    park(waiting_results_, std::move(result));
    return std::nullopt;
}

}  // namespace keel::eo::sink
