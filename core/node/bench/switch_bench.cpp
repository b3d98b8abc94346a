// keel-switch-bench: the paper's real-time switch (tasks A, B, C), measured on loopback DDS.
//
//   keel-switch-bench [--domain ID] [--switches 150] [--period-ms 20] [--lease-ms 25]
//                     [--up-ms 120] [--out FILE]
//
// Three processes: A (primary, ownership strength 2) and B (backup, strength 1) publish the
// same sampled stream every period; C (this process) subscribes. A runs for up-ms, then
// "dies" at a random instant of its period (it stops writing, as a crashed or hung node
// would), stays silent for lease + up-ms, and comes back. Each death is one switch: its time
// is from A's death to the first sample of B that C's subscriber delivers (sampled.hpp:
// DDS reports A's lease expired, and the subscriber hands over B's latest sample). A tells C the instant of each
// death over a pipe (CLOCK_MONOTONIC is shared by the processes of one host).
// Prints one JSON object: p50/p99/mean/max of the switch time over the switches measured.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/net/dds/sampled.hpp"

namespace {

using keel::net::dds::SampledConfig;
using keel::net::dds::SampledPublisher;
using keel::net::dds::SampledSample;
using keel::net::dds::SampledSubscriber;

constexpr std::uint16_t kStream = 100;

std::int64_t monotonic_ns() {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

void sleep_until_ns(std::int64_t deadline) {
    timespec at{};
    at.tv_sec = deadline / 1'000'000'000;
    at.tv_nsec = deadline % 1'000'000'000;
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR) {
    }
}

struct Options {
    unsigned domain = 0;
    unsigned switches = 150;
    unsigned period_ms = 20;
    unsigned lease_ms = 25;
    unsigned up_ms = 120;
    std::string out;
    // DDS Security: the credentials directory and the identities of the primary (address 1),
    // the backup (2) and the subscriber (3); empty directory: insecure.
    std::string security;
    std::vector<std::string> identities{"PN2", "PN3", "ST1"};
};

keel::net::dds::SecurityFiles security_for(const Options& options, keel::net::NodeAddress address) {
    if (options.security.empty()) return {};
    return keel::net::dds::security_files_in(options.security, options.identities.at(address - 1));
}

// A publisher process: writes every period; the primary dies and revives in cycles,
// reporting each death instant on `report_fd`. Runs until killed.
[[noreturn]] void publish(const Options& options, keel::net::NodeAddress address,
                          std::int32_t strength, int report_fd) {
    SampledConfig config;
    config.address = address;
    config.domain_id = options.domain;
    config.lease = std::chrono::milliseconds(options.lease_ms);
    config.security = security_for(options, address);
    SampledPublisher publisher(config, kStream, strength);
    const std::int64_t period = std::int64_t{options.period_ms} * 1'000'000;
    std::mt19937_64 random(address * 7919u + 1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uint64_t sequence = 0;
    std::int64_t next = monotonic_ns();
    std::int64_t cycle_start = next;
    const std::uint8_t payload[8] = {};
    for (;;) {
        sleep_until_ns(next);
        publisher.write(++sequence, monotonic_ns(), payload);
        const std::int64_t last_write = next;
        next += period;
        if (report_fd < 0 || next - cycle_start < std::int64_t{options.up_ms} * 1'000'000) continue;
        // Die at a random instant before the next write, stay silent, come back.
        const std::int64_t death = last_write + static_cast<std::int64_t>(unit(random) * static_cast<double>(period));
        sleep_until_ns(death);
        const std::int64_t reported = monotonic_ns();
        if (write(report_fd, &reported, sizeof reported) != sizeof reported) _exit(1);
        const std::int64_t back = reported + std::int64_t{options.lease_ms + options.up_ms} * 1'000'000;
        sleep_until_ns(back);
        next = back;
        cycle_start = back;
    }
}

double percentile(std::vector<double> values, double p) {
    std::sort(values.begin(), values.end());
    const auto index = static_cast<std::size_t>(p / 100.0 * static_cast<double>(values.size() - 1) + 0.5);
    return values[std::min(index, values.size() - 1)];
}

}  // namespace

int main(int argc, char** argv) {
    Options options;
    options.domain = 201 + static_cast<unsigned>(getpid()) % 24;
    CLI::App app{"keel-switch-bench: real-time switch of sampled data to a backup publisher"};
    app.add_option("--domain", options.domain, "DDS domain id");
    app.add_option("--switches", options.switches, "switches to measure")->check(CLI::Range(1, 100000));
    app.add_option("--period-ms", options.period_ms, "sampling period")->check(CLI::Range(1, 10000));
    app.add_option("--lease-ms", options.lease_ms, "liveliness lease (> period)")->check(CLI::Range(1, 10000));
    app.add_option("--up-ms", options.up_ms, "how long the primary runs between deaths");
    app.add_option("--out", options.out, "write the JSON here too");
    app.add_option("--security", options.security,
                   "credentials directory (keel-cluster credentials): run secured");
    app.add_option("--identities", options.identities,
                   "identities of the primary, backup and subscriber (addresses 1, 2, 3)")
        ->delimiter(',')
        ->expected(3);
    CLI11_PARSE(app, argc, argv);
    if (options.lease_ms <= options.period_ms) {
        std::fprintf(stderr, "keel-switch-bench: --lease-ms must exceed --period-ms\n");
        return 2;
    }

    int pipe_fds[2];
    if (pipe(pipe_fds) != 0) return 3;
    // Fork before any DDS entity exists in this process.
    const pid_t backup = fork();
    if (backup == 0) {
        close(pipe_fds[0]);
        close(pipe_fds[1]);
        publish(options, 2, 1, -1);
    }
    const pid_t primary = fork();
    if (primary == 0) {
        close(pipe_fds[0]);
        publish(options, 1, 2, pipe_fds[1]);
    }
    close(pipe_fds[1]);
    fcntl(pipe_fds[0], F_SETFL, O_NONBLOCK);

    int code = 0;
    std::vector<double> switch_ms;
    std::uint64_t samples = 0;
    {
        SampledConfig config;
        config.address = 3;
        config.domain_id = options.domain;
        config.lease = std::chrono::milliseconds(options.lease_ms);
        config.security = security_for(options, 3);
        SampledSubscriber subscriber(config);
        std::deque<std::int64_t> deaths;  // reported, waiting for B's first sample
        std::vector<SampledSample> batch;
        const std::int64_t give_up = monotonic_ns() +
            std::int64_t{options.switches + 20} * (2 * options.up_ms + options.lease_ms + 2 * options.period_ms) * 1'000'000 +
            30'000'000'000;
        bool primary_seen = false;
        while (switch_ms.size() < options.switches && monotonic_ns() < give_up) {
            subscriber.wait(std::chrono::milliseconds(5));
            const std::int64_t received = monotonic_ns();
            batch.clear();
            subscriber.take(batch);
            std::int64_t death = 0;
            while (read(pipe_fds[0], &death, sizeof death) == sizeof death) {
                // A death before C has seen A own the stream measures nothing.
                if (primary_seen) deaths.push_back(death);
            }
            for (const SampledSample& sample : batch) {
                ++samples;
                if (sample.writer == 1) primary_seen = true;
                if (sample.writer != 2 || deaths.empty()) continue;
                switch_ms.push_back(static_cast<double>(received - deaths.front()) / 1e6);
                deaths.clear();  // one switch per death; B keeps the stream until A is back
            }
        }
    }
    kill(primary, SIGKILL);
    kill(backup, SIGKILL);
    waitpid(primary, nullptr, 0);
    waitpid(backup, nullptr, 0);
    if (switch_ms.empty()) {
        std::fprintf(stderr, "keel-switch-bench: no switch measured (did the publishers match?)\n");
        return 1;
    }
    double sum = 0;
    for (double value : switch_ms) sum += value;
    char json[1024];
    std::snprintf(json, sizeof json,
                  "{\"switches\": %zu, \"period_ms\": %u, \"lease_ms\": %u, \"p50_ms\": %.3f, "
                  "\"p99_ms\": %.3f, \"mean_ms\": %.3f, \"min_ms\": %.3f, \"max_ms\": %.3f, "
                  "\"samples\": %llu, \"paper_mean_ms\": 66, \"target_p99_ms\": 30}",
                  switch_ms.size(), options.period_ms, options.lease_ms, percentile(switch_ms, 50),
                  percentile(switch_ms, 99), sum / static_cast<double>(switch_ms.size()),
                  *std::min_element(switch_ms.begin(), switch_ms.end()),
                  *std::max_element(switch_ms.begin(), switch_ms.end()),
                  static_cast<unsigned long long>(samples));
    std::printf("%s\n", json);
    if (!options.out.empty()) std::ofstream(options.out) << json << "\n";
    if (switch_ms.size() < options.switches) {
        std::fprintf(stderr, "keel-switch-bench: only %zu of %u switches measured\n", switch_ms.size(),
                     options.switches);
        code = 1;
    }
    return code;
}
