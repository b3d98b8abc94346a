// keel-node's command line as a library (keel/node/main.hpp): one node of a Keel cluster
// (one process per mission node), running the components of the registry it is given.
//
//   keel-node --mission IMAGE --node NAME (--security DIR | --insecure) [--public-key PUB]
//             [--trace FILE] [--domain ID] [--data-domain ID]
//             [--interface IFACE] [--peers ADDR,...] [--storage-db PATH] [--cold-start]
//             [--control-stdin] [--realtime] [--log-level LEVEL] [--log-format text|json]
//   keel-node --list-components
//
// A node flies only a mission image (keel-verify compile's output, core/mission/image.hpp);
// a mission YAML is refused (exit 2), saying how to compile it. The contract with the cluster
// launcher (flags, stdin control lines, stdout JSON status lines, NDJSON trace) is
// nodes/cluster/README.md. Logs go to stderr; stdout carries only status lines (and the
// component names of --list-components). Exit codes: 0 clean stop (SIGTERM, SIGINT,
// `quit`), 2 bad input (flags, a refused image as `IMAGE:LINE:COL: REASON: message`,
// mission file errors as file:line:col), 3 the node could not start (DDS, files, a
// component name registered twice), 4 its DDS Security credentials were refused (missing,
// expired, revoked, another node's...). A binary built with keel_add_node() says its own
// name where keel-node says "keel-node".
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <system_error>
#include <thread>
#include <variant>
#include <vector>

#include <pthread.h>

#include <getopt.h>
#include <unistd.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "logging.hpp"

#include "core/mission/image.hpp"
#include "core/net/dds/credentials.hpp"
#include "core/node/runtime.hpp"
#include "keel/node/main.hpp"

namespace {

// The usage text, naming the program as it names itself.
std::string usage(const std::string& program) {
    return program + ": one node of a Keel cluster (roles Master, Observer, Worker, Storage,\n"
    "Interface), running the mission's components under the verified protocols over\n"
    "Cyclone DDS.\n"
    "\n"
    "usage: " + program + " --mission IMAGE --node NAME (--security DIR | --insecure) [options]\n"
    "       " + program + " --list-components\n"
    "  --mission IMAGE     mission image (keel-verify compile MISSION.yaml -o IMAGE.json);\n"
    "                      a mission YAML is refused, saying how to compile it\n"
    "  --node NAME         this node's name in the mission\n"
    "  --security DIR      the node's kit of DDS Security credentials (keel-cluster\n"
    "                      credentials MISSION --out SET --kit NAME: SET/kits/NAME):\n"
    "                      ca.pem, governance.p7s, crl.pem, the ground's\n"
    "                      operator/{cert.pem,permissions.p7s}, mission/signing.pub and\n"
    "                      nodes/NAME/{cert.pem,key.pem,permissions.p7s}; a folder\n"
    "                      holding another private key (the CA's...) is refused\n"
    "  --insecure          run without DDS Security (tests, and DDS tools without\n"
    "                      credentials); a node speaks only for itself either way\n"
    "  --public-key PUB    Ed25519 public key (PEM): fly only images signed with its key\n"
    "  --trace FILE        append NDJSON protocol trace lines here\n"
    "  --domain ID         DDS domain id of the protocol (0..232, default 0)\n"
    "  --data-domain ID    DDS domain id of the data plane (samples between components;\n"
    "                      0..232, not the protocol's; default (ID + 116) mod 231)\n"
    "  --interface IFACE   network interface DDS is pinned to (default lo)\n"
    "  --peers ADDR,...    unicast discovery peers (default 127.0.0.1)\n"
    "  --storage-db PATH   the node's persistent state: PATH.state (its epoch, view,\n"
    "                      boot; synced in place) and the SQLite file PATH (on the\n"
    "                      Storage node, the checkpoints); a copy needs both\n"
    "  --cold-start        discard the persisted protocol state (epoch, view,\n"
    "                      incarnation) and boot the initial configuration; the Storage\n"
    "                      node keeps its checkpoints and the tasks resume from them.\n"
    "                      For a deliberate fresh start of the whole cluster (a power\n"
    "                      cycle recovers without it: the initial Master warm-boots)\n"
    "  --control-stdin     read control lines on stdin: ground SIGNATURE COMMAND (a\n"
    "                      ground command signed by the operator: phase, recover,\n"
    "                      exclude, readmit, pause-task, resume-task, designate\n"
    "                      NODE WAIT SPAN ECHO (signed only);\n"
    "                      docs/operations.md; unsigned `phase NAME`, `recover CONFIG`,\n"
    "                      `exclude NODE`, `readmit NODE`, `pause-task TASK`,\n"
    "                      `resume-task TASK` only with --insecure),\n"
    "                      status, quit; a test build (KEEL_FAULT_INJECTION, not a\n"
    "                      flight build) also partition NODE..., deaf [NODE...]\n"
    "                      (receive nothing from them; all: none named), heal\n"
    "  --realtime          the protocol loop under SCHED_FIFO above its tasks, memory\n"
    "                      locked, where the machine permits (the node says at boot and\n"
    "                      in its status lines what it got; docs/clusters.md)\n"
    "  --realtime-priority N  with --realtime: the loop's SCHED_FIFO priority, 1..99\n"
    "                      (default 50)\n"
    "  --task-priority N   with --realtime: the tasks' SCHED_FIFO priority, below the\n"
    "                      loop's; 0 (default): normal scheduling\n"
    "  --loop-budget PERCENT  with --realtime: the share of every 10 ms the loop may use\n"
    "                      the CPU, 1..100 (default 50); past it the loop sleeps until it\n"
    "                      has kept its share, 10 ms at most\n"
    "  --log-level LEVEL   trace, debug, info (default), warn, error\n"
    "  --log-format FORMAT text (default: UTC date and time, level, message) or json\n"
    "                      (one object per line: time, level, node, message)\n"
    "  --list-components   print the components this binary runs, one per line, and exit\n"
    "  -h, --help          this text\n"
    "      --version       the version\n"
    "\n"
    "Status lines (JSON) go to stdout, logs to stderr. Exit codes: 0 clean stop (SIGTERM,\n"
    "SIGINT, quit), 2 bad input (a refused image as IMAGE:LINE:COL: REASON: message,\n"
    "mission errors as file:line:col, a mission revision older than the one this node\n"
    "flew), 3 cannot start, 4 credentials refused (FILE: why),\n"
    "5 a disk failure (state or checkpoint not written: it asked to be excluded and stopped).\n";
}

// A private key in a node's credentials directory that is not the node's own: the CA's,
// the operator's, the mission signing key, another node's (the first found), or nothing.
std::optional<std::string> secret_beside(const std::string& security_dir, const std::string& node) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::absolute(security_dir);
    std::error_code error;
    for (const fs::path& secret :
         {dir / "ca.key", dir / "operator" / "key.pem", dir / "mission" / "signing.key"}) {
        if (fs::exists(secret, error)) return secret.string();
    }
    for (const auto& entry : fs::directory_iterator(dir / "nodes", error)) {
        if (entry.path().filename() != node && fs::exists(entry.path() / "key.pem", error)) {
            return (entry.path() / "key.pem").string();
        }
    }
    for (const auto& entry : fs::directory_iterator(dir / "tools", error)) {  // a tool's identity
        if (fs::exists(entry.path() / "key.pem", error)) return (entry.path() / "key.pem").string();
    }
    return std::nullopt;
}

// SIGTERM and SIGINT are blocked in every thread and taken by a watcher thread (sigwait),
// which asks the runtime to stop: request_stop() wakes the loop at once, which a signal
// handler could not do (a DDS guard condition takes a lock).
std::mutex g_runtime_mutex;
keel::node::NodeRuntime* g_runtime = nullptr;  // guarded by g_runtime_mutex

void watch_stop_signals(sigset_t signals) {
    for (;;) {
        int signal_number = 0;
        if (sigwait(&signals, &signal_number) != 0) return;
        std::lock_guard lock(g_runtime_mutex);
        if (g_runtime != nullptr) g_runtime->request_stop();
    }
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

// The image a mission YAML compiles to: the same path with .json for .yaml or .yml.
std::string image_path_for(const std::string& yaml) {
    for (const char* suffix : {".yaml", ".yml"}) {
        const std::string ending(suffix);
        if (yaml.size() > ending.size() &&
            yaml.compare(yaml.size() - ending.size(), ending.size(), ending) == 0) {
            return yaml.substr(0, yaml.size() - ending.size()) + ".json";
        }
    }
    return yaml + ".json";
}

// Checks the mission before the runtime loads it: a node flies only a proven mission
// image (keel-verify compile's output), verified (its signature with `public_key`, when
// given) and named in the log; anything else (a mission YAML) is refused, saying how to
// compile it. Returns the loaded mission, or the exit code to stop with.
std::variant<keel::mission::Mission, int> load_mission(const char* program, const std::string& path,
                                                        const std::string& public_key, std::string* sha256) {
    const bool image = keel::mission::is_mission_image(path);
    std::error_code ignored;
    if (!image && ::access(path.c_str(), R_OK) == 0 &&
        std::filesystem::is_regular_file(path, ignored)) {
        std::fprintf(stderr,
                     "%s: %s is not a mission image: a node flies only what keel-verify "
                     "proved; compile it: keel-verify compile %s -o %s%s\n",
                     program, path.c_str(), path.c_str(), image_path_for(path).c_str(),
                     public_key.empty() ? "" : " --sign-key KEY (signed with the key of --public-key)");
        return 2;
    }
    keel::mission::ImageOptions options;
    options.public_key_path = public_key;
    keel::mission::ImageSummary summary;
    const keel::mission::LoadResult loaded =
        keel::mission::load_mission_image(path, options, &summary);
    if (!loaded.ok()) {
        for (const auto& error : loaded.errors) {
            std::fprintf(stderr, "%s\n", error.to_string().c_str());
        }
        const std::string& reason = loaded.errors.front().rule;
        if (reason == "unsigned" || reason == "wrong-key" || reason == "bad-signature") {
            std::fprintf(stderr, "%s: sign the image with the mission's key: keel-verify "
                                 "compile MISSION.yaml -o %s --sign-key KEY\n", program, path.c_str());
        } else if (reason != "unreadable" && reason != "over-limit" && reason != "public-key") {
            std::fprintf(stderr, "%s: compile the mission again: keel-verify compile "
                                 "MISSION.yaml -o %s\n", program, path.c_str());
        }
        return 2;
    }
    std::string signature = "unsigned";
    if (summary.signature_verified) {
        signature = "signature verified, key id " + summary.key_id;
    } else if (!summary.key_id.empty()) {
        signature = "signed with key id " + summary.key_id + ", not checked (no --public-key)";
    }
    spdlog::info("mission image {}: {} proved by keel-verify {}, sha256 {}, {}", path,
                 loaded.mission->name, summary.verifier, summary.sha256, signature);
    *sha256 = summary.sha256;
    return std::move(*loaded.mission);
}

}  // namespace

namespace keel::node {

const char* keel_version() {
    return KEEL_VERSION;
}

std::string register_component_sets(tasking::ComponentRegistry& registry,
                                    std::span<const ComponentSet> sets) {
    // Who registered each name, for the message when another set takes it again.
    std::map<std::string, std::string, std::less<>> registered_by;
    for (const std::string& name : registry.names()) registered_by.emplace(name, "the registry given");
    for (const ComponentSet& set : sets) {
        tasking::ComponentRegistry own;
        if (!set.add || !set.add(own)) {
            return set.name + " registers a component name twice (or an empty factory)";
        }
        const std::vector<std::string> names = own.names();
        if (const auto taken = registry.merge(std::move(own))) {
            return "component '" + *taken + "' of " + set.name + " is already registered by " +
                   registered_by.at(*taken);
        }
        for (const std::string& name : names) registered_by.emplace(name, set.name);
    }
    return {};
}

int node_main(int argc, char** argv, std::span<const ComponentSet> sets, const NodeProgram& program) {
    tasking::ComponentRegistry registry;
    if (const std::string problem = register_component_sets(registry, sets); !problem.empty()) {
        std::fprintf(stderr, "%s: %s\n", program.name.c_str(), problem.c_str());
        return 3;
    }
    return node_main(argc, argv, registry, program);
}

int node_main(int argc, char** argv, const tasking::ComponentRegistry& registry,
              const NodeProgram& program) {
    const char* const name = program.name.c_str();
    const std::string usage_string = usage(program.name);
    const char* const usage_text = usage_string.c_str();
    // Not registered by name: a process may hold another logger of that name.
    auto logger = std::make_shared<spdlog::logger>(
        program.name, std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
    spdlog::set_default_logger(logger);
    set_log_format(LogFormat::text, "");

    RuntimeOptions options;
    std::string peers = "127.0.0.1";
    bool control_stdin = false;
    std::optional<int> realtime_priority;
    std::optional<int> task_priority;
    std::optional<int> loop_budget;
    bool list_components = false;
    std::string public_key;
    std::string security_dir;
    bool insecure = false;
    std::string log_level = "info";
    LogFormat log_format = LogFormat::text;
    // Flags by getopt_long: the flight binary carries no argument-parsing library.
    enum Flag : int { mission = 1, node, trace, domain, interface, peers_flag, storage_db,
                      cold_start, control, realtime, log_level_flag, help, version,
                      public_key_flag, list_components_flag, security_flag, insecure_flag,
                      log_format_flag, data_domain_flag, realtime_priority_flag,
                      task_priority_flag, loop_budget_flag };
    const option flags[] = {
        {"mission", required_argument, nullptr, mission},
        {"node", required_argument, nullptr, node},
        {"trace", required_argument, nullptr, trace},
        {"domain", required_argument, nullptr, domain},
        {"data-domain", required_argument, nullptr, data_domain_flag},
        {"interface", required_argument, nullptr, interface},
        {"peers", required_argument, nullptr, peers_flag},
        {"storage-db", required_argument, nullptr, storage_db},
        {"cold-start", no_argument, nullptr, cold_start},
        {"control-stdin", no_argument, nullptr, control},
        {"realtime", no_argument, nullptr, realtime},
        {"realtime-priority", required_argument, nullptr, realtime_priority_flag},
        {"task-priority", required_argument, nullptr, task_priority_flag},
        {"loop-budget", required_argument, nullptr, loop_budget_flag},
        {"log-level", required_argument, nullptr, log_level_flag},
        {"log-format", required_argument, nullptr, log_format_flag},
        {"help", no_argument, nullptr, help},
        {"version", no_argument, nullptr, version},
        {"public-key", required_argument, nullptr, public_key_flag},
        {"list-components", no_argument, nullptr, list_components_flag},
        {"security", required_argument, nullptr, security_flag},
        {"insecure", no_argument, nullptr, insecure_flag},
        {nullptr, 0, nullptr, 0},
    };
    opterr = 0;
    for (int flag; (flag = getopt_long(argc, argv, "h", flags, nullptr)) != -1;) {
        const std::string value = optarg != nullptr ? optarg : "";
        switch (flag) {
            case mission: options.mission_path = value; break;
            case node: options.node = value; break;
            case trace: options.trace_path = value; break;
            case domain:
            case data_domain_flag: {
                const char* what = flag == domain ? "--domain" : "--data-domain";
                char* end = nullptr;
                const unsigned long id = std::strtoul(value.c_str(), &end, 10);
                if (value.empty() || value[0] < '0' || value[0] > '9' || *end != '\0' ||
                    id > 232) {
                    std::fprintf(stderr, "%s: %s %s: not a DDS domain id (0..232)\n", name, what,
                                 value.c_str());
                    return 2;
                }
                if (flag == domain) options.domain_id = static_cast<std::uint32_t>(id);
                else options.data_domain_id = static_cast<std::uint32_t>(id);
                break;
            }
            case interface: options.network_interface = value; break;
            case peers_flag: peers = value; break;
            case storage_db: options.storage_db_path = value; break;
            case cold_start: options.cold_start = true; break;
            case control: control_stdin = true; break;
            case realtime: options.scheduling.realtime = true; break;
            case realtime_priority_flag:
            case task_priority_flag:
            case loop_budget_flag: {
                const char* what = flag == realtime_priority_flag ? "--realtime-priority"
                                   : flag == task_priority_flag   ? "--task-priority"
                                                                  : "--loop-budget";
                char* end = nullptr;
                const long number = std::strtol(value.c_str(), &end, 10);
                if (value.empty() || value[0] < '0' || value[0] > '9' || *end != '\0') {
                    std::fprintf(stderr, "%s: %s %s: not a number\n", name, what, value.c_str());
                    return 2;
                }
                if (number > 1000) {  // validate() names the range
                    std::fprintf(stderr, "%s: %s %s: out of range\n", name, what, value.c_str());
                    return 2;
                }
                if (flag == realtime_priority_flag) realtime_priority = static_cast<int>(number);
                else if (flag == task_priority_flag) task_priority = static_cast<int>(number);
                else loop_budget = static_cast<int>(number);
                break;
            }
            case public_key_flag: public_key = value; break;
            case list_components_flag: list_components = true; break;
            case security_flag: security_dir = value; break;
            case insecure_flag: insecure = true; break;
            case log_level_flag:
                if (value != "trace" && value != "debug" && value != "info" && value != "warn" &&
                    value != "error") {
                    std::fprintf(stderr, "%s: --log-level %s: one of trace, debug, info, warn, error\n",
                                 name, value.c_str());
                    return 2;
                }
                log_level = value;
                break;
            case log_format_flag:
                if (const auto format = parse_log_format(value)) {
                    log_format = *format;
                } else {
                    std::fprintf(stderr, "%s: --log-format %s: one of text, json\n", name,
                                 value.c_str());
                    return 2;
                }
                break;
            case version:
                // A binary of its own version also says which Keel it runs on.
                if (program.version.empty() || program.version == KEEL_VERSION) {
                    std::printf("%s %s\n", name, KEEL_VERSION);
                } else {
                    std::printf("%s %s (Keel %s)\n", name, program.version.c_str(), KEEL_VERSION);
                }
                return 0;
            case 'h':
            case help: std::fputs(usage_text, stdout); return 0;
            default:
                std::fprintf(stderr, "%s: %s: unknown flag or missing value\n%s", name,
                             argv[optind - 1], usage_text);
                return 2;
        }
    }
    if (optind < argc) {
        std::fprintf(stderr, "%s: unexpected argument '%s'\n%s", name, argv[optind], usage_text);
        return 2;
    }
    if (list_components) {
        for (const std::string& component : registry.names()) std::printf("%s\n", component.c_str());
        return std::fflush(stdout) == 0 ? 0 : 3;
    }
    if (options.mission_path.empty() || options.node.empty()) {
        std::fprintf(stderr, "%s: --mission and --node are required\n%s", name, usage_text);
        return 2;
    }
    if (options.data_domain_id == options.domain_id) {
        std::fprintf(stderr, "%s: --data-domain %u: the data plane needs a DDS domain of its own, "
                             "not the protocol's (--domain)\n",
                     name, static_cast<unsigned>(options.domain_id));
        return 2;
    }
    if ((realtime_priority || task_priority || loop_budget) && !options.scheduling.realtime) {
        std::fprintf(stderr, "%s: --realtime-priority, --task-priority and --loop-budget need "
                             "--realtime\n", name);
        return 2;
    }
    if (realtime_priority) options.scheduling.loop_priority = *realtime_priority;
    if (task_priority) options.scheduling.task_priority = *task_priority;
    if (loop_budget) options.scheduling.budget_percent = *loop_budget;
    if (const std::string wrong = keel::node::validate(options.scheduling); !wrong.empty()) {
        std::fprintf(stderr, "%s: %s\n", name, wrong.c_str());
        return 2;
    }
    if (options.cold_start && options.storage_db_path.empty()) {
        std::fprintf(stderr, "%s: --cold-start needs --storage-db (without it every boot is "
                             "a first boot)\n", name);
        return 2;
    }
    if (security_dir.empty() == !insecure) {
        std::fprintf(stderr, "%s: %s\n", name,
                     insecure ? "--security and --insecure exclude each other"
                              : "a node runs secured: give --security DIR (made by `keel-cluster "
                                "credentials MISSION --out DIR`), or --insecure to run without "
                                "DDS Security");
        return 2;
    }
    if (!insecure) {
        options.security = net::dds::security_files_in(security_dir, options.node);
        if (const auto problem = net::dds::check_credentials(options.security, options.node)) {
            std::fprintf(stderr, "%s: credentials refused: %s: %s\n", name, problem->file.c_str(),
                         problem->message.c_str());
            return 4;
        }
        // The ground's operator (docs/operations.md): a secured node takes ground commands
        // only signed by it, so it needs the operator's certificate and permissions.
        auto loaded = net::dds::OperatorIdentity::load(options.security,
                                                       net::dds::operator_files_in(security_dir));
        // A problem with the operator's files does not ground the node: it flies and takes
        // no ground command (each refused, naming the problem), until it is given valid ones.
        if (const auto* problem = std::get_if<net::dds::CredentialProblem>(&loaded)) {
            options.operator_problem = problem->file + ": " + problem->message;  // logged at boot
        } else {
            options.operator_identity = std::move(std::get<net::dds::OperatorIdentity>(loaded));
        }
        options.credential_expiries =
            net::dds::credential_expiries(options.security, net::dds::operator_files_in(security_dir));
        // A node holds its own key and public material only: never the CA's key (whoever
        // holds it can make identities), the operator's key (it speaks for the ground), the
        // mission signing key (it makes images nodes fly) or another node's key.
        // keel-cluster gives each node its kit (DIR/kits/NAME).
        if (const auto secret = secret_beside(security_dir, options.node)) {
            std::fprintf(stderr,
                         "%s: credentials refused: %s: a node never holds this key; give the node its kit "
                         "(keel-cluster credentials MISSION --out DIR --kit %s: DIR/kits/%s) "
                         "(docs/security.md)\n",
                         name, secret->c_str(), options.node.c_str(), options.node.c_str());
            return 4;
        }
    }
    spdlog::set_level(spdlog::level::from_str(log_level));
    set_log_format(log_format, options.node);
    options.peers = split_commas(peers);
    options.status_sink = [](const std::string& line) {
        std::fwrite(line.data(), 1, line.size(), stdout);
        std::fputc('\n', stdout);
        std::fflush(stdout);
    };

    auto flown = load_mission(name, options.mission_path, public_key, &options.image_sha256);
    if (const int* refused = std::get_if<int>(&flown)) return *refused;
    auto created =
        NodeRuntime::create(options, std::move(std::get<keel::mission::Mission>(flown)), registry);
    if (auto* error = std::get_if<SetupError>(&created)) {
        std::fputs(error->message.c_str(), stderr);
        return error->exit_code;
    }
    auto runtime = std::move(std::get<std::unique_ptr<NodeRuntime>>(created));
    {
        std::lock_guard lock(g_runtime_mutex);
        g_runtime = runtime.get();
    }
    std::signal(SIGPIPE, SIG_IGN);
    // A file-size limit (RLIMIT_FSIZE) reached is a failed write (EFBIG), the path a full
    // disk takes (docs/fault-model.md, "Durable state"), never a killed process.
    std::signal(SIGXFSZ, SIG_IGN);
    // Blocked before any other thread exists (DDS's, the executor's), so every thread
    // inherits the mask and only the watcher takes the signals.
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGTERM);
    sigaddset(&stop_signals, SIGINT);
    pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
    std::thread(watch_stop_signals, stop_signals).detach();

    if (control_stdin) {
        // Blocking reads on stdin cannot be interrupted portably: the reader is detached and
        // the process ends with _Exit once the runtime has shut down cleanly.
        std::thread([runtime_ptr = runtime.get()] {
            std::string line;
            while (std::getline(std::cin, line)) runtime_ptr->post_command(line);
        }).detach();
    }
    const int code = runtime->run();
    {
        std::lock_guard lock(g_runtime_mutex);
        g_runtime = nullptr;
    }
    runtime.reset();
    spdlog::shutdown();
    std::fflush(stdout);
    std::fflush(stderr);
    std::_Exit(code);
}

}  // namespace keel::node
