// The sink task: records each classified image once and tells the sensor what it recorded.
#include <spdlog/spdlog.h>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "core/fsm/json.hpp"
#include "core/tasking/bytes.hpp"
#include "keel/eo/components.hpp"

namespace keel::eo::components {

namespace {

constexpr std::int64_t kEveryMax = 1'000'000;
constexpr std::size_t kDuplicateKeysMax = 4096;
constexpr std::int64_t kAccountingRepeatNs = 1'000'000'000;

std::int64_t wall_clock_ns() {
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// The false-colour composite without tint (band 4 red, 3 green, 2 blue), for the report's
// scene-next-to-mask pictures.
cv::Mat false_colour(const Scene& scene) {
    std::vector<cv::Mat> planes;
    cv::split(scene.bands, planes);
    cv::Mat composite;
    cv::merge(std::vector<cv::Mat>{planes[kGreen], planes[kRed], planes[kNir]}, composite);
    return composite;
}

class SinkComponent final : public tasking::Component {
  public:
    tasking::PortTypes port_types() const override {
        return {{classified_type_id}, {accounting_type_id}};
    }

    tasking::LifecycleResult configure(const tasking::ComponentContext& context) override {
        const auto out_dir = context.string_param("out_dir", "");
        const auto overlays = context.bool_param("overlays", true);
        const auto pictures_every = context.int_param("pictures_every", 10);
        if (!out_dir || !overlays || !pictures_every) {
            return tasking::LifecycleResult::failed(
                "sink: out_dir must be a string, overlays a boolean, pictures_every an integer");
        }
        if (*pictures_every < 0 || *pictures_every > kEveryMax) {
            return tasking::LifecycleResult::failed(
                "sink: pictures_every must be within 0..1000000");
        }
        out_dir_parameter_ = *out_dir;
        overlays_ = *overlays;
        pictures_every_ = static_cast<std::uint64_t>(*pictures_every);
        task_ = context.task;
        return tasking::LifecycleResult::ok();
    }

    tasking::LifecycleResult activate(const std::optional<tasking::Snapshot>& snapshot) override {
        watermark_ = 0;
        above_.clear();
        recorded_ = 0;
        duplicates_ = 0;
        if (snapshot) {
            tasking::ByteReader reader(snapshot->payload);
            const std::uint64_t watermark = reader.u64();
            const std::uint64_t recorded = reader.u64();
            if (reader.fail() || !reader.at_end()) {
                return tasking::LifecycleResult::failed("sink snapshot is corrupt");
            }
            watermark_ = watermark;
            recorded_ = recorded;
        }
        out_dir_ = output_directory(out_dir_parameter_);
        std::error_code error;
        std::filesystem::create_directories(out_dir_, error);
        stats_.close();
        duplicates_file_.close();
        stats_.open(out_dir_ / "stats.ndjson", std::ios::app);
        duplicates_file_.open(out_dir_ / "duplicates.ndjson", std::ios::app);
        if (!stats_ || !duplicates_file_) {
            return tasking::LifecycleResult::failed("sink: cannot write to " + out_dir_.string() +
                                                    (error ? ": " + error.message() : ""));
        }
        spdlog::info("{}: recording to {}", task_, out_dir_.string());
        return tasking::LifecycleResult::ok();
    }

    tasking::ExecutionResult execute(const tasking::Inputs& inputs,
                                     tasking::Outputs& outputs) override {
        bool changed = false;
        bool failed = false;
        for (std::size_t index = 0; index < inputs.size(); ++index) {
            const tasking::Sample* sample = inputs.get(index);
            if (sample == nullptr || sample->payload == nullptr) continue;
            ClassifiedImage image;
            try {
                image = deserialise_classified(*sample->payload);
            } catch (const std::exception& error) {
                spdlog::warn("{}: dropped a classified image that does not decode: {}", task_,
                             error.what());
                failed = true;
                continue;
            }
            record(image, sample->timestamp_ns);
            changed = true;
        }
        // Also now and then without news: a lost accounting sample is made good, and a task
        // that starts consuming it later (the downlink in its phase) learns the state.
        const std::int64_t now_ns = outputs.timestamp_ns();
        if (changed || now_ns - last_accounting_ns_ >= kAccountingRepeatNs) {
            last_accounting_ns_ = now_ns;
            Accounting accounting;
            accounting.watermark = watermark_;
            accounting.recorded = recorded_;
            accounting.duplicates = duplicates_;
            // The newest sequence numbers: the sensor waits on recent scenes.
            auto first = above_.begin();
            if (above_.size() > accounting_list_max) {
                std::advance(first,
                             static_cast<std::ptrdiff_t>(above_.size() - accounting_list_max));
            }
            accounting.recorded_above.assign(first, above_.end());
            outputs.emit(accounting_type_id, serialise(accounting));
        }
        return {failed ? tasking::Outcome::failure : tasking::Outcome::success,
                static_cast<double>(recorded_)};
    }

    tasking::Snapshot deactivate() override {
        stats_.close();
        duplicates_file_.close();
        return snapshot();
    }

    tasking::Snapshot snapshot() const override {
        tasking::Snapshot state;
        tasking::put_u64(state.payload, watermark_);
        tasking::put_u64(state.payload, recorded_);
        return state;
    }

  private:
    bool is_recorded(std::uint64_t sequence) const {
        return sequence <= watermark_ || above_.contains(sequence);
    }

    void record(const ClassifiedImage& image, std::int64_t produced_ns) {
        const std::int64_t now_ns = wall_clock_ns();
        if (is_recorded(image.sequence)) {
            ++duplicates_;
            // Classified again (another instance, or the same one twice) versus the same
            // result sent again by the instance that classified it.
            const auto key = std::make_pair(image.sequence, image.worker_pid);
            const bool same_result = image.resent && first_classifier_.contains(key);
            duplicates_file_ << fsm::JsonObject()
                                    .field("sequence", image.sequence)
                                    .field("worker", image.worker)
                                    .field("worker_pid", image.worker_pid)
                                    .field("resent", image.resent)
                                    .field("kind",
                                           same_result ? "result-sent-again" : "classified-again")
                                    .field("t_ns", now_ns)
                                    .str()
                             << '\n';
            duplicates_file_.flush();
            return;
        }
        above_.insert(image.sequence);
        while (!above_.empty() && *above_.begin() == watermark_ + 1) {
            watermark_ = *above_.begin();
            above_.erase(above_.begin());
        }
        ++recorded_;
        first_classifier_.insert({image.sequence, image.worker_pid});
        while (first_classifier_.size() > kDuplicateKeysMax)
            first_classifier_.erase(first_classifier_.begin());

        sink::ImageStats stats;
        stats.sequence = image.sequence;
        stats.seed = image.seed;
        stats.width = image.result.cloud_mask.cols;
        stats.height = image.result.cloud_mask.rows;
        stats.cloud_fraction = image.result.cloud_fraction;
        stats.too_cloudy = image.result.too_cloudy;
        stats.ambiguous_pixels = image.result.ambiguous_pixels;
        stats.snow_pixels = image.result.snow_pixels;
        stats.compute_ms = image.result.compute_ms;
        if (image.versus_truth) {
            stats.truth_cloud_fraction = image.truth_cloud_fraction;
            stats.versus_truth = image.versus_truth;
        }
        std::string line = sink::to_json_line(stats);
        line.pop_back();  // the closing brace: the sink adds where and when
        line += "," + fsm::JsonObject()
                          .field("worker", image.worker)
                          .field("worker_pid", image.worker_pid)
                          .field("resent", image.resent)
                          .field("t_ns", now_ns)
                          .field("classified_t_ns", produced_ns)
                          .str()
                          .substr(1);
        stats_ << line << '\n';
        stats_.flush();
        write_pictures(image);
    }

    void write_pictures(const ClassifiedImage& image) {
        const Scene& quicklook = image.quicklook;
        cv::Mat mask;
        cv::resize(image.result.cloud_mask, mask, quicklook.bands.size(), 0, 0, cv::INTER_NEAREST);
        const std::string name = std::to_string(image.sequence) + ".png";
        try {
            if (overlays_) {
                const cv::Mat* truth = quicklook.has_truth() ? &quicklook.truth_mask : nullptr;
                cv::imwrite((out_dir_ / ("overlay-" + name)).string(),
                            sink::make_overlay(quicklook, mask, truth, 1.0));
            }
            if (pictures_every_ > 0 && image.sequence % pictures_every_ == 1 % pictures_every_) {
                cv::imwrite((out_dir_ / ("scene-" + name)).string(), false_colour(quicklook));
                cv::imwrite((out_dir_ / ("mask-" + name)).string(), mask);
                if (quicklook.has_truth()) {
                    cv::imwrite((out_dir_ / ("truth-" + name)).string(), quicklook.truth_mask);
                }
            }
        } catch (const std::exception& error) {
            spdlog::warn("{}: pictures of image {} not written: {}", task_, image.sequence,
                         error.what());
        }
    }

    std::string task_ = "sink";
    std::string out_dir_parameter_;
    bool overlays_ = true;
    std::uint64_t pictures_every_ = 10;

    std::filesystem::path out_dir_;
    std::ofstream stats_;
    std::ofstream duplicates_file_;
    std::uint64_t watermark_ = 0;
    std::set<std::uint64_t> above_;
    std::uint64_t recorded_ = 0;
    std::uint64_t duplicates_ = 0;
    std::int64_t last_accounting_ns_ = 0;
    std::set<std::pair<std::uint64_t, std::uint32_t>> first_classifier_;
};

}  // namespace

tasking::ComponentPtr make_sink_component() {
    return std::make_unique<SinkComponent>();
}

}  // namespace keel::eo::components
