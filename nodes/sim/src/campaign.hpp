// Campaigns: many seeds of random fault plans, every checker after every step; a failing
// seed prints itself with the command that replays it.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "nodes/sim/src/plan.hpp"

namespace keel::sim {

struct CampaignOptions {
    std::uint64_t from = 0;
    std::uint64_t seeds = 1000;
    RunOptions run;
    int jobs = 1;
    std::uint64_t progress_every = 1000;  // 0: no progress lines
    bool stop_at_first = false;
    // When set: stop at the first run that violates this invariant (a mutant is caught by
    // its checker), whatever other invariants earlier runs violated; it is `caught`.
    std::string stop_at_invariant;
    std::string replay_command;  // printed with " --seed S" appended
};

struct FailedSeed {
    std::uint64_t seed = 0;
    Violation violation;
};

// A run with one of fault model 2's overlaps (no invariant: measured, not judged).
struct OverlapSeed {
    std::uint64_t seed = 0;
    double two_masters_ms = 0;
    double double_run_ms = 0;
};

struct CampaignResult {
    std::uint64_t seeds_run = 0;
    std::uint64_t violated = 0;
    std::uint64_t agreed = 0;
    std::uint64_t headless = 0;
    std::uint64_t lease_stalled = 0;  // Outcome::lease_stalled
    std::map<std::string, std::uint64_t> by_invariant;
    std::vector<FailedSeed> failures;  // in seed order, at most max_listed
    std::optional<FailedSeed> caught;   // the run that violated stop_at_invariant
    double seconds = 0;
    std::uint64_t steps = 0;
    double agreement_ms_max = 0;
    // Fault model 2's overlap measures over the runs (RunResult): how many runs had any,
    // and the longest.
    std::uint64_t runs_two_masters = 0;
    double two_masters_ms_max = 0;
    std::uint64_t runs_double_run = 0;
    double double_run_ms_max = 0;
    std::vector<OverlapSeed> overlaps;  // in seed order, at most max_listed
    double seeds_per_second() const { return seconds > 0 ? static_cast<double>(seeds_run) / seconds : 0; }
};

// Progress lines and failures go to stderr as they happen.
CampaignResult run_campaign(const fsm::Topology& topology, const CampaignOptions& options);
std::string to_json(const CampaignResult& result, const std::string& mission, const CampaignOptions& options);

}  // namespace keel::sim
