#include "nodes/sim/src/campaign.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <thread>

#include "core/fsm/json.hpp"

namespace keel::sim {

namespace {
constexpr std::size_t kMaxListed = 20;
}

CampaignResult run_campaign(const fsm::Topology& topology, const CampaignOptions& options) {
    CampaignResult result;
    std::mutex mutex;
    std::atomic<std::uint64_t> next{0};
    std::atomic<bool> stop{false};
    const auto start = std::chrono::steady_clock::now();
    auto elapsed = [&] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };

    auto worker = [&] {
        while (!stop.load()) {
            const std::uint64_t index = next.fetch_add(1);
            if (index >= options.seeds) return;
            const std::uint64_t seed = options.from + index;
            const RunResult run = run_seed(topology, seed, options.run);
            std::lock_guard lock(mutex);
            ++result.seeds_run;
            result.steps += run.steps;
            switch (run.outcome) {
                case Outcome::agreed: ++result.agreed; break;
                case Outcome::headless: ++result.headless; break;
                case Outcome::lease_stalled: ++result.lease_stalled; break;
                case Outcome::violated: ++result.violated; break;
            }
            if (run.two_masters_ns > 0) {
                ++result.runs_two_masters;
                result.two_masters_ms_max =
                    std::max(result.two_masters_ms_max, static_cast<double>(run.two_masters_ns) / 1e6);
            }
            if (run.double_run_ns > 0) {
                ++result.runs_double_run;
                result.double_run_ms_max =
                    std::max(result.double_run_ms_max, static_cast<double>(run.double_run_ns) / 1e6);
            }
            if ((run.two_masters_ns > 0 || run.double_run_ns > 0) && result.overlaps.size() < kMaxListed) {
                result.overlaps.push_back({seed, static_cast<double>(run.two_masters_ns) / 1e6,
                                           static_cast<double>(run.double_run_ns) / 1e6});
            }
            if (run.agreement_ns) {
                result.agreement_ms_max = std::max(result.agreement_ms_max,
                                                   static_cast<double>(*run.agreement_ns) / 1e6);
            }
            if (!run.violations.empty()) {
                const Violation& first = run.violations.front();
                ++result.by_invariant[first.invariant];
                if (result.failures.size() < kMaxListed) result.failures.push_back({seed, first});
                std::fprintf(stderr, "FAIL seed %llu: %s at %.3fs: %s\n  replay: %s --seed %llu\n",
                             static_cast<unsigned long long>(seed), first.invariant.c_str(),
                             static_cast<double>(first.t_ns) / 1e9, first.message.c_str(),
                             options.replay_command.c_str(), static_cast<unsigned long long>(seed));
                if (options.stop_at_first) stop.store(true);
                for (const Violation& violation : run.violations) {
                    if (options.stop_at_invariant.empty() ||
                        violation.invariant != options.stop_at_invariant) {
                        continue;
                    }
                    if (!result.caught || seed < result.caught->seed) result.caught = FailedSeed{seed, violation};
                    stop.store(true);
                    break;
                }
            }
            if (options.progress_every > 0 && result.seeds_run % options.progress_every == 0) {
                const double seconds = elapsed();
                std::fprintf(stderr, "  %llu/%llu seeds, %llu violations, %.0f seeds/s\n",
                             static_cast<unsigned long long>(result.seeds_run),
                             static_cast<unsigned long long>(options.seeds),
                             static_cast<unsigned long long>(result.violated),
                             seconds > 0 ? static_cast<double>(result.seeds_run) / seconds : 0.0);
            }
        }
    };
    const int jobs = std::max(1, options.jobs);
    if (jobs == 1) {
        worker();
    } else {
        std::vector<std::thread> threads;
        for (int j = 0; j < jobs; ++j) threads.emplace_back(worker);
        for (auto& thread : threads) thread.join();
    }
    result.seconds = elapsed();
    std::sort(result.failures.begin(), result.failures.end(),
              [](const FailedSeed& a, const FailedSeed& b) { return a.seed < b.seed; });
    std::sort(result.overlaps.begin(), result.overlaps.end(),
              [](const OverlapSeed& a, const OverlapSeed& b) { return a.seed < b.seed; });
    return result;
}

std::string to_json(const CampaignResult& result, const std::string& mission,
                    const CampaignOptions& options) {
    std::string by_invariant = "{";
    bool first = true;
    for (const auto& [name, count] : result.by_invariant) {
        if (!first) by_invariant += ",";
        first = false;
        fsm::append_json_string(by_invariant, name);
        by_invariant += ":" + std::to_string(count);
    }
    by_invariant += "}";
    std::string failures = "[";
    for (std::size_t i = 0; i < result.failures.size(); ++i) {
        if (i > 0) failures += ",";
        const auto& failure = result.failures[i];
        failures += fsm::JsonObject()
                        .field("seed", failure.seed)
                        .field("invariant", failure.violation.invariant)
                        .field("t_ns", static_cast<std::int64_t>(failure.violation.t_ns))
                        .field("message", failure.violation.message)
                        .field("replay", options.replay_command + " --seed " + std::to_string(failure.seed))
                        .str();
    }
    failures += "]";
    std::string overlaps = "[";
    for (std::size_t i = 0; i < result.overlaps.size(); ++i) {
        if (i > 0) overlaps += ",";
        const auto& overlap = result.overlaps[i];
        overlaps += fsm::JsonObject()
                        .field("seed", overlap.seed)
                        .field("two_masters_ms", overlap.two_masters_ms)
                        .field("double_run_ms", overlap.double_run_ms)
                        .field("replay", options.replay_command + " --seed " + std::to_string(overlap.seed))
                        .str();
    }
    overlaps += "]";
    return fsm::JsonObject()
        .field("mission", mission)
        .field("mutant", fsm::to_string(options.run.mutant))
        .field("from", options.from)
        .field("seeds", result.seeds_run)
        .field("violations", result.violated)
        .field("agreed", result.agreed)
        .field("headless", result.headless)
        .field("lease_stalled", result.lease_stalled)
        .raw("by_invariant", by_invariant)
        .field("seconds", result.seconds)
        .field("seeds_per_second", result.seeds_per_second())
        .field("steps", result.steps)
        .field("agreement_ms_max", result.agreement_ms_max)
        .field("runs_two_masters", result.runs_two_masters)
        .field("two_masters_ms_max", result.two_masters_ms_max)
        .field("runs_double_run", result.runs_double_run)
        .field("double_run_ms_max", result.double_run_ms_max)
        .raw("failures", failures)
        .raw("overlaps", overlaps)
        .str();
}

}  // namespace keel::sim
