// keel-node: one node of a Keel cluster (one process per mission node).
//
//   keel-node --mission FILE --node NAME [--trace FILE] [--domain ID] [--interface IFACE]
//             [--peers ADDR,...] [--storage-db PATH] [--control-stdin] [--realtime]
//
// The contract with the cluster launcher (flags, stdin control lines, stdout JSON status
// lines, NDJSON trace) is nodes/cluster/README.md. Logs go to stderr; stdout carries only
// status lines. Exit codes: 0 clean stop (SIGTERM, SIGINT, `quit`), 2 bad input (flags,
// mission file errors as file:line:col), 3 the node could not start (DDS, files).
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "core/node/runtime.hpp"
#include "nodes/keel-node/components.hpp"

namespace {

keel::node::NodeRuntime* g_runtime = nullptr;

void on_signal(int) {
    if (g_runtime != nullptr) g_runtime->request_stop();
}

std::vector<std::string> split_commas(const std::string& text) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t end = text.find(',', start);
        const std::string part = text.substr(start, end == std::string::npos ? std::string::npos : end - start);
        if (!part.empty()) parts.push_back(part);
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return parts;
}

}  // namespace

int main(int argc, char** argv) {
    auto logger = spdlog::stderr_color_mt("keel-node");
    spdlog::set_default_logger(logger);
    spdlog::set_pattern("%H:%M:%S.%e %^%l%$ %v");

    keel::node::RuntimeOptions options;
    std::string peers = "127.0.0.1";
    bool control_stdin = false;
    std::string log_level = "info";
    CLI::App app{"keel-node: one node of a Keel cluster (roles Master, Observer, Worker, Storage, "
                 "Interface), running the mission's components under the verified protocols over "
                 "Cyclone DDS"};
    app.add_option("--mission", options.mission_path, "mission file (YAML, schema 1)")->required();
    app.add_option("--node", options.node, "this node's name in the mission")->required();
    app.add_option("--trace", options.trace_path, "append NDJSON protocol trace lines here");
    app.add_option("--domain", options.domain_id, "DDS domain id")->check(CLI::Range(0, 232));
    app.add_option("--interface", options.network_interface, "network interface DDS is pinned to");
    app.add_option("--peers", peers, "unicast discovery peers, comma-separated");
    app.add_option("--storage-db", options.storage_db_path,
                   "SQLite file for the node's persistent state (and, on the Storage node, checkpoints)");
    app.add_flag("--control-stdin", control_stdin,
                 "read control lines on stdin: phase NAME, partition NODE..., heal, status, quit");
    app.add_flag("--realtime", options.realtime,
                 "run components under SCHED_FIFO when the machine permits");
    app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
        ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);
        return code == 0 ? 0 : 2;
    }
    spdlog::set_level(spdlog::level::from_str(log_level));
    options.peers = split_commas(peers);
    options.status_sink = [](const std::string& line) {
        std::fwrite(line.data(), 1, line.size(), stdout);
        std::fputc('\n', stdout);
        std::fflush(stdout);
    };

    keel::tasking::ComponentRegistry registry;
    if (!keel::node::register_node_components(registry)) {
        std::fprintf(stderr, "keel-node: duplicate component name in the registry\n");
        return 3;
    }
    auto created = keel::node::NodeRuntime::create(options, registry);
    if (auto* error = std::get_if<keel::node::SetupError>(&created)) {
        std::fputs(error->message.c_str(), stderr);
        return error->exit_code;
    }
    auto runtime = std::move(std::get<std::unique_ptr<keel::node::NodeRuntime>>(created));
    g_runtime = runtime.get();
    struct sigaction action {};
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGTERM, &action, nullptr);
    sigaction(SIGINT, &action, nullptr);
    std::signal(SIGPIPE, SIG_IGN);

    if (control_stdin) {
        // Blocking reads on stdin cannot be interrupted portably: the reader is detached and
        // the process ends with _Exit once the runtime has shut down cleanly.
        std::thread([runtime_ptr = runtime.get()] {
            std::string line;
            while (std::getline(std::cin, line)) runtime_ptr->post_command(line);
        }).detach();
    }
    const int code = runtime->run();
    g_runtime = nullptr;
    runtime.reset();
    spdlog::shutdown();
    std::fflush(stdout);
    std::fflush(stderr);
    std::_Exit(code);
}
