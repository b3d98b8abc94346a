// keel-store-bench: what durable checkpoints cost the Storage node (StateDb, the file its
// checkpoint writer keeps; state_db.hpp).
//
//   keel-store-bench [--writes 400] [--bytes 1024] [--tasks 4] [--dir DIR] [--out FILE]
//
// Writes `writes` checkpoints of `bytes` bytes, round robin over `tasks` tasks, into a fresh
// database per durability (synchronous=FULL, what keel-node runs, and synchronous=NORMAL,
// what it ran before), in alternating rounds of 20 writes each so that both see the same
// disk and load. A write's time is StateDb::store_checkpoint's: one transaction, from the
// call to its return, which is when the checkpoint writer reports it written and the held
// acknowledgement may leave (checkpoint_persister.hpp). Prints one JSON object per
// durability: p50, p99, mean and max in microseconds, and writes per second.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/node/state_db.hpp"

namespace {

using keel::node::Durability;
using keel::node::StateDb;

struct Series {
    const char* name;
    Durability durability;
    std::vector<double> us;
};

double percentile(std::vector<double> values, double p) {
    std::sort(values.begin(), values.end());
    const auto index = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1) + 0.5);
    return values[std::min(index, values.size() - 1)];
}

std::string summary(const Series& series) {
    const double total = std::accumulate(series.us.begin(), series.us.end(), 0.0);
    char text[512];
    std::snprintf(text, sizeof text,
                  "{\"durability\": \"%s\", \"writes\": %zu, \"p50_us\": %.1f, \"p99_us\": %.1f, "
                  "\"mean_us\": %.1f, \"max_us\": %.1f, \"writes_per_s\": %.0f}",
                  series.name, series.us.size(), percentile(series.us, 0.5), percentile(series.us, 0.99),
                  total / static_cast<double>(series.us.size()),
                  *std::max_element(series.us.begin(), series.us.end()),
                  1e6 * static_cast<double>(series.us.size()) / total);
    return text;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"keel-store-bench: durable checkpoint writes (synchronous=FULL) against NORMAL"};
    int writes = 400;
    int bytes = 1024;
    int tasks = 4;
    std::string dir;
    std::string out;
    app.add_option("--writes", writes, "writes per durability")->check(CLI::Range(20, 1000000));
    app.add_option("--bytes", bytes, "state bytes per checkpoint")->check(CLI::Range(0, 16 << 20));
    app.add_option("--tasks", tasks, "tasks written round robin")->check(CLI::Range(1, 64));
    app.add_option("--dir", dir, "where the databases go (default: a fresh temporary folder)");
    app.add_option("--out", out, "also write the JSON here");
    CLI11_PARSE(app, argc, argv);

    namespace fs = std::filesystem;
    const bool own_dir = dir.empty();
    fs::path folder = own_dir ? fs::temp_directory_path() / ("keel-store-bench-" + std::to_string(::getpid()))
                              : fs::path(dir);
    std::error_code ignored;
    fs::create_directories(folder, ignored);
    std::vector<Series> series{{"full", Durability::full, {}}, {"normal", Durability::normal, {}}};
    try {
        std::vector<std::unique_ptr<StateDb>> dbs;
        for (const Series& s : series) {
            const fs::path path = folder / (std::string("store-") + s.name + ".sqlite");
            fs::remove(path, ignored);
            fs::remove(path.string() + "-wal", ignored);
            fs::remove(path.string() + "-shm", ignored);
            dbs.push_back(std::make_unique<StateDb>(path.string(), s.durability));
        }
        std::vector<std::uint8_t> state(static_cast<std::size_t>(bytes));
        std::uint64_t count = 0;
        constexpr int kRound = 20;
        for (int done = 0; done < writes; done += kRound) {
            for (std::size_t which = 0; which < series.size(); ++which) {
                for (int i = 0; i < kRound && done + i < writes; ++i) {
                    ++count;
                    if (!state.empty()) state[0] = static_cast<std::uint8_t>(count);
                    const std::string task = "task" + std::to_string((done + i) % tasks);
                    const auto start = std::chrono::steady_clock::now();
                    dbs[which]->store_checkpoint(task, {0, count}, state);
                    const auto took = std::chrono::steady_clock::now() - start;
                    series[which].us.push_back(std::chrono::duration<double, std::micro>(took).count());
                }
            }
        }
    } catch (const keel::node::StateDbError& error) {
        std::fprintf(stderr, "keel-store-bench: %s\n", error.what());
        return 1;
    }
    if (own_dir) fs::remove_all(folder, ignored);
    std::string json = "{\"bytes\": " + std::to_string(bytes) + ", \"tasks\": " + std::to_string(tasks) +
                       ", \"series\": [" + summary(series[0]) + ", " + summary(series[1]) + "]}";
    std::printf("%s\n", json.c_str());
    if (!out.empty()) std::ofstream(out) << json << "\n";
    return 0;
}
