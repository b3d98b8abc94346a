// The camera task: streams scenes from a pool generated in the background, and keeps each
// emitted scene until the sink's accounting covers it (DESIGN.md, "Every image accounted
// for").
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <vector>
#include <optional>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <thread>

#include "core/fsm/json.hpp"
#include "core/tasking/bytes.hpp"
#include "keel/eo/components.hpp"
#include "keel/eo/sensor.hpp"

namespace keel::eo::components {

namespace {

constexpr std::int64_t kSceneSideMin = 16;
constexpr std::int64_t kPoolMax = 64;
constexpr std::size_t kResendsPerExecutionMax = 4;

std::int64_t wall_clock_ns() {
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

struct PooledScene {
    tasking::Payload bytes;  // KSCN with sequence 0
    std::uint32_t body_crc = 0;
};

struct Emitted {
    std::uint64_t sequence = 0;
    std::size_t pool_index = 0;
    std::int64_t last_emit_ns = 0;
    std::uint32_t resends = 0;
};

class SensorComponent final : public tasking::Component {
  public:
    ~SensorComponent() override { join_generators(); }

    tasking::PortTypes port_types() const override {
        return {{accounting_type_id}, {scene_type_id}};
    }

    tasking::LifecycleResult configure(const tasking::ComponentContext& context) override {
        const auto size = context.int_param("scene_size_px", 2048);
        const auto pool = context.int_param("pool_size", 20);
        const auto seed = context.int_param("base_seed", 7);
        const auto resend_after = context.int_param("resend_after_ms", 1500);
        const auto resend_max = context.int_param("resend_max", 10);
        const auto window = context.int_param("window_max", 256);
        const auto out_dir = context.string_param("out_dir", "");
        const auto log = context.bool_param("log", true);
        if (!size || !pool || !seed || !resend_after || !resend_max || !window || !out_dir ||
            !log) {
            return tasking::LifecycleResult::failed(
                "sensor: scene_size_px, pool_size, base_seed, resend_after_ms, resend_max and "
                "window_max must be integers, out_dir a string, log a boolean");
        }
        if (*size < kSceneSideMin || *size > static_cast<std::int64_t>(kSceneSideMax)) {
            return tasking::LifecycleResult::failed("sensor: scene_size_px must be within " +
                                                    std::to_string(kSceneSideMin) + ".." +
                                                    std::to_string(kSceneSideMax));
        }
        if (*pool < 1 || *pool > kPoolMax) {
            return tasking::LifecycleResult::failed("sensor: pool_size must be within 1.." +
                                                    std::to_string(kPoolMax));
        }
        if (*resend_after < 1 || *resend_max < 0 || *window < 1) {
            return tasking::LifecycleResult::failed(
                "sensor: resend_after_ms and window_max must be positive, resend_max not negative");
        }
        stop_generator();
        const int side = static_cast<int>(*size);
        const auto pool_size = static_cast<std::size_t>(*pool);
        const auto base_seed = static_cast<std::uint64_t>(*seed);
        if (side != side_px_ || pool_size != pool_size_ || base_seed != base_seed_) {
            std::lock_guard lock(pool_mutex_);
            pool_.clear();
        }
        side_px_ = side;
        pool_size_ = pool_size;
        base_seed_ = base_seed;
        resend_after_ns_ = *resend_after * 1'000'000;
        resend_max_ = static_cast<std::uint32_t>(*resend_max);
        window_max_ = static_cast<std::size_t>(*window);
        out_dir_parameter_ = *out_dir;
        log_ = *log;
        task_ = context.task;
        return tasking::LifecycleResult::ok();
    }

    tasking::LifecycleResult activate(const std::optional<tasking::Snapshot>& snapshot) override {
        next_sequence_ = 1;
        window_.clear();
        if (snapshot) {
            tasking::ByteReader reader(snapshot->payload);
            const std::uint64_t next = reader.u64();
            if (reader.fail() || !reader.at_end() || next == 0) {
                return tasking::LifecycleResult::failed("sensor snapshot is corrupt");
            }
            next_sequence_ = next;
        }
        start_generator();
        log_file_.close();
        if (log_) {
            const std::filesystem::path dir = output_directory(out_dir_parameter_);
            std::error_code error;
            std::filesystem::create_directories(dir, error);
            log_file_.open(dir / "camera.ndjson", std::ios::app);
            if (!log_file_)
                spdlog::warn("{}: cannot write {}", task_, (dir / "camera.ndjson").string());
        }
        return tasking::LifecycleResult::ok();
    }

    tasking::ExecutionResult execute(const tasking::Inputs& inputs,
                                     tasking::Outputs& outputs) override {
        const std::int64_t now_ns = outputs.timestamp_ns();
        for (std::size_t index = 0; index < inputs.size(); ++index) {
            const tasking::Sample* sample = inputs.get(index);
            if (sample == nullptr || sample->payload == nullptr) continue;
            try {
                absorb(deserialise_accounting(*sample->payload));
            } catch (const std::exception& error) {
                spdlog::warn("{}: ignored an accounting sample: {}", task_, error.what());
            }
        }
        std::vector<PooledScene> pool = ready_pool();
        resend_overdue(pool, now_ns, outputs);
        if (inputs.trigger() == tasking::Trigger::timer && !pool.empty()) {
            const std::uint64_t sequence = next_sequence_++;
            const std::size_t index = static_cast<std::size_t>((sequence - 1) % pool.size());
            outputs.emit(scene_type_id,
                         restamp_scene(*pool[index].bytes, sequence, pool[index].body_crc));
            window_.push_back({sequence, index, now_ns, 0});
            write_log(sequence, 0);
            while (window_.size() > window_max_) {
                spdlog::warn("{}: scene {} abandoned: more than {} scenes await the sink", task_,
                             window_.front().sequence, window_max_);
                window_.pop_front();
                ++abandoned_;
            }
        }
        return {tasking::Outcome::success, static_cast<double>(next_sequence_ - 1)};
    }

    tasking::Snapshot deactivate() override {
        stop_generator();
        log_file_.close();
        return snapshot();
    }

    tasking::Snapshot snapshot() const override {
        tasking::Snapshot state;
        tasking::put_u64(state.payload, next_sequence_);
        return state;
    }

  private:
    void absorb(const Accounting& accounting) {
        std::erase_if(window_,
                      [&](const Emitted& emitted) { return accounting.covers(emitted.sequence); });
    }

    void resend_overdue(const std::vector<PooledScene>& pool, std::int64_t now_ns,
                        tasking::Outputs& outputs) {
        std::size_t sent = 0;
        for (auto it = window_.begin(); it != window_.end() && sent < kResendsPerExecutionMax;) {
            if (now_ns - it->last_emit_ns < resend_after_ns_ || it->pool_index >= pool.size()) {
                ++it;
                continue;
            }
            if (it->resends >= resend_max_) {
                spdlog::warn("{}: scene {} abandoned after {} resends", task_, it->sequence,
                             it->resends);
                ++abandoned_;
                it = window_.erase(it);
                continue;
            }
            ++it->resends;
            it->last_emit_ns = now_ns;
            const PooledScene& scene = pool[it->pool_index];
            outputs.emit(scene_type_id, restamp_scene(*scene.bytes, it->sequence, scene.body_crc));
            write_log(it->sequence, it->resends);
            spdlog::info("{}: scene {} not yet recorded by the sink: sent again ({})", task_,
                         it->sequence, it->resends);
            ++sent;
            ++it;
        }
    }

    // What the camera emitted, for the demo's accounting: one line per emission.
    void write_log(std::uint64_t sequence, std::uint32_t resend) {
        if (!log_file_) return;
        const std::string line = fsm::JsonObject()
                                     .field("sequence", sequence)
                                     .field("resend", resend)
                                     .field("t_ns", wall_clock_ns())
                                     .str() +
                                 "\n";
        log_file_.write(line.data(), static_cast<std::streamsize>(line.size()));
        log_file_.flush();
    }

    std::vector<PooledScene> ready_pool() const {
        std::lock_guard lock(pool_mutex_);
        return pool_;
    }

    void start_generator() {
        stop_generator();
        {
            std::lock_guard lock(pool_mutex_);
            if (pool_.size() >= pool_size_) return;
        }
        Generator generator;
        generator.stop = std::make_shared<std::atomic<bool>>(false);
        generator.done = std::make_shared<std::atomic<bool>>(false);
        generator.thread = std::thread([this, stop = generator.stop, done = generator.done] {
            generate(*stop);
            done->store(true);
        });
        generator_ = std::move(generator);
    }

    // Stops the generator without waiting for it: a scene under way (half a second at
    // 2048 px) is finished in the background and dropped, so a deactivation on the node's
    // loop does not hold its heartbeats back (keel-cluster saw the camera node excluded,
    // its loop blocked 0.4 s in a phase switch).
    void stop_generator() {
        if (generator_) {
            generator_->stop->store(true);
            retired_.push_back(std::move(*generator_));
            generator_.reset();
        }
        std::erase_if(retired_, [](Generator& retired) {
            if (!retired.done->load()) return false;
            retired.thread.join();
            return true;
        });
    }

    void join_generators() {
        stop_generator();
        for (Generator& retired : retired_) retired.thread.join();
        retired_.clear();
    }

    // Background: the scenes of the pool, one after the other. Scene i is emitted as soon as
    // it exists, so the stream starts after one scene's generation time, not the pool's.
    void generate(const std::atomic<bool>& stop) {
        // Generation is background work: it must not take the cores the node's event loop
        // needs for its heartbeats (a 2048 px scene keeps a core busy for half a second).
        // Linux gives each thread its own nice value; OpenCV runs this thread's work on it
        // alone (the camera node runs nothing else with OpenCV).
        (void)setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), 19);
        cv::setNumThreads(1);
        const auto start = std::chrono::steady_clock::now();
        // The pool is the start of the sensor library's own stream (the scenes Sensor::next
        // gives), so with the defaults it holds the 20 scenes bench-eo measures ACCA on.
        sensor::SensorConfig config;
        config.base_seed = base_seed_;
        config.spec.width_px = side_px_;
        config.spec.height_px = side_px_;
        const sensor::Sensor camera(config);
        for (;;) {
            std::size_t index = 0;
            {
                std::lock_guard lock(pool_mutex_);
                index = pool_.size();
            }
            if (index >= pool_size_ || stop.load()) break;
            const Scene scene = sensor::generate_scene(camera.seed_for(index), index, config.spec);
            std::vector<std::uint8_t> bytes = serialise(scene);
            PooledScene pooled{tasking::make_payload(std::move(bytes)), 0};
            pooled.body_crc = scene_body_crc(*pooled.bytes);
            std::lock_guard lock(pool_mutex_);
            // Stopped meanwhile: another generator (or another configuration) owns the
            // pool now, and this scene's index may already be taken.
            if (stop.load() || pool_.size() != index) break;
            pool_.push_back(std::move(pooled));
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::size_t ready = 0;
        {
            std::lock_guard lock(pool_mutex_);
            ready = pool_.size();
        }
        spdlog::info("{}: {} of {} scenes of {}x{} px in the pool ({:.1f} s{})", task_, ready,
                     pool_size_, side_px_, side_px_, seconds,
                     ready < pool_size_ ? ", stopped" : "");
    }

    std::string task_ = "camera";
    int side_px_ = 0;
    std::size_t pool_size_ = 0;
    std::uint64_t base_seed_ = 0;
    std::int64_t resend_after_ns_ = 0;
    std::uint32_t resend_max_ = 0;
    std::size_t window_max_ = 0;
    std::string out_dir_parameter_;
    bool log_ = true;
    std::ofstream log_file_;

    std::uint64_t next_sequence_ = 1;
    std::deque<Emitted> window_;
    std::uint64_t abandoned_ = 0;

    mutable std::mutex pool_mutex_;
    std::vector<PooledScene> pool_;
    struct Generator {
        std::thread thread;
        std::shared_ptr<std::atomic<bool>> stop;
        std::shared_ptr<std::atomic<bool>> done;
    };
    std::optional<Generator> generator_;
    std::vector<Generator> retired_;  // stopped, finishing a scene in the background
};

}  // namespace

tasking::ComponentPtr make_sensor_component() {
    return std::make_unique<SensorComponent>();
}

}  // namespace keel::eo::components
