// An ACCA worker: classifies the scenes whose sequence number is its own and sends the
// sink the mask, the statistics, the accuracy against the truth and a quick-look.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <deque>
#include <opencv2/imgproc.hpp>

#include "core/tasking/bytes.hpp"
#include "keel/eo/codec.hpp"
#include "keel/eo/components.hpp"

namespace keel::eo::components {

namespace {

constexpr std::int64_t kWorkersMax = 64;
constexpr std::int64_t kCacheMax = 64;
constexpr std::size_t kFlagsOffset = 6;  // of the KCLS header
constexpr std::uint8_t kFlagResent = 2;

struct CachedResult {
    std::uint64_t sequence = 0;
    tasking::Payload bytes;  // flagged as resent
};

class AccaComponent final : public tasking::Component {
  public:
    tasking::PortTypes port_types() const override {
        return {{scene_type_id}, {classified_type_id}};
    }

    tasking::LifecycleResult configure(const tasking::ComponentContext& context) override {
        const auto index = context.int_param("worker_index", 0);
        const auto count = context.int_param("worker_count", 1);
        const auto scale = context.double_param("quicklook_scale", 0.25);
        const auto cache = context.int_param("result_cache", 16);
        const auto too_cloudy = context.double_param("too_cloudy_fraction", 0.5);
        if (!index || !count || !scale || !cache || !too_cloudy) {
            return tasking::LifecycleResult::failed(
                "acca: worker_index, worker_count, result_cache must be integers; quicklook_scale "
                "and too_cloudy_fraction numbers");
        }
        if (*count < 1 || *count > kWorkersMax || *index < 0 || *index >= *count) {
            return tasking::LifecycleResult::failed(
                "acca: worker_index must be within 0..worker_count-1 "
                "and worker_count within 1.." +
                std::to_string(kWorkersMax));
        }
        if (!(*scale > 0 && *scale <= 1) || *cache < 0 || *cache > kCacheMax ||
            !(*too_cloudy >= 0 && *too_cloudy <= 1)) {
            return tasking::LifecycleResult::failed(
                "acca: quicklook_scale must be in (0, 1], result_cache within 0..64, "
                "too_cloudy_fraction within 0..1");
        }
        if (context.inputs.empty()) {
            return tasking::LifecycleResult::failed("acca: task '" + context.task +
                                                    "' needs the camera as an input");
        }
        worker_index_ = static_cast<std::uint64_t>(*index);
        worker_count_ = static_cast<std::uint64_t>(*count);
        quicklook_scale_ = *scale;
        cache_max_ = static_cast<std::size_t>(*cache);
        config_.too_cloudy_fraction = *too_cloudy;
        task_ = context.task;
        return tasking::LifecycleResult::ok();
    }

    tasking::LifecycleResult activate(const std::optional<tasking::Snapshot>& snapshot) override {
        classified_ = 0;
        last_sequence_ = 0;
        cache_.clear();
        if (snapshot) {
            tasking::ByteReader reader(snapshot->payload);
            const std::uint64_t classified = reader.u64();
            const std::uint64_t last = reader.u64();
            if (reader.fail() || !reader.at_end()) {
                return tasking::LifecycleResult::failed("acca snapshot is corrupt");
            }
            classified_ = classified;
            last_sequence_ = last;
        }
        return tasking::LifecycleResult::ok();
    }

    tasking::ExecutionResult execute(const tasking::Inputs& inputs,
                                     tasking::Outputs& outputs) override {
        for (std::size_t index = 0; index < inputs.size(); ++index) {
            const tasking::Sample* sample = inputs.get(index);
            if (sample == nullptr || sample->payload == nullptr) continue;
            const auto sequence = peek_scene_sequence(*sample->payload);
            if (!sequence) return {tasking::Outcome::failure, last_cloud_fraction_};
            if (*sequence % worker_count_ != worker_index_) continue;  // another worker's
            if (const CachedResult* cached = find_cached(*sequence)) {
                // The sensor sent the scene again: the sink has not recorded our result
                // (lost on the way, or not acknowledged yet). Send it again, do not redo it.
                outputs.emit(classified_type_id, cached->bytes);
                continue;
            }
            if (!classify(*sample->payload, outputs)) {
                return {tasking::Outcome::failure, last_cloud_fraction_};
            }
        }
        return {tasking::Outcome::success, last_cloud_fraction_};
    }

    tasking::Snapshot deactivate() override { return snapshot(); }

    tasking::Snapshot snapshot() const override {
        tasking::Snapshot state;
        tasking::put_u64(state.payload, classified_);
        tasking::put_u64(state.payload, last_sequence_);
        return state;
    }

  private:
    const CachedResult* find_cached(std::uint64_t sequence) const {
        for (const CachedResult& cached : cache_) {
            if (cached.sequence == sequence) return &cached;
        }
        return nullptr;
    }

    bool classify(const std::vector<std::uint8_t>& bytes, tasking::Outputs& outputs) {
        Scene scene;
        try {
            scene = deserialise_scene(bytes);
        } catch (const std::exception& error) {
            spdlog::warn("{}: dropped a scene that does not decode: {}", task_, error.what());
            return false;
        }
        ClassifiedImage image;
        image.sequence = scene.sequence;
        image.seed = scene.seed;
        image.worker = task_;
        image.worker_pid = static_cast<std::uint32_t>(::getpid());
        image.classified = 1;
        image.result = acca::classify(scene, config_);
        if (scene.has_truth()) {
            image.versus_truth = sink::compare_masks(image.result.cloud_mask, scene.truth_mask);
            image.truth_cloud_fraction = static_cast<double>(cv::countNonZero(scene.truth_mask)) /
                                         static_cast<double>(scene.truth_mask.total());
        }
        image.quicklook.sequence = scene.sequence;
        image.quicklook.seed = scene.seed;
        image.quicklook.reflectance_per_dn = scene.reflectance_per_dn;
        const cv::Size reduced(std::max(1, static_cast<int>(scene.width() * quicklook_scale_)),
                               std::max(1, static_cast<int>(scene.height() * quicklook_scale_)));
        cv::resize(scene.bands, image.quicklook.bands, reduced, 0, 0, cv::INTER_AREA);
        if (scene.has_truth()) {
            cv::resize(scene.truth_mask, image.quicklook.truth_mask, reduced, 0, 0,
                       cv::INTER_NEAREST);
        }
        std::vector<std::uint8_t> out = serialise(image);
        ++classified_;
        last_sequence_ = scene.sequence;
        last_cloud_fraction_ = image.result.cloud_fraction;
        if (cache_max_ > 0) {
            std::vector<std::uint8_t> resent = out;
            resent[kFlagsOffset] = static_cast<std::uint8_t>(resent[kFlagsOffset] | kFlagResent);
            const std::uint32_t crc =
                crc32(std::span<const std::uint8_t>(resent.data(), resent.size() - 4));
            for (std::size_t i = 0; i < 4; ++i) {
                resent[resent.size() - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
            }
            cache_.push_back({scene.sequence, tasking::make_payload(std::move(resent))});
            while (cache_.size() > cache_max_) cache_.pop_front();
        }
        outputs.emit(classified_type_id, std::move(out));
        return true;
    }

    std::string task_ = "acca";
    std::uint64_t worker_index_ = 0;
    std::uint64_t worker_count_ = 1;
    double quicklook_scale_ = 0.25;
    std::size_t cache_max_ = 16;
    acca::Config config_{};

    std::uint64_t classified_ = 0;
    std::uint64_t last_sequence_ = 0;
    double last_cloud_fraction_ = 0;
    std::deque<CachedResult> cache_;
};

}  // namespace

tasking::ComponentPtr make_acca_component() {
    return std::make_unique<AccaComponent>();
}

}  // namespace keel::eo::components
