// keel-sim: the deterministic cluster simulator (run, campaign, soak, scenario, bench).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <thread>

#include "core/fsm/json.hpp"
#include "core/mission/mission.hpp"
#include "nodes/sim/src/bench.hpp"
#include "nodes/sim/src/campaign.hpp"
#include "nodes/sim/src/mission_image.hpp"
#include "nodes/sim/src/plan.hpp"
#include "nodes/sim/src/scenario.hpp"
#include "nodes/sim/src/util.hpp"

namespace {

using namespace keel;
using namespace keel::sim;

struct Common {
    std::string mission_path;
    std::string mutant = "none";
    int period_ms = 0;  // 0: the mission's
    std::string loss;
    std::string duration = "5s";
    int max_failures = -1;  // -1: tolerance.node_failures + 1 (0 with --liar)
    bool liar = false;
    std::string disk_faults = "drawn";
    bool ground_pauses = false;
    bool ground_designates = false;
};

std::optional<mission::Mission> load(const Common& common) {
    std::string error;
    auto loaded = load_flown_mission(common.mission_path, &error);
    if (!loaded) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return std::nullopt;
    }
    mission::Mission result = std::move(*loaded);
    if (common.period_ms > 0) result.heartbeat.period_ms = common.period_ms;
    return result;
}

std::optional<RunOptions> run_options(const Common& common) {
    RunOptions options;
    auto mutant = fsm::parse_mutant(common.mutant);
    if (!mutant) {
        std::fprintf(stderr, "keel-sim: unknown mutant '%s'; known:", common.mutant.c_str());
        for (auto m : fsm::all_mutants()) std::fprintf(stderr, " %s", std::string(fsm::to_string(m)).c_str());
        std::fprintf(stderr, "\n");
        return std::nullopt;
    }
    options.mutant = *mutant;
    if (!common.loss.empty()) {
        auto loss = parse_rate(common.loss);
        if (!loss) {
            std::fprintf(stderr, "keel-sim: bad loss rate '%s'\n", common.loss.c_str());
            return std::nullopt;
        }
        options.plan.loss = *loss;
    }
    auto duration = parse_duration(common.duration);
    if (!duration || *duration <= 0) {
        std::fprintf(stderr, "keel-sim: bad duration '%s'\n", common.duration.c_str());
        return std::nullopt;
    }
    options.plan.fault_window_ns = *duration;
    if (common.max_failures >= 0) options.plan.max_failures = common.max_failures;
    options.plan.liar = common.liar;
    const auto disk_faults = parse_disk_faults(common.disk_faults);
    if (!disk_faults) {
        std::fprintf(stderr,
                     "keel-sim: unknown --disk-faults '%s'; known: all, storage-power-loss, master-power-loss, "
                     "storage-full\n",
                     common.disk_faults.c_str());
        return std::nullopt;
    }
    options.plan.disk_faults = *disk_faults;
    options.plan.ground_pauses = common.ground_pauses;
    options.plan.ground_designates = common.ground_designates;
    return options;
}

std::string replay_command(const Common& common) {
    std::string command = "keel-sim run " + common.mission_path;
    if (common.mutant != "none") command += " --mutant " + common.mutant;
    if (common.period_ms > 0) command += " --period " + std::to_string(common.period_ms);
    if (!common.loss.empty()) command += " --loss " + common.loss;
    if (common.duration != "5s") command += " --duration " + common.duration;
    if (common.max_failures >= 0) command += " --max-failures " + std::to_string(common.max_failures);
    if (common.liar) command += " --liar";
    if (common.disk_faults != "drawn") command += " --disk-faults " + common.disk_faults;
    if (common.ground_pauses) command += " --ground-pauses";
    if (common.ground_designates) command += " --ground-designates";
    return command;
}

void add_common(CLI::App* app, Common& common) {
    app->add_option("mission", common.mission_path, "mission file (YAML)")->required();
    app->add_option("--mutant", common.mutant, "a deliberately broken variant (tests only)");
    app->add_option("--period", common.period_ms, "override the heartbeat period (ms)");
    app->add_option("--loss", common.loss, "fixed message loss rate, e.g. 5% or 0.05");
    app->add_option("--duration", common.duration, "fault window of each run, e.g. 5s");
    app->add_option("--max-failures", common.max_failures,
                    "disruptive faults per run (crashes, partitions); default tolerance + 1, 0 with --liar");
    app->add_flag("--liar", common.liar,
                  "fault model 3: in every run one node of any role lies (sends wrong values), then restarts");
    app->add_option("--disk-faults", common.disk_faults,
                    "three disk faults in every run and no other disruptive fault, each at a phase change, on a "
                    "slow disk: storage-power-loss (at the Storage node's next checkpoint write), "
                    "master-power-loss (at the initial Master's next write), storage-full (the Storage node's "
                    "checkpoint writes fail), or all (one of each)");
    app->add_flag("--ground-pauses", common.ground_pauses,
                  "in every run the ground pauses a task that is not essential (pause-task), and in most "
                  "runs resumes it later (resume-task)");
    app->add_flag("--ground-designates", common.ground_designates,
                  "in every run the ground designates a processing node one to three times (designate; a "
                  "mission with heartbeat.tie_grace), each waiting out the spans it gave another node");
}

int command_run(const Common& common, std::uint64_t seed, const std::string& trace_path, bool verbose,
                bool keep_going) {
    auto mission = load(common);
    auto options = run_options(common);
    if (!mission || !options) return 2;
    std::string error;
    auto topology = fsm::Topology::build(*mission, &error);
    if (!topology) {
        std::fprintf(stderr, "keel-sim: %s\n", error.c_str());
        return 2;
    }
    const RunPlan plan = random_plan(*topology, seed, options->plan);
    std::printf("mission %s, seed %llu, mutant %s\n", mission->name.c_str(),
                static_cast<unsigned long long>(seed), common.mutant.c_str());
    std::printf("network: loss %.1f%%, duplicate %.1f%%, delay %.1f-%.1f ms\n", plan.network.loss * 100,
                plan.network.duplicate * 100, static_cast<double>(plan.network.delay_min_ns) / 1e6,
                static_cast<double>(plan.network.delay_max_ns) / 1e6);
    for (NodeId n = 0; n < plan.boot_ns.size(); ++n) {
        if (plan.boot_ns[n] > 0) {
            std::printf("  boot %s at %lldms\n", topology->node_name(n).c_str(),
                        static_cast<long long>(plan.boot_ns[n] / kMs));
        }
    }
    for (const auto& fault : plan.faults) std::printf("  %s\n", describe(*topology, fault).c_str());

    SimOptions sim_options;
    sim_options.seed = seed;
    sim_options.mutant = options->mutant;
    sim_options.tracing = !trace_path.empty() || verbose;
    sim_options.boot_ns = plan.boot_ns;
    sim_options.clocks = plan.clocks;
    std::ofstream trace;
    if (!trace_path.empty()) {
        trace.open(trace_path);
        if (!trace) {
            std::fprintf(stderr, "keel-sim: cannot write %s\n", trace_path.c_str());
            return 2;
        }
    }
    auto setup = [&](Simulation& sim) {
        sim.on_action = [&](TimeNs t, NodeId node, const fsm::Action& action) {
            const auto* event = std::get_if<fsm::act::Trace>(&action);
            if (event == nullptr) return;
            if (trace.is_open()) {
                write_trace_line(trace, t, topology->node_name(node), event->fsm, event->action,
                                 event->args, event->vars);
            }
            if (verbose) {
                const std::string name = event->action;
                if (name == "DeclareFailed" || name == "Exclude" || name == "BecomeMaster" || name == "CompleteSwitch" ||
                    name == "BroadcastCommand" || name == "RequestPhase") {
                    std::printf("  %9.3fs %s %s.%s %s\n", static_cast<double>(t) / 1e9,
                                topology->node_name(node).c_str(), event->fsm, event->action,
                                flat_json_to_words(event->args).c_str());
                }
            }
        };
        sim.on_environment = [&](TimeNs t, const char* action, const std::string& args) {
            if (trace.is_open()) write_env_line(trace, t, action, args);
            if (verbose) std::printf("  %9.3fs env.%s %s\n", static_cast<double>(t) / 1e9, action, flat_json_to_words(args).c_str());
        };
    };
    Simulation sim(*topology, sim_options, setup);
    // --keep-going: a checker's violation is reported and the run goes on to its end, so
    // that its trace shows what followed (trace validation is then judged on its own).
    sim.stop_on_violation = !keep_going;
    const RunResult result = execute(sim, plan);
    std::printf("outcome: %s after %.3fs simulated, %llu steps, %llu messages\n", to_string(result.outcome),
                static_cast<double>(result.end_ns) / 1e9, static_cast<unsigned long long>(result.steps),
                static_cast<unsigned long long>(result.messages));
    if (result.agreement_ns) {
        std::printf("agreement %.0f ms after faults stopped\n", static_cast<double>(*result.agreement_ns) / 1e6);
    }
    if (result.two_masters_ns > 0 || result.double_run_ns > 0) {
        std::printf("overlap: two running Masters for %.1f ms, a task on two running nodes for %.1f ms\n",
                    static_cast<double>(result.two_masters_ns) / 1e6, static_cast<double>(result.double_run_ns) / 1e6);
    }
    for (const auto& fault : sim.faults()) {
        std::printf("  %s %s at %.3fs: detected %s, reconfigured %s\n", fault.kind.c_str(),
                    fault.kind == "crash" ? topology->node_name(fault.node).c_str()
                                          : topology->phase(fault.phase).name.c_str(),
                    static_cast<double>(fault.injected_ns) / 1e9,
                    fault.detected_ns ? (std::to_string((*fault.detected_ns - fault.injected_ns) / kMs) + " ms later").c_str() : "-",
                    fault.reconfigured_ns ? (std::to_string((*fault.reconfigured_ns - fault.injected_ns) / kMs) + " ms later").c_str() : "-");
    }
    for (const auto& violation : result.violations) {
        std::printf("VIOLATION %s at %.3fs: %s\n", violation.invariant.c_str(),
                    static_cast<double>(violation.t_ns) / 1e9, violation.message.c_str());
    }
    if (!result.violations.empty()) {
        std::printf("replay: %s --seed %llu\n", replay_command(common).c_str(), static_cast<unsigned long long>(seed));
    }
    return result.violations.empty() ? 0 : 1;
}

int command_campaign(const Common& common, std::uint64_t from, std::uint64_t seeds, int jobs,
                     bool json, const std::string& expect, std::uint64_t progress_every,
                     std::optional<double> expect_rate = std::nullopt) {
    if (expect_rate && (expect.empty() || *expect_rate <= 0 || *expect_rate > 1)) {
        std::fprintf(stderr, "keel-sim: --expect-rate needs --expect and a rate in (0, 1]\n");
        return 2;
    }
    auto mission = load(common);
    auto options = run_options(common);
    if (!mission || !options) return 2;
    std::string error;
    auto topology = fsm::Topology::build(*mission, &error);
    if (!topology) {
        std::fprintf(stderr, "keel-sim: %s\n", error.c_str());
        return 2;
    }
    CampaignOptions campaign;
    campaign.from = from;
    campaign.seeds = seeds;
    campaign.run = *options;
    // --expect stops at the first catch (one job, so the first seed that catches is
    // found); --expect-rate runs every seed.
    campaign.jobs = expect.empty() || expect_rate ? jobs : 1;
    campaign.progress_every = progress_every;
    campaign.stop_at_invariant = expect_rate ? std::string() : expect;
    campaign.replay_command = replay_command(common);
    std::fprintf(stderr, "keel-sim campaign: mission %s, seeds %llu..%llu, mutant %s, %d job(s)\n",
                 mission->name.c_str(), static_cast<unsigned long long>(from),
                 static_cast<unsigned long long>(from + seeds - 1), common.mutant.c_str(), campaign.jobs);
    const CampaignResult result = run_campaign(*topology, campaign);
    if (json) {
        std::printf("%s\n", to_json(result, mission->name, campaign).c_str());
    } else {
        std::printf("campaign: %llu seeds in %.2f s (%.0f seeds/s), %llu violations; agreed %llu, headless %llu, "
                    "stalled by the lease %llu; slowest agreement %.0f ms after faults stopped\n",
                    static_cast<unsigned long long>(result.seeds_run), result.seconds, result.seeds_per_second(),
                    static_cast<unsigned long long>(result.violated), static_cast<unsigned long long>(result.agreed),
                    static_cast<unsigned long long>(result.headless),
                    static_cast<unsigned long long>(result.lease_stalled), result.agreement_ms_max);
        for (const auto& [name, count] : result.by_invariant) {
            std::printf("  %s: %llu seeds\n", name.c_str(), static_cast<unsigned long long>(count));
        }
        std::printf("  overlaps: %llu runs with two running Masters (longest %.0f ms), %llu with a task "
                    "on two running nodes (longest %.0f ms)\n",
                    static_cast<unsigned long long>(result.runs_two_masters), result.two_masters_ms_max,
                    static_cast<unsigned long long>(result.runs_double_run), result.double_run_ms_max);
        for (const auto& overlap : result.overlaps) {
            std::printf("    seed %llu: two running Masters %.1f ms, a task on two nodes %.1f ms\n",
                        static_cast<unsigned long long>(overlap.seed), overlap.two_masters_ms,
                        overlap.double_run_ms);
        }
    }
    if (expect_rate) {
        const auto found = result.by_invariant.find(expect);
        const std::uint64_t caught = found == result.by_invariant.end() ? 0 : found->second;
        const double rate =
            result.seeds_run == 0 ? 0 : static_cast<double>(caught) / static_cast<double>(result.seeds_run);
        std::printf("%s: mutant %s caught by %s in %llu of %llu seeds (%.0f %%, expected at least %.0f %%)\n",
                    rate >= *expect_rate ? "caught" : "NOT CAUGHT OFTEN ENOUGH", common.mutant.c_str(),
                    expect.c_str(), static_cast<unsigned long long>(caught),
                    static_cast<unsigned long long>(result.seeds_run), 100 * rate, 100 * *expect_rate);
        return rate >= *expect_rate ? 0 : 1;
    }
    if (!expect.empty()) {
        if (!result.caught) {
            std::printf("NOT CAUGHT: mutant %s survived %llu seeds (expected %s; %llu runs violated "
                        "other invariants)\n",
                        common.mutant.c_str(), static_cast<unsigned long long>(result.seeds_run),
                        expect.c_str(), static_cast<unsigned long long>(result.violated));
            return 1;
        }
        const auto& caught = *result.caught;
        std::printf("caught: mutant %s by %s at seed %llu, after %llu seeds\n", common.mutant.c_str(),
                    expect.c_str(), static_cast<unsigned long long>(caught.seed),
                    static_cast<unsigned long long>(result.seeds_run));
        return 0;
    }
    return result.violated == 0 ? 0 : 1;
}

int command_scenario(const std::vector<std::string>& files, bool update, const std::string& trace_dir,
                     const ScenarioVariant& variant) {
    const bool varied = variant.seed || variant.mutant != fsm::Mutant::none;
    if (varied && update) {
        std::fprintf(stderr, "keel-sim: --update rewrites golden output; not with --seed or --mutant\n");
        return 2;
    }
    const char* root_env = std::getenv("KEEL_ROOT");
    const std::string root = root_env != nullptr ? root_env : ".";
    const char* update_env = std::getenv("KEEL_UPDATE_GOLDEN");
    update = update || (update_env != nullptr && std::string(update_env) == "1");
    int failed = 0;
    for (const auto& file : files) {
        std::string trace_path;
        if (!trace_dir.empty()) {
            std::string stem = file.substr(file.find_last_of('/') + 1);
            stem = stem.substr(0, stem.rfind('.'));
            trace_path = trace_dir + "/" + stem + ".ndjson";
        }
        const ScenarioResult result = run_scenario_file(file, root, trace_path, variant);
        if (varied) {
            // Another seed or a mutant: the golden output does not apply; what the run
            // broke is what it reports.
            std::printf("ran  %s: %d checker violation(s)\n", file.c_str(), result.violations);
            continue;
        }
        if (update) {
            std::ofstream out(file);
            out << result.rewritten;
            std::printf("%s: %s\n", file.c_str(), result.passed ? "unchanged" : "rewritten");
            continue;
        }
        if (result.passed) {
            std::printf("ok   %s\n", file.c_str());
        } else {
            ++failed;
            std::printf("FAIL %s\n%s", file.c_str(), result.diff.c_str());
        }
    }
    if (failed > 0 && !update) {
        std::printf("%d scenario file(s) failed; KEEL_UPDATE_GOLDEN=1 rewrites the expected output\n", failed);
    }
    return failed == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"keel-sim: deterministic simulation of a Keel cluster with fault injection"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("keel-sim ") + KEEL_VERSION);

    Common run_common;
    std::uint64_t run_seed_value = 1;
    std::string trace_path;
    bool verbose = false;
    bool keep_going = false;
    auto* run = app.add_subcommand("run", "one seed: its fault plan, every checker, a trace");
    add_common(run, run_common);
    run->add_option("--seed", run_seed_value, "seed");
    run->add_option("--trace", trace_path, "write the NDJSON trace here");
    run->add_flag("-v,--verbose", verbose, "print declarations, elections and switches");
    run->add_flag("--keep-going", keep_going,
                  "run on after a checker's violation (default: stop there), so that the trace "
                  "shows what followed; the exit code still says a checker fired");

    Common campaign_common;
    std::uint64_t from = 0;
    std::uint64_t seeds = 1000;
    int jobs = 1;
    bool json = false;
    std::string expect;
    std::optional<double> expect_rate;
    auto* campaign = app.add_subcommand("campaign", "many seeds; failing seeds print a replay command");
    add_common(campaign, campaign_common);
    campaign->add_option("--seeds", seeds, "number of seeds");
    campaign->add_option("--from", from, "first seed");
    campaign->add_option("-j,--jobs", jobs, "threads");
    campaign->add_flag("--json", json, "print the summary as JSON");
    campaign->add_option("--expect", expect,
                         "with --mutant: succeed only if this invariant's checker catches it first");
    campaign->add_option("--expect-rate", expect_rate,
                         "with --expect: run every seed and succeed only if that checker caught the mutant in "
                         "at least this fraction of them (e.g. 0.9)");

    Common soak_common;
    std::uint64_t soak_seeds = 1'000'000;
    std::uint64_t soak_from = 0;
    int soak_jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    bool soak_json = false;
    auto* soak = app.add_subcommand("soak", "a long campaign (default 1,000,000 seeds on every core)");
    add_common(soak, soak_common);
    soak->add_option("--seeds", soak_seeds, "number of seeds");
    soak->add_option("--from", soak_from, "first seed");
    soak->add_option("-j,--jobs", soak_jobs, "threads");
    soak->add_flag("--json", soak_json, "print the summary as JSON");

    std::vector<std::string> scenario_files;
    bool update = false;
    auto* scenario = app.add_subcommand("scenario", "data-driven scenario files with golden output");
    scenario->add_option("files", scenario_files, "scenario files")->required();
    scenario->add_flag("--update", update, "rewrite the expected output (also KEEL_UPDATE_GOLDEN=1)");
    std::string scenario_trace_dir;
    scenario->add_option("--trace-dir", scenario_trace_dir,
                         "write each scenario's NDJSON trace here, as NAME.ndjson");
    std::uint64_t scenario_seed = 0;
    auto* scenario_seed_option = scenario->add_option(
        "--seed", scenario_seed, "run with this seed instead of the mission line's (no golden check)");
    std::string scenario_mutant = "none";
    scenario->add_option("--mutant", scenario_mutant, "every node runs this mutant (no golden check)");

    std::string bench_mission;
    std::string bench_out;
    BenchOptions bench_options;
    auto* bench = app.add_subcommand("bench", "seeds/s and latency distributions, as JSON");
    bench->add_option("mission", bench_mission, "mission file")->required();
    bench->add_option("--out", bench_out, "write the JSON here (default: stdout)");
    bench->add_option("--runs", bench_options.runs, "runs per fault type, period and loss rate");
    bench->add_option("--periods", bench_options.periods_ms, "heartbeat periods (ms)")->delimiter(',');
    bench->add_option("--losses", bench_options.losses, "loss rates (0..1)")->delimiter(',');
    bench->add_option("--campaign-seeds", bench_options.campaign_seeds, "seeds for the throughput figure");
    std::string bench_mutant = "none";
    bench->add_option("--mutant", bench_mutant, "every node runs this mutant (a baseline; tests only)");

    CLI11_PARSE(app, argc, argv);

    if (run->parsed()) return command_run(run_common, run_seed_value, trace_path, verbose, keep_going);
    if (campaign->parsed()) {
        return command_campaign(campaign_common, from, seeds, jobs, json, expect, 1000, expect_rate);
    }
    if (soak->parsed()) return command_campaign(soak_common, soak_from, soak_seeds, soak_jobs, soak_json, "", 10000);
    if (scenario->parsed()) {
        ScenarioVariant variant;
        if (scenario_seed_option->count() > 0) variant.seed = scenario_seed;
        const auto mutant = fsm::parse_mutant(scenario_mutant);
        if (!mutant) {
            std::fprintf(stderr, "keel-sim: unknown mutant '%s'\n", scenario_mutant.c_str());
            return 2;
        }
        variant.mutant = *mutant;
        return command_scenario(scenario_files, update, scenario_trace_dir, variant);
    }
    if (bench->parsed()) {
        std::string error;
        auto loaded = load_flown_mission(bench_mission, &error);
        if (!loaded) {
            std::fprintf(stderr, "%s\n", error.c_str());
            return 2;
        }
        const auto mutant = fsm::parse_mutant(bench_mutant);
        if (!mutant) {
            std::fprintf(stderr, "keel-sim: unknown mutant '%s'\n", bench_mutant.c_str());
            return 2;
        }
        bench_options.mutant = *mutant;
        std::string table;
        const std::string report = run_bench(*loaded, bench_options, &table);
        std::fprintf(stderr, "%s", table.c_str());
        if (bench_out.empty()) {
            std::printf("%s\n", report.c_str());
        } else {
            std::ofstream out(bench_out);
            out << report << "\n";
            std::fprintf(stderr, "wrote %s\n", bench_out.c_str());
        }
        return 0;
    }
    return 2;
}
