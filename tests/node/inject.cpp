// keel-node-inject: puts hostile traffic on a running cluster's DDS domain, for the test
// that every node drops it and keeps running (tests/node/test_cluster.py).
//
//   keel-node-inject --domain ID --address A [--count N] [--heartbeat-ms P] [--flood N]
//                    [--sample-port P --sample-bytes B] [--data-domain ID]
//                    [--security DIR --identity NODE] [--stall-s S]
//                    [--checkpoint-flood N --checkpoint-task T --checkpoint-to A
//                     --checkpoint-bytes B] [--request-flood N]
//                    [--impostor-of B [--impostor-s S]] [--error-flood-s S] [--rate R]
//
// Joins the domain as node address A (pinned to lo) and writes, N times each, on the
// topics a node reads: a protocol payload that does not decode, an error notification whose
// claimed sender is not its envelope's source, an envelope from an address outside the mission,
// an envelope from an epoch below every node's floor, and an envelope with an out-of-range
// kind-specific layout. With --flood N it then writes N samples of 60 MB on the large-data
// topic to every other node of a four-node mission (addressed, as nodes send large data), in
// the data plane's domain (--data-domain, default the node's: data_domain_for(ID)), while
// the protocol participant stays joined. With --sample-port it writes, five times, a sample
// of B payload bytes as the output of the task on port P, to every other node's data plane.
// With --stall-s S it writes nothing: it reads every protocol topic and takes nothing for S
// seconds (a stuck insider), then exits at once, without deleting its participant.
// With --checkpoint-flood N it writes N checkpoints of task T (its index in the mission) of
// B state bytes (default: the largest a checkpoint may carry, fsm::kMaxStateBytes), in the
// protocol's domain,
// each a version above the last, as its own node, to node A (default 3, the four-node
// mission's Storage node; checkpoints are addressed as nodes address them): an insider's
// flood of the protocol domain with the largest messages it admits. It then exits without
// deleting its participant.
// With --request-flood N it sends N checkpoint requests of task T to node A (the options
// above), each naming a switch of its own, as its own node: a flood of a few bytes each that
// asks for a whole state each, then exits without deleting its participant.
// With --impostor-of B --impostor-s S it writes, for S seconds and as fast as DDS takes them,
// heartbeats and Commands that name node B as their sender (envelope and payload), from its
// own writers: an insider speaking for another node on the keyed topics, where a sample of
// B's instance could displace B's own before a node takes it. Then it exits.
// With --error-flood-s S it writes, for S seconds and as fast as DDS takes them, error
// notifications whose payload does not decode, as its own node, to every node: a flood of
// small messages on a reliable keep-all topic every node reads. Then it exits.
// --rate R paces those two floods at R messages a second.
// With --command-on-error-topic it joins as a node that may not command does (its
// KeelCommand reader only) and writes, N times, a Command of a far newer epoch that names
// itself Master of safe mode on KeelError, the one protocol topic of bytes it may write.
// If DDS refuses its participant or a writer (access control), it prints {"refused": why}
// and exits with 3.
// With --message JSON (repeatable) it writes each message, --count times, every --every-ms,
// to node --to (default every node): any protocol message kind with any field values, as
// its own node (inject_message.hpp has the format). Fault model 3's tool: a value-faulty
// node says something wrong under its own name.
// With --security it joins with that node's credentials, as an insider. Prints one JSON line
// with what it sent.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/fsm/codec.hpp"
#include "core/net/dds/dds_transport.hpp"
#include "core/node/wire.hpp"
#include "inject_message.hpp"

int main(int argc, char** argv) {
    unsigned domain = 0;
    unsigned address = 0;
    unsigned count = 5;
    unsigned stale_epoch = 0;
    unsigned heartbeat_ms = 100;
    unsigned flood = 0;
    std::optional<unsigned> data_domain;
    unsigned sample_port = 0;
    unsigned stall_s = 0;
    unsigned sample_bytes = 0;
    unsigned checkpoint_flood = 0;
    unsigned checkpoint_task = 0;
    unsigned checkpoint_to = 3;
    std::size_t checkpoint_bytes = keel::fsm::kMaxStateBytes;
    unsigned request_flood = 0;
    std::optional<unsigned> impostor_of;
    unsigned impostor_s = 5;
    unsigned error_flood_s = 0;
    unsigned rate = 0;
    bool command_on_error_topic = false;
    std::vector<std::string> messages;
    std::optional<unsigned> to;
    unsigned every_ms = 20;
    CLI::App app{"keel-node-inject: hostile traffic for the node robustness test"};
    app.add_option("--message", messages,
                   "a protocol message as JSON, any kind, any field values (tests/node/"
                   "inject_message.hpp); written --count times, every --every-ms, to --to")
        ->check([](const std::string& text) {
            try {
                (void)keel::inject::message_from_json(nlohmann::json::parse(text), 0);
                return std::string();
            } catch (const std::exception& error) {
                return std::string(error.what());
            }
        });
    app.add_option("--to", to, "the node address --message goes to (default: every node)");
    app.add_option("--every-ms", every_ms, "milliseconds between two writes of --message");
    app.add_option("--domain", domain)->required();
    app.add_option("--address", address, "address written as the source")->required();
    app.add_option("--count", count);
    app.add_option("--stale-epoch", stale_epoch, "epoch to stamp on the stale messages");
    app.add_option("--heartbeat-ms", heartbeat_ms,
                   "the mission's heartbeat period (the heartbeat topic's QoS must match)");
    app.add_option("--flood", flood, "60 MB samples to write on the large-data topic");
    app.add_option("--stall-s", stall_s, "read every protocol topic, take nothing, for S s");
    app.add_option("--sample-port", sample_port, "write samples as the task on this port's");
    app.add_option("--sample-bytes", sample_bytes, "payload bytes of those samples");
    app.add_option("--checkpoint-flood", checkpoint_flood,
                   "largest checkpoints to write in the protocol's domain");
    app.add_option("--checkpoint-task", checkpoint_task, "the task those checkpoints are of");
    app.add_option("--checkpoint-to", checkpoint_to, "the node those checkpoints are sent to");
    app.add_option("--checkpoint-bytes", checkpoint_bytes, "the state bytes of each")
        ->check(CLI::Range(std::size_t{0}, keel::fsm::kMaxStateBytes));
    app.add_option("--request-flood", request_flood,
                   "checkpoint requests of --checkpoint-task to send to --checkpoint-to");
    app.add_option("--impostor-of", impostor_of,
                   "write heartbeats and Commands naming this node as their sender");
    app.add_option("--impostor-s", impostor_s, "for this many seconds (with --impostor-of)");
    app.add_option("--error-flood-s", error_flood_s,
                   "write undecodable error notifications as fast as DDS takes them, S s");
    app.add_option("--rate", rate,
                   "messages a second of --impostor-of and --error-flood-s (0: as fast as DDS "
                   "takes them)");
    app.add_flag("--command-on-error-topic", command_on_error_topic,
                 "command on KeelError, as a node without KeelCommand's writer");
    app.add_option("--data-domain", data_domain,
                   "the data plane's DDS domain (default: data_domain_for(--domain))");
    std::string security_dir;
    std::string identity;
    app.add_option("--security", security_dir,
                   "credentials directory (keel-cluster credentials): join as an insider");
    app.add_option("--identity", identity, "the node whose credentials to take (with --security)");
    CLI11_PARSE(app, argc, argv);

    keel::net::dds::DdsConfig config;
    config.address = static_cast<keel::net::NodeAddress>(address);
    config.domain_id = domain;
    config.heartbeat_period = std::chrono::milliseconds(heartbeat_ms);
    if (!security_dir.empty()) {
        config.security = keel::net::dds::security_files_in(security_dir, identity);
    }
    // Large data is addressed (a node's data plane reads its own partition only): the flood
    // goes to every other node of a four-node mission, one writer per destination.
    std::vector<keel::net::NodeAddress> flooded;
    for (keel::net::NodeAddress node = 0; node < 4; ++node) {
        if (node != address) flooded.push_back(node);
    }
    // Only the kinds it writes: a reader of the others (checkpoints, acknowledgements: keep-all)
    // that nobody drains fills up, and deleting a participant whose readers are full can hang
    // (Cyclone 0.10; seen in CI).
    config.kinds = {keel::net::MessageKind::error_notification,
                    keel::net::MessageKind::reconfiguration_command};
    if (impostor_of) config.kinds.push_back(keel::net::MessageKind::heartbeat);
    if (checkpoint_flood > 0) {
        config.kinds.push_back(keel::net::MessageKind::reliable_data);
        config.addressed_kinds = {keel::net::MessageKind::reliable_data};
        config.addressed_destinations = {static_cast<keel::net::NodeAddress>(checkpoint_to)};
    }
    if (request_flood > 0) {  // addressed, as nodes address requests
        config.kinds.push_back(keel::net::MessageKind::request);
        config.addressed_kinds.push_back(keel::net::MessageKind::request);
        config.addressed_destinations = {static_cast<keel::net::NodeAddress>(checkpoint_to)};
    }
    if (stall_s > 0) {
        config.kinds.clear();  // every kind, read only
        for (const keel::net::MessageKind kind : keel::net::all_message_kinds) {
            config.receive_only_kinds.push_back(kind);
        }
    }
    if (command_on_error_topic) {
        config.receive_only_kinds = {keel::net::MessageKind::reconfiguration_command};
    }
    if (!messages.empty()) {
        // Writers of the kinds the messages travel as, and no other (a node's identity may
        // write only some: the Storage node's commands none). Checkpoints, requests and
        // replies are addressed, as nodes address them.
        config.kinds.clear();
        config.addressed_kinds.clear();
        for (const std::string& text : messages) {
            const auto kind = keel::node::kind_of(keel::inject::message_from_json(nlohmann::json::parse(text), 0));
            if (std::find(config.kinds.begin(), config.kinds.end(), kind) != config.kinds.end()) continue;
            config.kinds.push_back(kind);
            if (kind == keel::net::MessageKind::reliable_data || kind == keel::net::MessageKind::request ||
                kind == keel::net::MessageKind::response || kind == keel::net::MessageKind::acknowledgement) {
                config.addressed_kinds.push_back(kind);
            }
        }
        const bool only_acks = config.addressed_kinds.size() == 1 &&
                               config.addressed_kinds[0] == keel::net::MessageKind::acknowledgement;
        if (!config.addressed_kinds.empty()) {
            // Acknowledgements are addressed as nodes address them (keel.node.D, or
            // keel.broadcast for every node); the other addressed kinds need a destination.
            if (!to && !only_acks) {
                std::fprintf(stderr, "keel-node-inject: --message of an addressed kind needs --to\n");
                return 2;
            }
            config.addressed_destinations = {to ? static_cast<keel::net::NodeAddress>(*to)
                                                : keel::net::broadcast_address};
        }
    }
    std::optional<keel::net::dds::DdsTransport> joined;
    try {
        joined.emplace(config);
    } catch (const keel::net::dds::DdsError& refused) {
        std::string why = refused.what();
        for (char& c : why) {
            if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20) c = ' ';
        }
        std::printf("{\"refused\": \"%s\"}\n", why.c_str());
        return 3;
    }
    keel::net::dds::DdsTransport& transport = *joined;
    if (stall_s > 0) {
        transport.wait_for_peers(0, std::chrono::milliseconds(3000));
        std::this_thread::sleep_for(std::chrono::seconds(stall_s));
        // What its readers hold now: at their bounds when the stall filled them.
        std::vector<keel::net::Inbound> held;
        transport.receive(held, 1'000'000);
        std::printf("{\"stalled_s\": %u, \"held\": %zu}\n", stall_s, held.size());
        std::fflush(stdout);
        std::_Exit(0);  // deleting a participant whose readers are full can hang (Cyclone 0.10)
    }
    std::optional<keel::net::dds::DdsTransport> data_plane;
    if (flood > 0 || sample_port > 0) {
        keel::net::dds::DdsConfig data = config;
        data.domain_id = data_domain.value_or(keel::net::dds::data_domain_for(domain));
        data.kinds = {keel::net::MessageKind::unreliable_data, keel::net::MessageKind::large};
        data.addressed_kinds = data.kinds;
        data.addressed_destinations = flooded;
        data_plane.emplace(data);
    }
    transport.wait_for_peers(1, std::chrono::milliseconds(3000));
    if (data_plane) data_plane->wait_for_peers(1, std::chrono::milliseconds(3000));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));

    using keel::net::Envelope;
    using keel::net::MessageKind;
    const auto source = static_cast<keel::net::NodeAddress>(address);
    const keel::net::Epoch epoch = 1'000;  // above every floor: only the payload is wrong
    std::uint64_t sent = 0;
    auto write = [&](Envelope envelope) {
        const bool on_data_plane = envelope.kind == MessageKind::large ||
                            envelope.kind == MessageKind::unreliable_data;
        keel::net::dds::DdsTransport& via = on_data_plane ? *data_plane : transport;
        if (via.send_unchecked(envelope) == keel::net::SendResult::sent) ++sent;
    };
    std::uint32_t sequence = 1;
    if (!messages.empty()) {
        // Fault model 3: what a value-faulty node says, under its own identity.
        std::vector<std::string> kinds;
        for (unsigned i = 0; i < count; ++i) {
            for (const std::string& text : messages) {
                const nlohmann::json spec = nlohmann::json::parse(text);
                const keel::fsm::Message message =
                    keel::inject::message_from_json(spec, static_cast<keel::fsm::NodeId>(address));
                if (i == 0) kinds.emplace_back(keel::fsm::kind_name(message));
                // The envelope's epoch: the message's own; for a kind without one (a phase
                // request), the JSON's "epoch", as an honest node stamps its current epoch.
                const keel::fsm::Epoch claimed =
                    std::holds_alternative<keel::fsm::Heartbeat>(message)
                        ? std::get<keel::fsm::Heartbeat>(message).epoch
                        : keel::fsm::has_epoch(message) ? keel::fsm::epoch_of(message)
                                                        : spec.value("epoch", keel::fsm::Epoch{0});
                write({keel::node::kind_of(message), source,
                       to ? static_cast<keel::net::NodeAddress>(*to) : keel::net::broadcast_address, 0,
                       std::min<keel::net::Epoch>(claimed, keel::net::max_epoch), sequence++,
                       keel::fsm::encode(message)});
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(every_ms));
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        std::string names;
        for (const std::string& kind : kinds) names += (names.empty() ? "\"" : ", \"") + kind + "\"";
        std::printf("{\"sent\": %llu, \"kinds\": [%s]}\n", static_cast<unsigned long long>(sent), names.c_str());
        return 0;
    }
    if (command_on_error_topic) {
        keel::fsm::View view;
        view.epoch = 1'002;
        view.seq = 1;
        view.master = static_cast<keel::fsm::NodeId>(address);
        view.config = keel::fsm::kSafeConfig;
        const std::vector<std::uint8_t> command = keel::fsm::encode(
            keel::fsm::Message{keel::fsm::Command(static_cast<keel::fsm::NodeId>(address), view)});
        for (unsigned i = 0; i < count; ++i) {
            write({MessageKind::error_notification, source, keel::net::broadcast_address, 0,
                   view.epoch, sequence++, command});
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        std::printf("{\"sent\": %llu}\n", static_cast<unsigned long long>(sent));
        return 0;
    }
    // The floods' pace: the n-th message not before n / rate seconds from the start.
    const auto flood_start = std::chrono::steady_clock::now();
    auto pace = [&](std::uint64_t n) {
        if (rate == 0) return;
        std::this_thread::sleep_until(flood_start +
                                      std::chrono::microseconds(n * 1'000'000 / rate));
    };
    if (impostor_of) {
        // What node B would say if it meant to be excluded, or to command the whole
        // cluster into safe mode under a far newer epoch: believed, either reconfigures.
        const auto b = static_cast<keel::fsm::NodeId>(*impostor_of);
        const auto claimed = static_cast<keel::net::NodeAddress>(*impostor_of);
        const keel::net::Epoch newer = 1'002;
        keel::fsm::Heartbeat heartbeat{b, newer, 1'000, true, 1, {}, false};
        keel::fsm::View view;
        view.epoch = newer;
        view.seq = 1;
        view.master = b;
        view.config = keel::fsm::kSafeConfig;
        const std::vector<std::uint8_t> command =
            keel::fsm::encode(keel::fsm::Message{keel::fsm::Command(b, view)});
        std::uint64_t heartbeats = 0;
        std::uint64_t commands = 0;
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(impostor_s);
        while (std::chrono::steady_clock::now() < until) {
            for (int i = 0; i < 64; ++i, ++heartbeat.seq) {
                pace(heartbeats + commands);
                write({MessageKind::heartbeat, claimed, keel::net::broadcast_address, 0, newer,
                       sequence++, keel::fsm::encode(keel::fsm::Message{heartbeat})});
                ++heartbeats;
            }
            write({MessageKind::reconfiguration_command, claimed, keel::net::broadcast_address, 0,
                   newer, sequence++, command});
            ++commands;
        }
        std::printf("{\"sent\": %llu, \"heartbeats\": %llu, \"commands\": %llu}\n",
                    static_cast<unsigned long long>(sent),
                    static_cast<unsigned long long>(heartbeats),
                    static_cast<unsigned long long>(commands));
        std::fflush(stdout);
        std::_Exit(0);
    }
    if (error_flood_s > 0) {
        std::uint64_t errors = 0;
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(error_flood_s);
        while (std::chrono::steady_clock::now() < until) {
            pace(errors);
            write({MessageKind::error_notification, source, keel::net::broadcast_address, 0, epoch,
                   sequence++, {0xde, 0xad, 0xbe, 0xef}});
            ++errors;
        }
        std::printf("{\"sent\": %llu, \"errors\": %llu}\n", static_cast<unsigned long long>(sent),
                    static_cast<unsigned long long>(errors));
        std::fflush(stdout);
        std::_Exit(0);  // as after the checkpoint flood
    }
    for (unsigned i = 0; i < count; ++i) {
        // 1. undecodable protocol payload (on the error topic: the typed topics, commands,
        //    heartbeats and acknowledgements, cannot even carry it)
        write({MessageKind::error_notification, source, keel::net::broadcast_address, 0, epoch,
               sequence++, {0xde, 0xad, 0xbe, 0xef}});
        // 2. an error notification claiming to come from another node than its envelope's
        //    source (were it believed, the Master would exclude node 1). Not a heartbeat: the
        //    heartbeat topic keeps the latest sample per source, so forged heartbeats would
        //    also crowd out the real node's.
        keel::fsm::ErrorNotification forged{static_cast<keel::fsm::NodeId>((address + 1) % 4), epoch, 1};
        write({MessageKind::error_notification, source, keel::net::broadcast_address, 0, epoch,
               sequence++, keel::fsm::encode(forged)});
        // 3. an envelope from an address outside the mission
        write({MessageKind::error_notification, 200, keel::net::broadcast_address, 0, epoch,
               sequence++, keel::fsm::encode(keel::fsm::ErrorNotification{200, epoch, 0})});
        // 4. a stale epoch: an Activate from an epoch below the nodes' floor
        write({MessageKind::reconfiguration_command, source, keel::net::broadcast_address, 0,
               stale_epoch, sequence++,
               keel::fsm::encode(keel::fsm::ActivateCommand{static_cast<keel::fsm::NodeId>(address),
                                                            stale_epoch, 1})});
        // 5. an error notification with a truncated body
        auto truncated = keel::fsm::encode(keel::fsm::ErrorNotification{source, epoch, 1});
        truncated.pop_back();
        write({MessageKind::error_notification, source, keel::net::broadcast_address, 0, epoch,
               sequence++, truncated});
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    // A sample as a node's data plane encodes it: type id, sequence, timestamp, payload.
    std::vector<std::uint8_t> sample(20 + sample_bytes, 0x33);
    for (unsigned i = 0; sample_port > 0 && i < 5; ++i) {
        for (const keel::net::NodeAddress node : flooded) {
            write({MessageKind::unreliable_data, source, node,
                   static_cast<keel::net::Port>(sample_port), epoch, sequence++, sample});
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    const std::vector<std::uint8_t> huge(60u * 1024u * 1024u, 0x5a);
    for (unsigned i = 0; i < flood; ++i) {
        for (const keel::net::NodeAddress node : flooded) {
            write({MessageKind::large, source, node, 0, epoch, sequence++, huge});
        }
    }
    // The floods of checkpoints and requests are of the cluster's own epoch (the tests flood
    // a cluster in its initial configuration, epoch 1): one far above is dropped unread
    // (fault model 3's epoch bound), and the floods are to reach the store and its budget.
    // Their versions open a lineage of that epoch, above every state of the initial one.
    const keel::net::Epoch flood_epoch = 1;
    if (checkpoint_flood > 0) {
        keel::fsm::CheckpointWrite checkpoint{static_cast<keel::fsm::NodeId>(address), flood_epoch,
                                         static_cast<keel::fsm::TaskId>(checkpoint_task),
                                         keel::fsm::Version(keel::fsm::lineage_of(flood_epoch, 1), 1), false,
                                         std::vector<std::uint8_t>(checkpoint_bytes, 0x77)};
        const auto started = std::chrono::steady_clock::now();
        for (unsigned i = 0; i < checkpoint_flood; ++i, ++checkpoint.version.count) {
            write({MessageKind::reliable_data, source,
                   static_cast<keel::net::NodeAddress>(checkpoint_to), 0, flood_epoch, sequence++,
                   keel::fsm::encode(checkpoint)});
        }
        const std::chrono::duration<double> took = std::chrono::steady_clock::now() - started;
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        std::printf("{\"sent\": %llu, \"checkpoint_flood_s\": %.3f}\n",
                    static_cast<unsigned long long>(sent), took.count());
        std::fflush(stdout);
        std::_Exit(0);  // its KeelReliableData reader is never drained (see above)
    }
    if (request_flood > 0) {
        const auto started = std::chrono::steady_clock::now();
        for (unsigned i = 0; i < request_flood; ++i) {
            write({MessageKind::request, source, static_cast<keel::net::NodeAddress>(checkpoint_to),
                   0, flood_epoch, sequence++,
                   keel::fsm::encode(keel::fsm::CheckpointRequest{
                       static_cast<keel::fsm::NodeId>(address), flood_epoch, i,
                       static_cast<keel::fsm::TaskId>(checkpoint_task)})});
        }
        const std::chrono::duration<double> took = std::chrono::steady_clock::now() - started;
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        std::printf("{\"sent\": %llu, \"request_flood_s\": %.3f}\n",
                    static_cast<unsigned long long>(sent), took.count());
        std::fflush(stdout);
        std::_Exit(0);  // as after the checkpoint flood
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    std::printf("{\"sent\": %llu}\n", static_cast<unsigned long long>(sent));
    return 0;
}
