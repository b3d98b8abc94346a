// keel-eo: runs the earth-observation components without the runtime, for trying them
// out and for the benchmark (tests/bench/bench-eo).
//
//   keel-eo scene --seed 7 --out DIR            write a synthetic scene as band PNGs + wire buffer
//   keel-eo acca --seed 7 --count 20 --json     generate, classify, report accuracy and ms/image
//   keel-eo acca --in DIR --out OUT             classify scenes read from band images
//   keel-eo aocs --migrate-at 500 --json        attitude error across a task migration
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "keel/eo/acca.hpp"
#include "keel/eo/aocs.hpp"
#include "keel/eo/codec.hpp"
#include "keel/eo/scene.hpp"
#include "keel/eo/sensor.hpp"
#include "keel/eo/sink.hpp"

namespace {

namespace fs = std::filesystem;
using namespace keel::eo;
using Clock = std::chrono::steady_clock;

// CPU time of the whole process (all threads): with other work on a shared machine,
// wall time overstates what the classification itself costs.
double process_cpu_ms() {
    timespec now{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

double elapsed_ms(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::string num(double value) {
    if (!std::isfinite(value)) return "null";
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value);
    return text;
}

// Nearest-rank percentile of a non-empty sample.
double percentile(std::vector<double> values, double p) {
    std::sort(values.begin(), values.end());
    const auto rank =
        static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(values.size())));
    return values[std::min(values.size() - 1, rank == 0 ? 0 : rank - 1)];
}

double mean(const std::vector<double>& values) {
    double sum = 0;
    for (double v : values) sum += v;
    return values.empty() ? NAN : sum / static_cast<double>(values.size());
}

std::string distribution(const std::vector<double>& values) {
    if (values.empty()) return "null";
    return "{\"p50\":" + num(percentile(values, 50)) + ",\"p99\":" + num(percentile(values, 99)) +
           ",\"mean\":" + num(mean(values)) +
           ",\"min\":" + num(*std::min_element(values.begin(), values.end())) +
           ",\"max\":" + num(*std::max_element(values.begin(), values.end())) + "}";
}

struct SceneOptions {
    std::uint64_t seed = 7;
    int size_px = 2048;
    int count = 1;
    std::string out;
    bool json = false;
};

int run_scene(const SceneOptions& options) {
    sensor::SensorConfig config;
    config.base_seed = options.seed;
    config.spec.width_px = config.spec.height_px = options.size_px;
    sensor::Sensor camera(config);
    for (int i = 0; i < options.count; ++i) {
        const auto start = Clock::now();
        sensor::SceneComposition composition;
        const auto sequence = camera.sequence();
        const Scene scene =
            sensor::generate_scene(camera.seed_for(sequence), sequence, config.spec, &composition);
        (void)camera.next();  // keep the stream's sequence in step with what was written
        const double generate_ms = elapsed_ms(start);
        const fs::path folder = options.count == 1
                                    ? fs::path(options.out)
                                    : fs::path(options.out) / ("scene-" + std::to_string(i));
        sensor::write_band_folder(scene, folder);
        const auto bytes = serialise(scene);
        std::ofstream(folder / "scene.kscn", std::ios::binary)
            .write(reinterpret_cast<const char*>(bytes.data()),
                   static_cast<std::streamsize>(bytes.size()));
        const std::string line =
            "{\"sequence\":" + std::to_string(scene.sequence) +
            ",\"seed\":" + std::to_string(scene.seed) + ",\"folder\":\"" + folder.string() +
            "\",\"bytes\":" + std::to_string(bytes.size()) +
            ",\"generate_ms\":" + num(generate_ms) +
            ",\"water_fraction\":" + num(composition.water_fraction) +
            ",\"vegetation_fraction\":" + num(composition.vegetation_fraction) +
            ",\"snow_fraction\":" + num(composition.snow_fraction) +
            ",\"truth_cloud_fraction\":" + num(composition.truth_cloud_fraction) +
            ",\"thin_cloud_fraction\":" + num(composition.thin_cloud_fraction) + "}";
        if (options.json) {
            std::cout << line << '\n';
        } else {
            std::printf(
                "scene %d -> %s (%zu bytes on the wire, cloud %.1f %%, generated in %.0f ms)\n", i,
                folder.string().c_str(), bytes.size(), 100 * composition.truth_cloud_fraction,
                generate_ms);
        }
    }
    return 0;
}

// Where the classification errors of synthetic scenes lie, as fractions of all pixels:
// false alarms by what was under them (clear sky, or haze the truth counts as clear),
// misses by how opaque the missed cloud was.
struct ErrorBreakdown {
    static constexpr int kCovers = 4;
    double false_alarm_clear[kCovers] = {};
    double false_alarm_haze[kCovers] = {};
    double missed_thin = 0;   // opacity below 0.5
    double missed_thick = 0;  // opacity 0.5 and above
    double pixels = 0;

    void add(const cv::Mat& mask, const cv::Mat& truth,
             const sensor::SceneComposition& composition) {
        cv::Mat false_alarm, missed, hazy, clear, selected, thick;
        cv::compare(mask, truth, false_alarm, cv::CMP_GT);  // mask 255, truth 0
        cv::compare(mask, truth, missed, cv::CMP_LT);
        cv::compare(composition.opacity, 0.02, hazy, cv::CMP_GT);
        cv::bitwise_not(hazy, clear);
        for (int cover = 0; cover < kCovers; ++cover) {
            cv::Mat of_cover;
            cv::compare(composition.dominant_cover, cover, of_cover, cv::CMP_EQ);
            cv::bitwise_and(false_alarm, of_cover, selected);
            cv::Mat under_haze;
            cv::bitwise_and(selected, hazy, under_haze);
            false_alarm_haze[cover] += cv::countNonZero(under_haze);
            cv::bitwise_and(selected, clear, selected);
            false_alarm_clear[cover] += cv::countNonZero(selected);
        }
        cv::compare(composition.opacity, 0.5, thick, cv::CMP_GE);
        cv::bitwise_and(missed, thick, selected);
        const int missed_thick_count = cv::countNonZero(selected);
        missed_thick += missed_thick_count;
        missed_thin += cv::countNonZero(missed) - missed_thick_count;
        pixels += static_cast<double>(mask.total());
    }

    std::string json() const {
        std::string out = "{\"false_alarm_clear\":{";
        for (int cover = 0; cover < kCovers; ++cover) {
            out += std::string(cover ? "," : "") + "\"" + sensor::kSurfaceCoverNames[cover] +
                   "\":" + num(false_alarm_clear[cover] / pixels);
        }
        out += "},\"false_alarm_under_haze\":{";
        for (int cover = 0; cover < kCovers; ++cover) {
            out += std::string(cover ? "," : "") + "\"" + sensor::kSurfaceCoverNames[cover] +
                   "\":" + num(false_alarm_haze[cover] / pixels);
        }
        out += "},\"missed_opacity_below_0_5\":" + num(missed_thin / pixels) +
               ",\"missed_opacity_0_5_and_above\":" + num(missed_thick / pixels) + "}";
        return out;
    }
};

struct AccaOptions {
    std::uint64_t seed = 7;
    int size_px = 2048;
    int count = 20;
    std::string in;
    std::string out;
    double overlay_scale = 0.25;
    double too_cloudy_fraction = 0.5;
    bool json = false;
};

int run_acca(const AccaOptions& options) {
    sensor::SensorConfig sensor_config;
    sensor_config.base_seed = options.seed;
    sensor_config.spec.width_px = sensor_config.spec.height_px = options.size_px;
    if (!options.in.empty()) sensor_config.folder = options.in;
    sensor::Sensor camera(sensor_config);
    acca::Config acca_config;
    acca_config.too_cloudy_fraction = options.too_cloudy_fraction;
    std::optional<sink::Sink> recorder;
    if (!options.out.empty()) {
        recorder.emplace(
            sink::SinkConfig{.out_dir = options.out, .overlay_scale = options.overlay_scale});
    }

    std::vector<double> compute_ms, compute_cpu_ms, generate_ms, serialise_ms, deserialise_ms,
        accuracy, precision, recall;
    int too_cloudy = 0;
    std::size_t scene_bytes = 0;
    ErrorBreakdown errors;
    const bool synthetic = options.in.empty();
    for (int i = 0; i < options.count; ++i) {
        auto start = Clock::now();
        // Synthetic scenes are generated here rather than by camera.next() so the generator's
        // opacity and cover maps are at hand for the error breakdown; the seeds are the same.
        sensor::SceneComposition composition;
        const auto sequence = static_cast<std::uint64_t>(i);
        const Scene generated = synthetic
                                    ? sensor::generate_scene(camera.seed_for(sequence), sequence,
                                                             sensor_config.spec, &composition)
                                    : camera.next();
        generate_ms.push_back(elapsed_ms(start));
        // Ship the scene through its wire format, as the runtime will between nodes.
        start = Clock::now();
        const auto bytes = serialise(generated);
        serialise_ms.push_back(elapsed_ms(start));
        start = Clock::now();
        const Scene scene = deserialise_scene(bytes);
        deserialise_ms.push_back(elapsed_ms(start));
        scene_bytes = bytes.size();

        const double cpu_start_ms = process_cpu_ms();
        const acca::Result result = acca::classify(scene, acca_config);
        compute_cpu_ms.push_back(process_cpu_ms() - cpu_start_ms);
        compute_ms.push_back(result.compute_ms);
        if (synthetic) errors.add(result.cloud_mask, scene.truth_mask, composition);
        too_cloudy += result.too_cloudy ? 1 : 0;
        const sink::ImageStats stats =
            recorder ? recorder->consume(scene, result) : sink::make_stats(scene, result);
        if (stats.versus_truth) {
            accuracy.push_back(stats.versus_truth->accuracy());
            precision.push_back(stats.versus_truth->precision());
            recall.push_back(stats.versus_truth->recall());
        }
        if (options.json) {
            std::cout << sink::to_json_line(stats) << '\n';
        } else {
            std::printf("image %3llu: cloud %5.1f %%%s  %6.1f ms",
                        static_cast<unsigned long long>(stats.sequence), 100 * stats.cloud_fraction,
                        stats.too_cloudy ? " (too cloudy)" : "             ", stats.compute_ms);
            if (stats.versus_truth) {
                std::printf("  accuracy %.4f precision %.4f recall %.4f",
                            stats.versus_truth->accuracy(), stats.versus_truth->precision(),
                            stats.versus_truth->recall());
            }
            std::printf("\n");
        }
    }
    const std::string summary =
        "{\"summary\":{\"images\":" + std::to_string(options.count) +
        ",\"width\":" + std::to_string(options.size_px) +
        ",\"height\":" + std::to_string(options.size_px) +
        ",\"scene_bytes\":" + std::to_string(scene_bytes) +
        ",\"acca_compute_ms\":" + distribution(compute_ms) +
        ",\"acca_compute_cpu_ms\":" + distribution(compute_cpu_ms) +
        ",\"generate_ms\":" + distribution(generate_ms) +
        ",\"serialise_ms\":" + distribution(serialise_ms) +
        ",\"deserialise_ms\":" + distribution(deserialise_ms) +
        ",\"accuracy\":" + distribution(accuracy) + ",\"precision\":" + distribution(precision) +
        ",\"recall\":" + distribution(recall) +
        ",\"too_cloudy_images\":" + std::to_string(too_cloudy) +
        ",\"errors\":" + (synthetic ? errors.json() : std::string("null")) + "}}";
    if (options.json) {
        std::cout << summary << '\n';
    } else if (!compute_ms.empty()) {
        std::printf("ACCA %dx%d: p50 %.1f ms, p99 %.1f ms per image", options.size_px,
                    options.size_px, percentile(compute_ms, 50), percentile(compute_ms, 99));
        if (!accuracy.empty()) {
            std::printf("; accuracy mean %.4f, min %.4f", mean(accuracy),
                        *std::min_element(accuracy.begin(), accuracy.end()));
        }
        std::printf("; %d of %d too cloudy\n", too_cloudy, options.count);
    }
    return 0;
}

struct AocsOptions {
    std::uint64_t seed = 1;
    int steps = 2000;
    int migrate_at = 500;
    int checkpoint_every = 1;
    int outage_steps = 0;
    bool no_replay = false;
    int history_depth = 200;
    bool json = false;
};

int run_aocs(const AocsOptions& options) {
    if (options.migrate_at < 1 || options.migrate_at + options.outage_steps >= options.steps) {
        std::cerr
            << "keel-eo aocs: need 1 <= --migrate-at and --migrate-at + --outage-steps < --steps\n";
        return 2;
    }
    aocs::RunConfig config;
    config.truth.seed = options.seed;
    config.steps = options.steps;
    config.checkpoint_every_steps = options.checkpoint_every;
    config.replay_lost_samples = !options.no_replay;
    config.history_depth_samples = options.history_depth;
    const aocs::RunReport reference = aocs::run(config);
    config.migrate_after_step = options.migrate_at;
    config.outage_steps = options.outage_steps;
    const aocs::RunReport migrated = aocs::run(config);

    // The nominal step is taken from the reference's converged part: from half-way to the
    // migration point, when the bias estimate has settled.
    const int from_step = std::max(2, options.migrate_at / 2);
    const double nominal = aocs::nominal_step_rad(reference, from_step);
    std::vector<double> steady;
    for (std::size_t i = static_cast<std::size_t>(from_step - 1); i < reference.error_rad.size();
         ++i) {
        steady.push_back(reference.error_rad[i]);
    }
    std::vector<double> step_changes;
    for (std::size_t i = static_cast<std::size_t>(from_step - 1); i < reference.error_rad.size();
         ++i) {
        step_changes.push_back(std::abs(reference.error_rad[i] - reference.error_rad[i - 1]));
    }
    double after_max_rad = 0;
    for (std::size_t i = static_cast<std::size_t>(migrated.resumed_at_step - 1);
         i < migrated.error_rad.size(); ++i) {
        after_max_rad = std::max(after_max_rad, migrated.error_rad[i]);
    }
    // Cost of one checkpoint round trip.
    aocs::AttitudeEstimator estimator;
    const auto start = Clock::now();
    constexpr int kRounds = 1000;
    for (int i = 0; i < kRounds; ++i) estimator.restore(estimator.snapshot());
    const double round_trip_us = elapsed_ms(start) * 1000.0 / kRounds;

    const auto before = migrated.error_rad[static_cast<std::size_t>(options.migrate_at - 1)];
    const auto after = migrated.error_rad[static_cast<std::size_t>(migrated.resumed_at_step - 1)];
    if (options.json) {
        std::cout << "{\"seed\":" << options.seed << ",\"steps\":" << options.steps
                  << ",\"gyro_period_s\":" << num(config.truth.gyro_period_s)
                  << ",\"star_tracker_every_steps\":" << config.truth.star_tracker_every_steps
                  << ",\"migrate_after_step\":" << options.migrate_at
                  << ",\"checkpoint_every_steps\":" << options.checkpoint_every
                  << ",\"outage_steps\":" << options.outage_steps
                  << ",\"replay\":" << (options.no_replay ? "false" : "true")
                  << ",\"replayed_samples\":" << migrated.replayed_samples
                  << ",\"resumed_at_step\":" << migrated.resumed_at_step
                  << ",\"error_before_rad\":" << num(before)
                  << ",\"error_after_rad\":" << num(after)
                  << ",\"jump_rad\":" << num(migrated.jump_rad)
                  << ",\"nominal_step_rad\":" << num(nominal)
                  << ",\"step_change_p50_rad\":" << num(percentile(step_changes, 50))
                  << ",\"jump_over_nominal\":" << num(migrated.jump_rad / nominal)
                  << ",\"jump_within_nominal\":"
                  << (migrated.jump_rad <= nominal ? "true" : "false")
                  << ",\"reference_error_rad\":" << distribution(steady)
                  << ",\"migrated_error_max_after_resume_rad\":" << num(after_max_rad)
                  << ",\"snapshot_bytes\":" << migrated.snapshot_bytes
                  << ",\"snapshot_restore_us\":" << num(round_trip_us) << "}\n";
    } else {
        std::printf(
            "AOCS migration after step %d (checkpoint every %d, outage %d steps), resumed at step "
            "%d after "
            "replaying %d samples\n",
            options.migrate_at, options.checkpoint_every, options.outage_steps,
            migrated.resumed_at_step, migrated.replayed_samples);
        std::printf(
            "  attitude error %.3g rad before, %.3g rad after: jump %.3g rad vs nominal step %.3g "
            "rad (%s)\n",
            before, after, migrated.jump_rad, nominal,
            migrated.jump_rad <= nominal ? "within" : "EXCEEDS");
        std::printf(
            "  reference error p50 %.3g rad, max %.3g rad; checkpoint %llu bytes, %.1f us per "
            "round trip\n",
            percentile(steady, 50), *std::max_element(steady.begin(), steady.end()),
            static_cast<unsigned long long>(migrated.snapshot_bytes), round_trip_us);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "Keel earth-observation components: sensor, ACCA, sink and AOCS without the runtime"};
    app.require_subcommand(1);

    SceneOptions scene_options;
    auto* scene = app.add_subcommand(
        "scene", "write synthetic scenes as band PNGs, truth.png and scene.kscn");
    scene->add_option("--seed", scene_options.seed, "base seed of the sensor stream");
    scene->add_option("--size", scene_options.size_px, "side in pixels")
        ->check(CLI::Range(16, 16384));
    scene
        ->add_option("--count", scene_options.count,
                     "scenes to write (sub-folders when more than one)")
        ->check(CLI::PositiveNumber);
    scene->add_option("--out", scene_options.out, "output folder")->required();
    scene->add_flag("--json", scene_options.json, "one JSON line per scene");

    AccaOptions acca_options;
    auto* acca_cmd = app.add_subcommand(
        "acca", "generate (or read) scenes, classify them, report accuracy and time");
    acca_cmd->add_option("--seed", acca_options.seed, "base seed of the sensor stream");
    acca_cmd->add_option("--size", acca_options.size_px, "side in pixels")
        ->check(CLI::Range(16, 16384));
    acca_cmd->add_option("--count", acca_options.count, "images")->check(CLI::PositiveNumber);
    acca_cmd->add_option("--in", acca_options.in, "read band images from this folder instead")
        ->check(CLI::ExistingDirectory);
    acca_cmd->add_option("--out", acca_options.out, "write overlays and stats.ndjson here");
    acca_cmd
        ->add_option("--overlay-scale", acca_options.overlay_scale,
                     "overlay size relative to the scene")
        ->check(CLI::Range(0.01, 1.0));
    acca_cmd
        ->add_option("--too-cloudy", acca_options.too_cloudy_fraction,
                     "cloud fraction above which not to downlink")
        ->check(CLI::Range(0.0, 1.0));
    acca_cmd->add_flag("--json", acca_options.json, "a JSON line per image, then a summary line");

    AocsOptions aocs_options;
    auto* aocs_cmd = app.add_subcommand(
        "aocs", "run the attitude filter against the truth and migrate it mid-run");
    aocs_cmd->add_option("--seed", aocs_options.seed, "truth simulator seed");
    aocs_cmd->add_option("--steps", aocs_options.steps, "gyro steps (100 Hz)")
        ->check(CLI::Range(4, 10'000'000));
    aocs_cmd->add_option("--migrate-at", aocs_options.migrate_at,
                         "the hosting node fails after this step");
    aocs_cmd
        ->add_option("--checkpoint-every", aocs_options.checkpoint_every,
                     "steps between checkpoints")
        ->check(CLI::PositiveNumber);
    aocs_cmd
        ->add_option("--outage-steps", aocs_options.outage_steps,
                     "samples lost while the task is re-placed")
        ->check(CLI::NonNegativeNumber);
    aocs_cmd->add_flag("--no-replay", aocs_options.no_replay,
                       "bridge the gap in one propagation instead of replaying missed samples");
    aocs_cmd->add_option("--history-depth", aocs_options.history_depth, "samples kept for replay")
        ->check(CLI::PositiveNumber);
    aocs_cmd->add_flag("--json", aocs_options.json, "one JSON object");

    CLI11_PARSE(app, argc, argv);
    try {
        if (scene->parsed()) return run_scene(scene_options);
        if (acca_cmd->parsed()) return run_acca(acca_options);
        return run_aocs(aocs_options);
    } catch (const std::exception& error) {
        std::cerr << "keel-eo: " << error.what() << '\n';
        return 1;
    }
}
