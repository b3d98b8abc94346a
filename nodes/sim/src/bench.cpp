#include "nodes/sim/src/bench.hpp"

#include <chrono>
#include <cstdio>

#include "core/fsm/json.hpp"
#include "nodes/sim/src/campaign.hpp"
#include "nodes/sim/src/util.hpp"

namespace keel::sim {

namespace {

std::string distribution_json(const Distribution& d) {
    return fsm::JsonObject()
        .field("count", static_cast<std::uint64_t>(d.count))
        .field("min", d.min)
        .field("p50", d.p50)
        .field("p90", d.p90)
        .field("p99", d.p99)
        .field("max", d.max)
        .field("mean", d.mean)
        .str();
}

struct Sample {
    std::vector<double> detection_ms;
    std::vector<double> reconfiguration_ms;
    int recovered = 0;
    std::size_t violations = 0;
};

// One injected fault of `kind` on a quiet cluster with loss `loss`.
void measure(const fsm::Topology& topology, const std::string& kind, double loss,
             std::uint64_t seed, fsm::Mutant mutant, Sample& sample) {
    const TimeNs period = topology.heartbeat_period_ns();
    SimOptions options;
    options.seed = seed;
    options.mutant = mutant;
    options.network.loss = loss;
    options.network.delay_min_ns = kMs / 5;
    options.network.delay_max_ns = std::min<TimeNs>(5 * kMs, period / 3);
    Simulation sim(topology, options);
    sim.stop_on_violation = false;
    Rng rng(seed * 31 + 7);
    const TimeNs t0 = 3 * period + static_cast<TimeNs>(rng.below(static_cast<std::uint64_t>(period)));
    sim.run_until(t0);
    const fsm::View initial = topology.initial_view();
    if (kind == "worker") {
        std::vector<NodeId> workers;
        topology.processing_nodes().for_each([&](NodeId n) {
            if (n != initial.master && !topology.tasks_on(initial, n).empty()) workers.push_back(n);
        });
        if (workers.empty()) return;
        sim.crash(workers[rng.below(workers.size())]);
    } else if (kind == "master") {
        sim.crash(initial.master);
    } else if (kind == "storage") {
        if (topology.storage_node() == fsm::kNoNode) return;
        sim.crash(topology.storage_node());
    } else {
        const fsm::PhaseId current = topology.phase_of(initial);
        sim.request_phase(static_cast<fsm::PhaseId>((current + 1) % topology.phase_count()));
    }
    const TimeNs limit = t0 + 60 * period;
    const FaultRecord* fault = &sim.faults().back();
    while (sim.now() < limit && !fault->reconfigured_ns) {
        sim.run_for(period / 4);
        fault = &sim.faults().back();
    }
    if (fault->detected_ns) sample.detection_ms.push_back(static_cast<double>(*fault->detected_ns - fault->injected_ns) / 1e6);
    if (fault->reconfigured_ns) {
        ++sample.recovered;
        sample.reconfiguration_ms.push_back(static_cast<double>(*fault->reconfigured_ns - fault->injected_ns) / 1e6);
    }
    sample.violations += sim.violations().size();
}

}  // namespace

std::string run_bench(const keel::mission::Mission& mission, const BenchOptions& options,
                      std::string* table) {
    std::string error;
    auto base = fsm::Topology::build(mission, &error);
    if (!base) return fsm::JsonObject().field("error", error).str();

    CampaignOptions campaign;
    campaign.seeds = options.campaign_seeds;
    campaign.run.mutant = options.mutant;
    campaign.progress_every = 0;
    const CampaignResult throughput = run_campaign(*base, campaign);

    std::vector<std::string> kinds = {"worker", "master", "storage"};
    if (base->phase_count() > 1) kinds.push_back("phase");
    std::string rows = "[";
    std::string text;
    char line[256];
    std::snprintf(line, sizeof line, "%-8s %9s %6s %5s  %-26s  %-26s\n", "fault", "period_ms", "loss",
                  "runs", "detection ms p50/p90/max", "reconfiguration ms p50/p90/max");
    text += line;
    std::size_t total_violations = 0;
    bool first_row = true;
    for (int period_ms : options.periods_ms) {
        keel::mission::Mission variant = mission;
        variant.heartbeat.period_ms = period_ms;
        auto topology = fsm::Topology::build(variant, &error);
        if (!topology) return fsm::JsonObject().field("error", error).str();
        for (double loss : options.losses) {
            for (const auto& kind : kinds) {
                Sample sample;
                for (int run = 0; run < options.runs; ++run) {
                    measure(*topology, kind, loss, static_cast<std::uint64_t>(run) + 1, options.mutant, sample);
                }
                total_violations += sample.violations;
                const Distribution detection = summarize(sample.detection_ms);
                const Distribution reconfiguration = summarize(sample.reconfiguration_ms);
                if (!first_row) rows += ",";
                first_row = false;
                fsm::JsonObject row;
                row.field("fault", kind)
                    .field("period_ms", period_ms)
                    .field("loss", loss)
                    .field("runs", options.runs)
                    .field("recovered", sample.recovered);
                if (kind != "phase") row.raw("detection_ms", distribution_json(detection));
                row.raw("reconfiguration_ms", distribution_json(reconfiguration));
                rows += row.str();
                char detection_text[64] = "-";
                if (kind != "phase") {
                    std::snprintf(detection_text, sizeof detection_text, "%.0f/%.0f/%.0f", detection.p50,
                                  detection.p90, detection.max);
                }
                std::snprintf(line, sizeof line, "%-8s %9d %5.0f%% %5d  %-26s  %.0f/%.0f/%.0f%s\n",
                              kind.c_str(), period_ms, loss * 100, options.runs, detection_text,
                              reconfiguration.p50, reconfiguration.p90, reconfiguration.max,
                              sample.recovered < options.runs
                                  ? (" (" + std::to_string(options.runs - sample.recovered) + " not recovered)").c_str()
                                  : "");
                text += line;
            }
        }
    }
    rows += "]";
    std::snprintf(line, sizeof line, "campaign: %llu seeds in %.2f s = %.0f seeds/s, %llu violations\n",
                  static_cast<unsigned long long>(throughput.seeds_run), throughput.seconds,
                  throughput.seeds_per_second(), static_cast<unsigned long long>(throughput.violated));
    text = line + text;
    if (table != nullptr) *table = text;
    return fsm::JsonObject()
        .field("benchmark", "sim")
        .field("mission", mission.name)
        .field("miss_limit", static_cast<std::int64_t>(mission.heartbeat.miss_limit))
        .raw("campaign", to_json(throughput, mission.name, campaign))
        .field("seeds_per_second", throughput.seeds_per_second())
        .raw("latency", rows)
        .field("latency_violations", static_cast<std::uint64_t>(total_violations))
        .str();
}

}  // namespace keel::sim
