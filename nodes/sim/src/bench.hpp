// The simulator's benchmark: campaign throughput, and per fault type the detection and
// reconfiguration latency distributions (simulated ms) as a function of the heartbeat
// period and the loss rate — the model the real cluster's measurements are compared to.
#pragma once

#include <string>
#include <vector>

#include "core/fsm/mutants.hpp"
#include "core/mission/mission.hpp"

namespace keel::sim {

struct BenchOptions {
    std::vector<int> periods_ms = {100, 500, 1000};
    std::vector<double> losses = {0, 0.01, 0.05, 0.1};
    int runs = 100;                      // per (fault, period, loss)
    std::uint64_t campaign_seeds = 2000;  // for seeds/s
    fsm::Mutant mutant = fsm::Mutant::none;  // every node runs it (bench-admission's baseline)
};

// Returns the JSON report; `table` receives a human-readable summary.
std::string run_bench(const keel::mission::Mission& mission, const BenchOptions& options,
                      std::string* table);

}  // namespace keel::sim
