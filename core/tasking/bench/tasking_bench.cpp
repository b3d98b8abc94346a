// keel-tasking-bench: how long a node takes to configure N components, and how fast the
// executor runs them. Writes one JSON object (stdout, or --out PATH).
//
// Configuration time is what the paper's Fig. 13 measures: from the configuration command
// to every component configured, here instantiate (registry, from the mission model) +
// configure + wire (the executor's routing table) + activate, for N components on one node.
// Half the components are periodic producers, half consumers of one producer each.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/tasking/builtin.hpp"
#include "core/tasking/executor.hpp"

namespace {

using namespace keel;
using namespace keel::tasking;
using Wall = std::chrono::steady_clock;

// CPU time of the calling thread: what the configuration costs, whatever else the machine
// runs (wall time on shared cores includes the time other processes held the CPU).
double thread_cpu_ms() {
    timespec now{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
    return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) / 1e6;
}

double ms_since(Wall::time_point start) {
    return std::chrono::duration<double, std::milli>(Wall::now() - start).count();
}

mission::Mission pairs_mission(std::size_t components) {
    mission::Mission mission;
    mission.name = "bench-" + std::to_string(components);
    mission.path = "<bench>";
    mission::Phase phase;
    phase.name = "nominal";
    for (std::size_t index = 0; index < components; ++index) {
        mission::Task task;
        const std::size_t pair = index / 2;
        if (index % 2 == 0) {
            task.name = "p" + std::to_string(pair);
            task.component = "producer";
            task.period_ms = 20;
            task.params = {{"step", std::int64_t{1}}};
        } else {
            task.name = "c" + std::to_string(pair);
            task.component = "consumer";
            task.inputs = {"p" + std::to_string(pair)};
            task.checkpoint = true;
            task.health = mission::Health{0.0, 1e12, 1000};
        }
        task.port = static_cast<std::int64_t>(1000 + index);
        task.line = static_cast<int>(index + 1);
        mission.tasks.push_back(task);
        phase.tasks.push_back(task.name);
    }
    mission.phases.push_back(phase);
    return mission;
}

struct ConfigurationRun {
    double instantiate_configure_ms = 0;
    double activate_ms = 0;
    double total_ms = 0;
    double cpu_ms = 0;
};

ConfigurationRun configure_once(const mission::Mission& mission,
                                const ComponentRegistry& registry) {
    ManualClock clock;
    ExecutorLimits limits;
    limits.max_tasks = 4096;
    Executor executor(clock, limits);
    ConfigurationRun run;
    const double cpu_start = thread_cpu_ms();
    const auto start = Wall::now();
    std::vector<InstantiateResult> instances = registry.instantiate_all(mission, "nominal");
    std::vector<TaskId> ids;
    ids.reserve(instances.size());
    for (InstantiateResult& instance : instances) {
        if (!instance.ok()) {
            std::cerr << instance.error << "\n";
            std::exit(1);
        }
        Executor::AddResult added = executor.add(std::move(*instance.instance));
        if (!added.id) {
            std::cerr << added.result.message << "\n";
            std::exit(1);
        }
        ids.push_back(*added.id);
    }
    run.instantiate_configure_ms = ms_since(start);
    const auto activation = Wall::now();
    for (TaskId id : ids) {
        if (!executor.activate(id).succeeded()) std::exit(1);
    }
    run.activate_ms = ms_since(activation);
    run.total_ms = ms_since(start);
    run.cpu_ms = thread_cpu_ms() - cpu_start;
    // One round proves the node is configured and wired: every consumer ran once.
    const std::size_t executed = executor.run_ready();
    if (executed != ids.size()) {
        std::cerr << "expected " << ids.size() << " executions, got " << executed << "\n";
        std::exit(1);
    }
    return run;
}

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    const std::size_t mid = values.size() / 2;
    return values.size() % 2 ? values[mid] : (values[mid - 1] + values[mid]) / 2;
}

std::string fixed(double value, int digits = 3) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
    return buffer;
}

// Manual mode: 128 producer/consumer pairs, one 20 ms period per step.
std::string manual_throughput(const ComponentRegistry& registry, std::size_t steps) {
    const mission::Mission mission = pairs_mission(256);
    ManualClock clock;
    Executor executor(clock);
    for (InstantiateResult& instance : registry.instantiate_all(mission, "nominal")) {
        executor.activate(*executor.add(std::move(*instance.instance)).id);
    }
    std::size_t executions = 0;
    const auto start = Wall::now();
    for (std::size_t step = 0; step < steps; ++step) {
        executions += executor.run_ready();
        clock.advance_ms(20);
        executor.take_checkpoints();
    }
    const double elapsed_ms = ms_since(start);
    return "{\"mode\": \"manual\", \"components\": 256, \"executions\": " +
           std::to_string(executions) + ", \"elapsed_ms\": " + fixed(elapsed_ms) +
           ", \"executions_per_s\": " +
           fixed(static_cast<double>(executions) / (elapsed_ms / 1000.0), 0) + "}";
}

// Threaded mode: 128 event-triggered producers feeding 128 consumers through the pool.
std::string threaded_throughput(const ComponentRegistry& registry, std::size_t rounds) {
    mission::Mission mission = pairs_mission(256);
    for (mission::Task& task : mission.tasks) task.period_ms.reset();
    SteadyClock clock;
    ExecutorLimits limits;
    limits.input_queue_capacity = 1024;
    Executor executor(clock, limits);
    std::vector<TaskId> producers;
    for (InstantiateResult& instance : registry.instantiate_all(mission, "nominal")) {
        const bool producer = instance.instance->spec.component == "producer";
        const TaskId id = *executor.add(std::move(*instance.instance)).id;
        executor.activate(id);
        if (producer) producers.push_back(id);
    }
    executor.start();
    const auto start = Wall::now();
    for (std::size_t round = 0; round < rounds; ++round) {
        for (TaskId id : producers) {
            while (!executor.raise_event(id)) std::this_thread::yield();
        }
    }
    while (!executor.wait_idle(100)) {
    }
    const double elapsed_ms = ms_since(start);
    executor.stop();
    std::uint64_t executions = 0;
    for (std::size_t id = 0; id < 256; ++id)
        executions += executor.stats(static_cast<TaskId>(id)).executions;
    return "{\"mode\": \"threaded\", \"threads\": " + std::to_string(executor.thread_count()) +
           ", \"components\": 256, \"executions\": " + std::to_string(executions) +
           ", \"elapsed_ms\": " + fixed(elapsed_ms) + ", \"executions_per_s\": " +
           fixed(static_cast<double>(executions) / (elapsed_ms / 1000.0), 0) + "}";
}

// A 16 MB scene through a chain of 8 pass-through tasks to a consumer, on one node.
std::string large_payload(const ComponentRegistry& registry, std::size_t scenes) {
    mission::Mission mission;
    mission.path = "<bench>";
    constexpr int hops = 8;
    for (int index = 0; index <= hops; ++index) {
        mission::Task task;
        task.name = "t" + std::to_string(index);
        task.component = index == hops ? "consumer" : "passthrough";
        task.port = 10 + index;
        task.inputs = {index == 0 ? "camera" : "t" + std::to_string(index - 1)};
        mission.tasks.push_back(task);
    }
    mission::Task camera;
    camera.name = "camera";
    camera.component = "passthrough";
    camera.port = 9;
    mission.tasks.push_back(camera);
    ManualClock clock;
    Executor executor(clock);
    for (int index = 0; index <= hops; ++index) {
        InstantiateResult instance = registry.instantiate(mission, "t" + std::to_string(index));
        executor.activate(*executor.add(std::move(*instance.instance)).id);
    }
    Sample scene;
    scene.type_id = counter_type_id;
    scene.source_port = 9;
    scene.payload = make_payload(counter_payload(1, 16u * 1024u * 1024u));
    std::size_t executions = 0;
    const auto start = Wall::now();
    for (std::size_t index = 0; index < scenes; ++index) {
        executor.deliver(scene);
        executions += executor.run_ready();
    }
    const double elapsed_ms = ms_since(start);
    return "{\"payload_bytes\": 16777216, \"hops\": " + std::to_string(hops + 1) +
           ", \"scenes\": " + std::to_string(scenes) +
           ", \"executions\": " + std::to_string(executions) +
           ", \"us_per_hop\": " + fixed(elapsed_ms * 1000.0 / static_cast<double>(executions)) +
           "}";
}

}  // namespace

int main(int argc, char** argv) {
    std::string out_path;
    bool quick = false;
    std::vector<std::size_t> sizes = {16, 64, 256, 1024, 4096};
    for (int index = 1; index < argc; ++index) {
        const std::string arg = argv[index];
        if (arg == "--out" && index + 1 < argc) {
            out_path = argv[++index];
        } else if (arg == "--quick") {
            quick = true;
        } else if (arg == "--help" || arg == "-h") {
            std::cout << "usage: keel-tasking-bench [--out PATH] [--quick]\n"
                         "Measures configuration time for 16..4096 components and executor "
                         "throughput; prints JSON.\n";
            return 0;
        } else {
            std::cerr << "keel-tasking-bench: unknown argument '" << arg << "'\n";
            return 2;
        }
    }
    ComponentRegistry registry;
    register_builtin_components(registry);

    std::ostringstream json;
    json << "{\n  \"benchmark\": \"tasking\",\n  \"hardware_threads\": "
         << std::thread::hardware_concurrency() << ",\n  \"configuration\": [\n";
    double median_1024 = 0;
    for (std::size_t size_index = 0; size_index < sizes.size(); ++size_index) {
        const std::size_t components = sizes[size_index];
        const mission::Mission mission = pairs_mission(components);
        const std::size_t runs = quick ? 3 : (components >= 1024 ? 11 : 31);
        configure_once(mission, registry);  // warm-up
        std::vector<double> totals, configure, activate, cpu;
        for (std::size_t run = 0; run < runs; ++run) {
            const ConfigurationRun result = configure_once(mission, registry);
            totals.push_back(result.total_ms);
            configure.push_back(result.instantiate_configure_ms);
            activate.push_back(result.activate_ms);
            cpu.push_back(result.cpu_ms);
        }
        const double total_median = median(totals);
        if (components == 1024) median_1024 = total_median;
        json << "    {\"components\": " << components << ", \"runs\": " << runs
             << ", \"total_ms\": {\"min\": "
             << fixed(*std::min_element(totals.begin(), totals.end()))
             << ", \"median\": " << fixed(total_median)
             << ", \"max\": " << fixed(*std::max_element(totals.begin(), totals.end()))
             << "}, \"instantiate_configure_wire_ms_median\": " << fixed(median(configure))
             << ", \"activate_ms_median\": " << fixed(median(activate))
             << ", \"cpu_ms_median\": " << fixed(median(cpu)) << ", \"us_per_component\": "
             << fixed(total_median * 1000.0 / static_cast<double>(components)) << "}"
             << (size_index + 1 < sizes.size() ? ",\n" : "\n");
    }
    json << "  ],\n  \"target\": {\"components\": 1024, \"max_ms\": 50, \"median_ms\": "
         << fixed(median_1024) << ", \"met\": " << (median_1024 <= 50.0 ? "true" : "false")
         << "},\n";
    json << "  \"throughput\": [\n    " << manual_throughput(registry, quick ? 50 : 500)
         << ",\n    " << threaded_throughput(registry, quick ? 20 : 200) << "\n  ],\n";
    json << "  \"large_payload\": " << large_payload(registry, quick ? 5 : 50) << "\n}\n";

    if (out_path.empty()) {
        std::cout << json.str();
    } else {
        std::ofstream file(out_path);
        if (!file) {
            std::cerr << "keel-tasking-bench: cannot write " << out_path << "\n";
            return 2;
        }
        file << json.str();
        std::cerr << "keel-tasking-bench: wrote " << out_path << "\n";
    }
    return 0;
}
