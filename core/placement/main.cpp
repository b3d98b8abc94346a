// keel-place IMAGE: the online placer and its checker (core/placement) on a proven image,
// as a node runs them.
//
//   keel-place IMAGE --phase P [--from CONFIG] [--failed N1,N2]
//       the placement the placer computes: master, observers, each task's node, the tasks
//       shed and how many moved. Exit 0 placed, 1 safe mode (the essential tasks do not
//       fit), 2 input error. --from: the configuration the cluster runs (default: the
//       phase's initial one).
//   keel-place IMAGE --batch
//       one JSON query per line on stdin, one answer per line on stdout (tests/placement):
//       {"op": "check", "phase", "failed": [names], "config": {"master", "observers",
//        "tasks": [[task, node], ...]}, "shedding": bool} -> {"findings": [{"kind", "task",
//        "node", "message"}]}
//       {"op": "place", "phase", "failed", "from": config | {...}, "time": N} -> {"safe",
//        "config", "shed", "moved", "started"} (and "ns_p50", the median of N placements
//        timed, when "time" is given)
//       A query that names what the mission does not define is answered {"error": why}.
//   keel-place IMAGE --bench [--repeat R] [--failures K]
//       place() timed for every failed set of at most K nodes (default 1) from every
//       phase's initial configuration, R times each: one JSON object with the count, p50,
//       p99 and max in nanoseconds, the checker's p50 and p99 on each placement, and the
//       peak resident memory (tests/bench/bench-placement). Exit 1 if a placement fails
//       the checker.
//   keel-place IMAGE --prove [--failures K]
//       the proof of every phase placed online or graph+online (prove.hpp): every sequence
//       of at most K node failures (default: the mission's tolerance.node_failures), in
//       every order, the placer run as the nodes run it. One JSON object: per phase the
//       states expanded, the failed sets within the tolerance and beyond it (running every
//       task, shedding, which tasks, SAFE), the violations with their failure sequence, and
//       the time in ms. Exit 0 proved, 1 a violation, 2 input error, 3 undecided (a phase
//       reached --max-transitions before every sequence was explored: never a pass).
//       keel-verify check runs it for a mission with such a phase.
#include <CLI/CLI.hpp>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <exception>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/mission/image.hpp"
#include "core/placement/check.hpp"
#include "core/placement/place.hpp"
#include "core/placement/prove.hpp"

namespace {

// This process's peak resident memory in kB: VmHWM (of this program's own memory, reset at
// exec), else getrusage's ru_maxrss (which keeps the parent's peak across the exec).
long peak_rss_kb() {
    std::ifstream status("/proc/self/status");
    for (std::string line; std::getline(status, line);) {
        if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
    }
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss;
}

using Json = nlohmann::json;
using keel::placement::Configuration;
using keel::placement::FailedSet;
using keel::placement::kNone;
using keel::placement::Model;

struct Input {
    const keel::mission::Mission& mission;
    const Model& model;
};

// Errors of a query, thrown and answered as {"error": why}.
struct QueryError {
    std::string why;
};

int node_named(const Model& model, const std::string& name) {
    const int id = model.node_id(name);
    if (id == kNone) throw QueryError{"no node " + name};
    return id;
}

FailedSet failed_of(const Model& model, const Json& names) {
    FailedSet failed = model.no_failures();
    for (const Json& n : names) failed[static_cast<std::size_t>(node_named(model, n.get<std::string>()))] = true;
    return failed;
}

Configuration configuration_of(const Input& in, const Json& raw) {
    if (raw.is_string()) {
        auto c = in.model.configuration(in.mission, raw.get<std::string>());
        if (!c) throw QueryError{"no configuration " + raw.get<std::string>()};
        return *c;
    }
    Configuration c;
    c.master = node_named(in.model, raw.at("master").get<std::string>());
    for (const Json& o : raw.value("observers", Json::array())) {
        c.observers.push_back(node_named(in.model, o.get<std::string>()));
    }
    c.host.assign(static_cast<std::size_t>(in.model.task_count()), kNone);
    for (const Json& pair : raw.value("tasks", Json::array())) {
        const std::string task = pair.at(0).get<std::string>();
        const int t = in.model.task_id(task);
        if (t == kNone) throw QueryError{"no task " + task};
        c.host[static_cast<std::size_t>(t)] = node_named(in.model, pair.at(1).get<std::string>());
    }
    return c;
}

int phase_of(const Model& model, const Json& raw) {
    const int phase = model.phase_id(raw.get<std::string>());
    if (phase == kNone) throw QueryError{"no phase " + raw.get<std::string>()};
    return phase;
}

Json names(const Model& model, const std::vector<int>& nodes) {
    Json out = Json::array();
    for (const int n : nodes) out.push_back(model.node(n).name);
    return out;
}

Json configuration_json(const Model& model, const Configuration& c) {
    Json tasks = Json::array();
    for (int t = 0; t < model.task_count(); ++t) {
        const int host = c.host[static_cast<std::size_t>(t)];
        if (host != kNone) tasks.push_back({model.task(t).name, model.node(host).name});
    }
    return {{"master", model.node(c.master).name},
            {"observers", names(model, c.observers)},
            {"tasks", std::move(tasks)}};
}

Json place_json(const Model& model, const keel::placement::Placement& p) {
    Json shed = Json::array();
    for (const int t : p.shed) shed.push_back(model.task(t).name);
    return {{"safe", p.safe},
            {"config", p.safe ? Json(nullptr) : configuration_json(model, p.config)},
            {"shed", std::move(shed)},
            {"moved", p.moved},
            {"started", p.started}};
}

Configuration initial_of(const Input& in, int phase) {
    const auto& info = in.model.phase(phase);
    return *in.model.configuration(in.mission, info.configurations[static_cast<std::size_t>(info.initial)]);
}

Json answer(const Input& in, const Json& query) {
    const std::string op = query.at("op").get<std::string>();
    const int phase = phase_of(in.model, query.at("phase"));
    const FailedSet failed = failed_of(in.model, query.value("failed", Json::array()));
    if (op == "check") {
        const auto shedding = query.value("shedding", false) ? keel::placement::Shedding::allowed
                                                             : keel::placement::Shedding::forbidden;
        Json findings = Json::array();
        for (const auto& f : keel::placement::check(in.model, phase, failed,
                                                    configuration_of(in, query.at("config")),
                                                    shedding)) {
            findings.push_back({{"kind", f.kind},
                                {"task", f.task == kNone ? Json(nullptr) : Json(in.model.task(f.task).name)},
                                {"node", f.node == kNone ? Json(nullptr) : Json(in.model.node(f.node).name)},
                                {"message", f.message}});
        }
        return {{"findings", std::move(findings)}};
    }
    if (op == "place") {
        const Configuration from =
            query.contains("from") ? configuration_of(in, query.at("from")) : initial_of(in, phase);
        Json out = place_json(in.model, keel::placement::place(in.model, phase, failed, from));
        // "time": N also times the placement N times: the median in nanoseconds.
        const int times = query.value("time", 0);
        if (times < 0 || times > 1000000) throw QueryError{"time is 0 to 1000000 placements"};
        if (times > 0) {
            std::vector<std::int64_t> samples;
            for (int r = 0; r < times; ++r) {
                const auto start = std::chrono::steady_clock::now();
                const auto placed = keel::placement::place(in.model, phase, failed, from);
                const auto end = std::chrono::steady_clock::now();
                if (placed.safe != out["safe"].get<bool>()) throw QueryError{"the placer is not deterministic"};
                samples.push_back(std::chrono::duration_cast<std::chrono::nanoseconds>(end - start).count());
            }
            std::sort(samples.begin(), samples.end());
            out["ns_p50"] = samples[samples.size() / 2];
        }
        return out;
    }
    throw QueryError{"unknown op " + op};
}

int batch(const Input& in) {
    std::string line;
    while (std::getline(std::cin, line)) {
        if (line.empty()) continue;
        Json out;
        try {
            out = answer(in, Json::parse(line));
        } catch (const QueryError& e) {
            out = {{"error", e.why}};
        } catch (const std::exception& e) {
            out = {{"error", std::string("malformed query: ") + e.what()}};
        }
        std::cout << out.dump() << '\n';
    }
    std::cout.flush();
    return std::cout ? 0 : 2;
}

// Every failed set of at most `depth` nodes, as id lists, in lexicographic order.
void failed_sets(int nodes, int depth, std::vector<int>& prefix, std::vector<std::vector<int>>& out) {
    out.push_back(prefix);
    if (static_cast<int>(prefix.size()) == depth) return;
    for (int n = prefix.empty() ? 0 : prefix.back() + 1; n < nodes; ++n) {
        prefix.push_back(n);
        failed_sets(nodes, depth, prefix, out);
        prefix.pop_back();
    }
}

int bench(const Input& in, int repeat, int depth) {
    std::vector<std::vector<int>> sets;
    std::vector<int> prefix;
    failed_sets(in.model.node_count(), depth, prefix, sets);
    std::vector<std::int64_t> samples;
    std::vector<std::int64_t> check_samples;
    int safe = 0;
    int shed = 0;
    int invalid = 0;
    std::int64_t moved = 0;
    for (int phase = 0; phase < in.model.phase_count(); ++phase) {
        const Configuration from = initial_of(in, phase);
        for (const auto& set : sets) {
            FailedSet failed = in.model.no_failures();
            for (const int n : set) failed[static_cast<std::size_t>(n)] = true;
            keel::placement::Placement p;
            for (int r = 0; r < repeat; ++r) {
                const auto start = std::chrono::steady_clock::now();
                p = keel::placement::place(in.model, phase, failed, from);
                const auto end = std::chrono::steady_clock::now();
                samples.push_back(std::chrono::duration_cast<std::chrono::nanoseconds>(end - start).count());
            }
            if (p.safe) {
                ++safe;
                continue;
            }
            // What every node pays before it acts on it: the checker on the placement.
            for (int r = 0; r < repeat; ++r) {
                const auto start = std::chrono::steady_clock::now();
                const bool ok = keel::placement::valid(in.model, phase, failed, p.config,
                                                       keel::placement::Shedding::allowed);
                const auto end = std::chrono::steady_clock::now();
                check_samples.push_back(std::chrono::duration_cast<std::chrono::nanoseconds>(end - start).count());
                if (!ok) ++invalid;
            }
            if (!p.shed.empty()) ++shed;
            moved += p.moved;
        }
    }
    std::sort(samples.begin(), samples.end());
    std::sort(check_samples.begin(), check_samples.end());
    auto quantile = [](const std::vector<std::int64_t>& sorted, double q) -> std::int64_t {
        if (sorted.empty()) return 0;
        return sorted[std::min(sorted.size() - 1, static_cast<std::size_t>(q * static_cast<double>(sorted.size())))];
    };
    auto at = [&](double q) { return quantile(samples, q); };
    const auto placements = samples.size() / static_cast<std::size_t>(repeat);
    const Json out = {{"nodes", in.model.node_count()},
                      {"tasks", in.model.task_count()},
                      {"phases", in.model.phase_count()},
                      {"failed_sets", sets.size()},
                      {"placements", placements},
                      {"samples", samples.size()},
                      {"p50_ns", at(0.5)},
                      {"p99_ns", at(0.99)},
                      {"max_ns", samples.back()},
                      {"check_p50_ns", quantile(check_samples, 0.5)},
                      {"check_p99_ns", quantile(check_samples, 0.99)},
                      {"safe", safe},
                      {"shed", shed},
                      {"moved_per_placement", placements == 0 ? 0.0 : static_cast<double>(moved) / static_cast<double>(placements)},
                      {"invalid", invalid},
                      {"peak_rss_kb", peak_rss_kb()}};
    std::cout << out.dump() << '\n';
    return invalid == 0 ? 0 : 1;
}

// --prove's answer keeps its fields in the order written (a report read by people too).
using OrderedJson = nlohmann::ordered_json;

OrderedJson ordered_names(const Model& model, const std::vector<int>& nodes) {
    OrderedJson out = OrderedJson::array();
    for (const int n : nodes) out.push_back(model.node(n).name);
    return out;
}

OrderedJson shed_json(const Model& model, const std::vector<std::int64_t>& by_task) {
    OrderedJson out = OrderedJson::object();
    for (std::size_t t = 0; t < by_task.size(); ++t) {
        if (by_task[t] > 0) out[model.task(static_cast<int>(t)).name] = by_task[t];
    }
    return out;
}

OrderedJson outcomes_json(const Model& model, const keel::placement::Outcomes& o, bool with_safe) {
    OrderedJson out = {{"failed_sets", o.failed_sets},
                {"running_every_task", o.running_every_task},
                {"shedding", o.shedding},
                {"shed", shed_json(model, o.shed_by_task)}};
    if (with_safe) out["safe"] = o.safe;
    return out;
}

OrderedJson phase_proof_json(const Model& model, const keel::placement::PhaseProof& p, double ms) {
    OrderedJson violations = OrderedJson::array();
    for (const auto& v : p.violations) {
        OrderedJson path = OrderedJson::array();
        for (const auto& e : v.path) {
            if (e.node != keel::placement::kNone) {
                path.push_back({{"failure", model.node(e.node).name}});
            } else {
                path.push_back({{"phase", model.phase(e.phase).name}});
            }
        }
        violations.push_back({{"kind", v.kind},
                              {"failures", ordered_names(model, v.sequence)},
                              {"start", model.phase(v.start).name},
                              {"path", std::move(path)},
                              {"message", v.message}});
    }
    return {{"phase", model.phase(p.phase).name},
            {"placement", keel::mission::placement_name(p.mode)},
            {"failures", p.failures},
            {"states", p.states},
            {"transitions", p.transitions},
            {"placements", p.placements},
            {"readmissions", p.readmissions},
            {"phase_changes", p.phase_changes},
            {"within_tolerance", outcomes_json(model, p.within, false)},
            {"violation_count", p.violation_count},
            {"violations", std::move(violations)},
            {"beyond_tolerance", outcomes_json(model, p.beyond, true)},
            {"complete", p.complete},
            {"ms", ms}};
}

// --prove: exit 0 proved, 1 a violation, 3 undecided.
int prove(const Input& in, const std::string& path, int failures, std::int64_t max_transitions, int threads) {
    OrderedJson phases = OrderedJson::array();
    std::int64_t violations = 0;
    bool complete = true;
    const auto start = std::chrono::steady_clock::now();
    const std::vector<keel::placement::PhaseProof> proofs =
        keel::placement::prove(in.mission, in.model, failures, max_transitions, threads);
    const auto end = std::chrono::steady_clock::now();
    const auto us = std::chrono::duration_cast<std::chrono::microseconds>(end - start).count();
    const double ms = static_cast<double>(us) / 1000.0;  // every phase's, explored together
    for (const keel::placement::PhaseProof& proof : proofs) {
        violations += proof.violation_count;
        complete = complete && proof.complete;
        phases.push_back(phase_proof_json(in.model, proof, ms));
    }
    const OrderedJson out = {{"image", path},
                      {"mission", in.mission.name},
                      {"node_failures", in.mission.tolerance.node_failures},
                      {"failures", failures},
                      {"result", violations != 0 ? "violated" : complete ? "proved" : "undecided"},
                      {"violation_count", violations},
                      {"ms", ms},
                      {"peak_rss_kb", peak_rss_kb()},
                      {"phases", std::move(phases)}};
    std::cout << out.dump(2) << '\n';
    return violations != 0 ? 1 : complete ? 0 : 3;
}

std::vector<std::string> split(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

}  // namespace

static int run(int argc, char** argv) {
    CLI::App app{"The online placer and its checker on a proven image (core/placement).",
                 "keel-place"};
    std::string path;
    std::string phase;
    std::string from;
    std::string failed;
    bool batch_mode = false;
    bool bench_mode = false;
    bool prove_mode = false;
    int repeat = 10;
    int depth = -1;  // --bench: 1; --prove: the mission's tolerance
    std::int64_t max_transitions = keel::placement::kMaxProveTransitions;
    int threads = 0;
    app.add_option("image", path, "mission image (keel-verify compile MISSION.yaml -o IMAGE.json)")
        ->required();
    app.add_option("--phase", phase, "the phase to place");
    app.add_option("--from", from, "the configuration the cluster runs (default: the phase's initial)");
    app.add_option("--failed", failed, "failed nodes, comma-separated");
    app.add_flag("--batch", batch_mode, "answer JSON queries, one per line, from stdin");
    app.add_flag("--bench", bench_mode, "time the placer over every failed set (JSON)");
    app.add_flag("--prove", prove_mode,
                 "prove the online phases under every failure sequence of at most --failures "
                 "nodes (JSON)");
    app.add_option("--repeat", repeat, "--bench: placements timed per failed set")->check(CLI::Range(1, 1000000));
    app.add_option("--failures", depth,
                   "--bench: failed sets of at most this many nodes (default 1, at most 3); --prove: "
                   "failure sequences of at most this many (default: the mission's tolerance)")
        ->check(CLI::Range(0, keel::placement::kMaxProveFailures));
    app.add_option("--threads", threads,
                   "--prove: threads checking the readmissions, the exploring one included (default 0: one per core); "
                   "the proof is the same for any number")
        ->check(CLI::Range(0, keel::placement::kMaxProveThreads));
    app.add_option("--max-transitions", max_transitions,
                   "--prove: failures and phase changes applied before the proof gives up (exit 3)")
        ->check(CLI::Range(std::int64_t{0}, keel::placement::kMaxProveTransitions));
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);
        return code == 0 ? 0 : 2;
    }
    const keel::mission::LoadResult loaded = keel::mission::load_mission_image(path);
    if (!loaded.ok()) {
        for (const auto& error : loaded.errors) std::cerr << error.to_string() << '\n';
        return 2;
    }
    std::string why;
    const auto model = Model::build(*loaded.mission, &why);
    if (!model) {
        std::cerr << path << ":1:1: placement: " << why << '\n';
        return 2;
    }
    const Input in{*loaded.mission, *model};
    if (batch_mode) return batch(in);
    if (bench_mode) {
        if (depth > 3) {
            std::cerr << "keel-place: --bench --failures is at most 3\n";
            return 2;
        }
        return bench(in, repeat, depth < 0 ? 1 : depth);
    }
    if (prove_mode) {
        const std::int64_t tolerance = loaded.mission->tolerance.node_failures;
        if (depth < 0 && tolerance > keel::placement::kMaxProveFailures) {
            std::cerr << path << ": tolerance.node_failures " << tolerance
                      << " is beyond what --prove explores (" << keel::placement::kMaxProveFailures
                      << "); give --failures\n";
            return 2;
        }
        return prove(in, path, depth < 0 ? static_cast<int>(tolerance) : depth, max_transitions, threads);
    }
    if (phase.empty()) {
        std::cerr << "keel-place: give --phase, --batch or --bench\n";
        return 2;
    }
    Json query = {{"op", "place"}, {"phase", phase}, {"failed", split(failed)}};
    if (!from.empty()) query["from"] = from;
    try {
        const Json out = answer(in, query);
        const auto& c = out["config"];
        if (out["safe"].get<bool>()) {
            std::cout << "phase " << phase << ": safe mode (the essential tasks do not fit)\n";
            return 1;
        }
        std::cout << "phase " << phase << ": master " << c["master"].get<std::string>()
                  << ", observers " << c["observers"].dump() << "\n";
        for (const auto& pair : c["tasks"]) {
            std::cout << "  " << pair[0].get<std::string>() << " on " << pair[1].get<std::string>() << '\n';
        }
        std::cout << "shed " << out["shed"].dump() << ", moved " << out["moved"] << ", started "
                  << out["started"] << '\n';
        return 0;
    } catch (const QueryError& e) {
        std::cerr << path << ": " << e.why << '\n';
        return 2;
    }
}

int main(int argc, char** argv) {
    // An operating error is reported and exits 2; nothing escapes as a crash.
    try {
        return run(argc, argv);
    } catch (const std::exception& error) {
        std::cerr << "keel-place: " << error.what() << '\n';
        return 2;
    }
}
