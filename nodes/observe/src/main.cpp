// keel-observe: joins a running cluster's protocol domain read only and prints what the
// nodes publish, one JSON object a line on stdout, for the console (keel-cluster console
// --dds, nodes/cluster/keel_cluster/console.py) or anyone watching.
//
//   keel-observe --domain ID [--security DIR] [--interface NAME] [--peer ADDRESS]...
//                [--period-ms P] [--seconds S]
//
// It reads KeelNodeState, KeelHeartbeat, KeelCommand, KeelAck and KeelError (a monitor's
// declarations) in every node's sender partition, and writes nothing: its participant has
// no writer (DdsConfig::read_only). With --security DIR (a `keel-cluster credentials`
// directory, or a run's `security` folder) it joins as the subscribe-only identity
// DIR/tools/monitor (CN=keel-monitor), whose permissions let it publish nothing; without,
// it joins an --insecure cluster. Ids are the mission's indices (the console names them
// from the image).
//
// Lines, each with "t_ns" (wall clock, as the nodes' traces) and "observed":
//   joined     {"domain", "secured"}: the participant exists
//   state      {"node", "name", "role", "epoch", "configuration_id", "configuration",
//               "phase"}: a node's KeelNodeState, when it changes
//   heartbeat  {"from", "epoch", "incarnation", "boot", "excluded", "waiting"}
//   command    {"from", "epoch", "seq", "config", "base", "master", "failed", "joint"}
//   activate   {"from", "epoch", "seq"}
//   ack        {"from", "to", "epoch", "seq", "kind"}: a switch's Prepared or Activated
//   checkpoint {"from", "to", "epoch", "task", "lineage", "count"}: the Storage node's ack
//   declare    {"from", "epoch", "failed"}: a monitor's declaration (failed == from: the
//              node asks for its own exclusion)
//   dropped    {"kind", "why"}: a sample that did not decode (counted, never printed whole)
// A heartbeat is printed once per node per --period-ms at most (they come every period from
// every node; the console needs them for liveness only), and a command, activate or
// declaration once per --period-ms while it stays the same (it goes to every node, one
// sample each, and is repeated).
//
// Exit status: 0 after --seconds (or on SIGINT/SIGTERM, or when stdout is closed); 2 for a
// usage error; 3 when DDS refuses the participant (credentials, access control), with the
// reason on stderr.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/fsm/codec.hpp"
#include "core/net/dds/dds_transport.hpp"

namespace {

using keel::net::MessageKind;
using nlohmann::json;

std::atomic<bool> stop{false};
void on_signal(int) { stop = true; }

std::int64_t wall_clock_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

// False when stdout is gone (the console ended): the observer ends too.
bool print(json line) {
    line["t_ns"] = wall_clock_ns();
    const std::string text = line.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
    return std::fwrite(text.data(), 1, text.size(), stdout) == text.size() && std::fflush(stdout) == 0;
}

json failed_ids(const keel::fsm::NodeSet& set) {
    json ids = json::array();
    set.for_each([&](keel::fsm::NodeId node) { ids.push_back(node); });
    return ids;
}

// The line a decoded message makes, or nothing for a message the console has no use for.
std::optional<json> line_of(const keel::net::Envelope& envelope, const keel::fsm::Message& message) {
    using namespace keel::fsm;
    return std::visit(
        [&](const auto& m) -> std::optional<json> {
            using T = std::decay_t<decltype(m)>;
            if constexpr (std::is_same_v<T, Heartbeat>) {
                if (m.reply) return std::nullopt;  // a monitor's reply: the sender's own heartbeat says it
                return json{{"observed", "heartbeat"}, {"from", m.from}, {"epoch", m.epoch},
                            {"incarnation", m.incarnation}, {"boot", m.boot},
                            {"excluded", m.excluded}, {"waiting", m.waiting}};
            } else if constexpr (std::is_same_v<T, Command>) {
                return json{{"observed", "command"}, {"from", m.from}, {"epoch", m.view.epoch},
                            {"seq", m.view.seq}, {"config", m.view.config}, {"base", m.view.base},
                            {"master", m.view.master}, {"failed", failed_ids(m.view.failed)},
                            {"joint", m.joint.size()}};
            } else if constexpr (std::is_same_v<T, ActivateCommand>) {
                return json{{"observed", "activate"}, {"from", m.from}, {"epoch", m.epoch}, {"seq", m.seq}};
            } else if constexpr (std::is_same_v<T, Ack>) {
                return json{{"observed", "ack"}, {"from", m.from}, {"to", envelope.destination},
                            {"epoch", m.epoch}, {"seq", m.seq}, {"kind", to_string(m.kind)}};
            } else if constexpr (std::is_same_v<T, CheckpointAck>) {
                return json{{"observed", "checkpoint"}, {"from", m.from}, {"to", envelope.destination},
                            {"epoch", m.epoch}, {"task", m.task}, {"lineage", m.version.lineage},
                            {"count", m.version.count}};
            } else if constexpr (std::is_same_v<T, ErrorNotification>) {
                return json{{"observed", "declare"}, {"from", m.from}, {"epoch", m.epoch},
                            {"failed", m.failed_node}};
            } else {
                return std::nullopt;
            }
        },
        message);
}

json state_line(const keel::net::NodeState& state) {
    return json{{"observed", "state"},
                {"node", state.node},
                {"name", state.name},
                {"role", std::string(keel::net::to_string(state.role))},
                {"epoch", state.epoch},
                {"configuration_id", state.configuration_id},
                {"configuration", state.configuration},
                {"phase", state.phase}};
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"keel-observe: a read-only view of a running cluster's protocol domain"};
    unsigned domain = 0;
    std::string security;
    std::string interface = "lo";
    std::vector<std::string> peers{"127.0.0.1"};
    unsigned period_ms = 100;
    double seconds = 0;
    app.add_option("--domain", domain, "the cluster's protocol DDS domain")->required()->check(CLI::Range(0, 230));
    app.add_option("--security", security,
                   "a credentials directory (keel-cluster credentials, or RUN_DIR/security): join as "
                   "its subscribe-only monitor identity (tools/monitor)");
    app.add_option("--interface", interface, "the network interface DDS uses (default lo)");
    app.add_option("--peer", peers, "unicast peer addresses (default 127.0.0.1)");
    app.add_option("--period-ms", period_ms, "print a node's heartbeat at most once per this many ms (default 100)")
        ->check(CLI::Range(1u, 60'000u));
    app.add_option("--seconds", seconds, "stop after this many seconds (default: until stopped)")
        ->check(CLI::Range(0.0, 1e7));
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);  // prints the help, or the error and a hint
        return code == 0 ? 0 : 2;
    }

    keel::net::dds::DdsConfig config;
    config.address = 65000;  // no node's: it names no writer (it has none) and no mission node
    config.domain_id = domain;
    config.network_interface = interface;
    config.peers = peers;
    config.read_only = true;
    // Whatever the mission's size: the nodes take the indices below (a 32-node mission on
    // one host takes 32 of them), and an observer the first one free.
    config.max_auto_participant_index = keel::net::dds::max_participant_indices;
    config.node_state_refresh = std::chrono::milliseconds(0);
    config.kinds = {MessageKind::heartbeat, MessageKind::reconfiguration_command,
                    MessageKind::acknowledgement, MessageKind::error_notification};
    if (!security.empty()) {
        const std::filesystem::path root = std::filesystem::absolute(security);
        const std::filesystem::path monitor = root / "tools" / "monitor";
        for (const auto& needed : {root / "ca.pem", root / "governance.p7s", monitor / "cert.pem",
                                   monitor / "key.pem", monitor / "permissions.p7s"}) {
            if (!std::filesystem::exists(needed)) {
                std::fprintf(stderr, "keel-observe: %s: missing (a credentials directory has the monitor's identity in tools/monitor)\n",
                             needed.string().c_str());
                return 2;
            }
        }
        config.security = keel::net::dds::security_files_in(root.string(), "");
        config.security.identity_certificate = (monitor / "cert.pem").string();
        config.security.private_key = (monitor / "key.pem").string();
        config.security.permissions = (monitor / "permissions.p7s").string();
    }
    std::optional<keel::net::dds::DdsTransport> joined;
    try {
        joined.emplace(config);
    } catch (const std::exception& refused) {
        std::fprintf(stderr, "keel-observe: DDS refused the participant in domain %u: %s\n", domain, refused.what());
        return 3;
    }
    keel::net::dds::DdsTransport& transport = *joined;
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::signal(SIGPIPE, SIG_IGN);
    if (!print(json{{"observed", "joined"}, {"domain", domain}, {"secured", !security.empty()}})) return 0;

    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const auto period = std::chrono::milliseconds(period_ms);
    std::map<std::uint16_t, Clock::time_point> heartbeat_printed;
    std::map<std::string, Clock::time_point> repeated;
    std::map<std::uint16_t, keel::net::NodeState> states;
    auto states_polled = Clock::time_point{};
    std::vector<keel::net::Inbound> inbound;
    bool open = true;
    while (open && !stop) {
        const auto now = Clock::now();
        if (seconds > 0 && now - start >= std::chrono::duration<double>(seconds)) break;
        if (now - states_polled >= std::chrono::milliseconds(50)) {
            states_polled = now;
            for (const keel::net::NodeState& state : transport.node_states()) {
                auto known = states.find(state.node);
                if (known != states.end() && known->second == state) continue;
                states[state.node] = state;
                open = open && print(state_line(state));
            }
        }
        transport.wait(std::chrono::milliseconds(20));
        inbound.clear();
        transport.receive(inbound, 4096);
        for (const keel::net::Inbound& in : inbound) {
            if (!in.ok) {
                open = open && print(json{{"observed", "dropped"}, {"kind", "envelope"}, {"why", in.detail}});
                continue;
            }
            const keel::fsm::DecodedMessage decoded = keel::fsm::decode(in.envelope.payload);
            if (!decoded.ok()) {
                open = open && print(json{{"observed", "dropped"},
                                          {"kind", std::string(keel::net::to_string(in.envelope.kind))},
                                          {"why", "the payload does not decode"}});
                continue;
            }
            auto line = line_of(in.envelope, *decoded.message);
            if (!line) continue;
            if ((*line)["observed"] == "heartbeat") {
                auto& last = heartbeat_printed[in.envelope.source];
                if (Clock::now() - last < period) continue;
                last = Clock::now();
            } else if ((*line)["observed"] != "ack" && (*line)["observed"] != "checkpoint") {
                // A Command, an Activate or a declaration goes to every node, one sample
                // each, and is repeated: printed once per period while it stays the same.
                if (repeated.size() > 4096) repeated.clear();  // bounded: a long run switches often
                auto& last = repeated[line->dump()];
                if (Clock::now() - last < period) continue;
                last = Clock::now();
            }
            open = open && print(std::move(*line));
        }
    }
    std::fflush(stdout);
    return 0;
}
