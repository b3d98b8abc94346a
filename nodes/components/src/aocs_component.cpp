// The AOCS task: the attitude filter fed by a truth simulator that runs on the wall clock,
// so the simulated world keeps going while the task migrates (nodes/aocs/DESIGN.md).
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>

#include "core/fsm/json.hpp"
#include "core/tasking/bytes.hpp"
#include "keel/eo/aocs.hpp"
#include "keel/eo/components.hpp"

namespace keel::eo::components {

namespace {

constexpr std::uint32_t kStateVersion = 1;
constexpr std::int64_t kCatchUpMax = 600'000;

std::int64_t wall_clock_ns() {
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

class AocsComponent final : public tasking::Component {
  public:
    tasking::PortTypes port_types() const override { return {{}, {attitude_type_id}}; }

    tasking::LifecycleResult configure(const tasking::ComponentContext& context) override {
        const auto seed = context.int_param("seed", 1);
        const auto steps_max = context.int_param("steps_per_execution_max", 6000);
        const auto out_dir = context.string_param("out_dir", "");
        const auto log = context.bool_param("log", true);
        if (!seed || !steps_max || !out_dir || !log) {
            return tasking::LifecycleResult::failed(
                "aocs: seed and steps_per_execution_max must be integers, out_dir a string, log a "
                "boolean");
        }
        if (*steps_max < 1 || *steps_max > kCatchUpMax) {
            return tasking::LifecycleResult::failed(
                "aocs: steps_per_execution_max must be within 1.." + std::to_string(kCatchUpMax));
        }
        truth_config_ = {};
        truth_config_.seed = static_cast<std::uint64_t>(*seed);
        steps_per_execution_max_ = static_cast<std::uint64_t>(*steps_max);
        out_dir_parameter_ = *out_dir;
        log_ = *log;
        task_ = context.task;
        return tasking::LifecycleResult::ok();
    }

    tasking::LifecycleResult activate(const std::optional<tasking::Snapshot>& snapshot) override {
        activated_ns_ = wall_clock_ns();
        truth_ = std::make_unique<aocs::TruthSimulator>(truth_config_);
        // The initial star-tracker reading draws from the simulator's generator: a restored
        // instance draws it too, so its simulator replays the same sensor samples.
        const aocs::Quaternion initial = truth_->initial_star_tracker();
        if (snapshot && !snapshot->payload.empty()) {
            tasking::ByteReader reader(snapshot->payload);
            const std::uint32_t version = reader.u32();
            const std::int64_t world_start = reader.i64();
            const std::uint64_t truth_step = reader.u64();
            const std::uint64_t seed = reader.u64();
            const std::vector<std::uint8_t> filter = reader.bytes();
            if (reader.fail() || !reader.at_end() || version != kStateVersion) {
                return tasking::LifecycleResult::failed(
                    "aocs snapshot is corrupt or of another version");
            }
            if (seed != truth_config_.seed) {
                return tasking::LifecycleResult::failed("aocs snapshot is of another truth seed");
            }
            try {
                estimator_ = std::make_unique<aocs::AttitudeEstimator>(
                    aocs::AttitudeEstimator::from_snapshot(filter));
            } catch (const std::exception& error) {
                return tasking::LifecycleResult::failed(std::string("aocs snapshot: ") +
                                                        error.what());
            }
            world_start_ns_ = world_start;
            truth_->advance_to(truth_step);
            restored_ = true;
            spdlog::info("{}: restored at step {} (t = {:.2f} s of the world); replaying to now",
                         task_, truth_step,
                         static_cast<double>(truth_step) * truth_config_.gyro_period_s);
        } else {
            estimator_ =
                std::make_unique<aocs::AttitudeEstimator>(aocs::EstimatorConfig{}, initial);
            world_start_ns_ = activated_ns_;
            restored_ = false;
        }
        open_log();
        return tasking::LifecycleResult::ok();
    }

    tasking::ExecutionResult execute(const tasking::Inputs&, tasking::Outputs& outputs) override {
        const std::int64_t now_ns = wall_clock_ns();
        const double period_s = truth_config_.gyro_period_s;
        const auto due = static_cast<std::uint64_t>(std::max<double>(
            0, std::floor(static_cast<double>(now_ns - world_start_ns_) / 1e9 / period_s)));
        std::uint64_t stepped = 0;
        double error_rad = last_error_rad_;
        while (truth_->steps() < due && stepped < steps_per_execution_max_) {
            const aocs::TruthSample sample = truth_->next();
            try {
                estimator_->step(sample.gyro_rad_per_s, sample.time_s - estimator_->time_s(),
                                 sample.star_tracker);
            } catch (const std::invalid_argument& error) {
                spdlog::warn("{}: step {} rejected: {}", task_, truth_->steps(), error.what());
                return {tasking::Outcome::failure, estimator_->attitude_sigma_rad()};
            }
            error_rad = aocs::angle_between_rad(estimator_->attitude(), sample.true_attitude);
            const auto sample_ns = world_start_ns_ + static_cast<std::int64_t>(sample.time_s * 1e9);
            // Samples older than this activation are replayed, the rest live.
            const bool replay = sample_ns < activated_ns_;
            write_log(truth_->steps(), sample.time_s, error_rad, replay, now_ns);
            ++stepped;
        }
        last_error_rad_ = error_rad;
        if (stepped > 0) {
            std::vector<std::uint8_t> report;
            tasking::put_u64(report, truth_->steps());
            tasking::put_u64(report, static_cast<std::uint64_t>(std::llround(error_rad * 1e12)));
            outputs.emit(attitude_type_id, std::move(report));
        }
        return {tasking::Outcome::success, estimator_->attitude_sigma_rad()};
    }

    tasking::Snapshot deactivate() override {
        tasking::Snapshot state = snapshot();
        log_file_.close();
        return state;
    }

    tasking::Snapshot snapshot() const override {
        tasking::Snapshot state;
        if (!estimator_ || !truth_) return state;
        tasking::put_u32(state.payload, kStateVersion);
        tasking::put_i64(state.payload, world_start_ns_);
        tasking::put_u64(state.payload, truth_->steps());
        tasking::put_u64(state.payload, truth_config_.seed);
        tasking::put_bytes(state.payload, estimator_->snapshot());
        return state;
    }

  private:
    void open_log() {
        log_file_.close();
        if (!log_) return;
        const std::filesystem::path dir = output_directory(out_dir_parameter_);
        std::error_code error;
        std::filesystem::create_directories(dir, error);
        log_file_.open(dir / "aocs.ndjson", std::ios::app);
        if (!log_file_) spdlog::warn("{}: cannot write {}", task_, (dir / "aocs.ndjson").string());
    }

    void write_log(std::uint64_t step, double time_s, double error_rad, bool replay,
                   std::int64_t now_ns) {
        if (!log_file_) return;
        // One write per line on a file opened for appending: instances on several nodes can
        // share the file.
        const std::string line = fsm::JsonObject()
                                     .field("step", step)
                                     .field("time_s", time_s)
                                     .field("error_rad", error_rad)
                                     .field("sigma_rad", estimator_->attitude_sigma_rad())
                                     .field("pid", static_cast<std::int64_t>(::getpid()))
                                     .field("mode", replay ? "replay" : "live")
                                     .field("restored", restored_)
                                     .field("t_ns", now_ns)
                                     .str() +
                                 "\n";
        log_file_.write(line.data(), static_cast<std::streamsize>(line.size()));
        log_file_.flush();
    }

    std::string task_ = "aocs";
    aocs::TruthConfig truth_config_{};
    std::uint64_t steps_per_execution_max_ = 6000;
    std::string out_dir_parameter_;
    bool log_ = true;

    std::unique_ptr<aocs::TruthSimulator> truth_;
    std::unique_ptr<aocs::AttitudeEstimator> estimator_;
    std::int64_t world_start_ns_ = 0;
    std::int64_t activated_ns_ = 0;
    bool restored_ = false;
    double last_error_rad_ = 0;
    std::ofstream log_file_;
};

// The radio: takes the sink's accounting and keeps what is ready to send down.
class DownlinkComponent final : public tasking::Component {
  public:
    tasking::PortTypes port_types() const override { return {{accounting_type_id}, {}}; }

    tasking::LifecycleResult configure(const tasking::ComponentContext& context) override {
        task_ = context.task;
        return tasking::LifecycleResult::ok();
    }

    tasking::LifecycleResult activate(const std::optional<tasking::Snapshot>& snapshot) override {
        ready_ = 0;
        if (snapshot && !snapshot->payload.empty()) {
            tasking::ByteReader reader(snapshot->payload);
            const std::uint64_t ready = reader.u64();
            if (reader.fail() || !reader.at_end()) {
                return tasking::LifecycleResult::failed("downlink snapshot is corrupt");
            }
            ready_ = ready;
        }
        return tasking::LifecycleResult::ok();
    }

    tasking::ExecutionResult execute(const tasking::Inputs& inputs, tasking::Outputs&) override {
        for (std::size_t index = 0; index < inputs.size(); ++index) {
            const tasking::Sample* sample = inputs.get(index);
            if (sample == nullptr || sample->payload == nullptr) continue;
            try {
                const Accounting accounting = deserialise_accounting(*sample->payload);
                if (accounting.recorded > ready_) {
                    spdlog::info("{}: {} images recorded, all up to {} ready to send", task_,
                                 accounting.recorded, accounting.watermark);
                }
                ready_ = std::max(ready_, accounting.recorded);
            } catch (const std::exception& error) {
                spdlog::warn("{}: ignored an accounting sample: {}", task_, error.what());
                return {tasking::Outcome::failure, static_cast<double>(ready_)};
            }
        }
        return {tasking::Outcome::success, static_cast<double>(ready_)};
    }

    tasking::Snapshot deactivate() override { return snapshot(); }

    tasking::Snapshot snapshot() const override {
        tasking::Snapshot state;
        tasking::put_u64(state.payload, ready_);
        return state;
    }

  private:
    std::string task_ = "downlink";
    std::uint64_t ready_ = 0;
};

}  // namespace

tasking::ComponentPtr make_aocs_component() {
    return std::make_unique<AocsComponent>();
}

tasking::ComponentPtr make_downlink_component() {
    return std::make_unique<DownlinkComponent>();
}

bool register_eo_components(tasking::ComponentRegistry& registry) {
    bool all = registry.add("sensor", make_sensor_component);
    all = registry.add("acca", make_acca_component) && all;
    all = registry.add("sink", make_sink_component) && all;
    all = registry.add("aocs", make_aocs_component) && all;
    all = registry.add("downlink", make_downlink_component) && all;
    return all;
}

}  // namespace keel::eo::components
