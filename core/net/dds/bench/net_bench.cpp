// keel-net-bench: measures Keel's network layer over real Cyclone DDS on loopback.
//
//   keel-net-bench pong --domain D [--duration S]
//       node 2: echoes every envelope on port 1 back to its sender (same kind, same
//       payload); counts and discards envelopes on port 2. Stops after S seconds or on
//       SIGTERM/SIGINT.
//   keel-net-bench ping --domain D [--sizes 64,65536,16777216] [--rounds-small N] ...
//       node 1: for each payload size, sends an envelope to node 2, waits for the echo,
//       and records the round trip (component to component: Endpoint to Endpoint, filter
//       included). Then sends bursts of best-effort KeelData to port 2 and reads the
//       interface's tx_bytes counter to measure bytes on the wire per message.
//       Prints one JSON object; exits 1 if any round trip got no echo.
//   keel-net-bench cdr-size [--domain D]
//       serialises KeelData samples through DDS in one process and reports the
//       serialized size Cyclone sends (ddsi_serdata_size), as JSON.
//   keel-net-bench beacon --domain D --address N --name PN1 --role master [...]
//       a stand-in node: publishes its NodeState and broadcasts a heartbeat every period,
//       so DDS tools can be tried on something (core/net/README.md, "Observing a cluster").
//   keel-net-bench bare-pong|bare-ping --domain D [--keep-last] [--sizes 64,65536] ...
//       the floor under Keel's own code: plain libddsc, the same participant (domain
//       configuration, DDS Security when --security is given), the same topic
//       (KeelReliableData, keel_wire_Message), partitions and QoS as Keel's reliable_data
//       (reliable, keep-all with Keel's resource limits), or with --keep-last reliable
//       keep-last 1 as ddsperf's ping/pong. One reader on one waitset, no envelope, no
//       filter, no sender check: bare-pong writes back what it takes (dds_take), bare-ping
//       prints round trips as ping does.
//   keel-net-bench config-xml [--interface lo]
//       prints the Cyclone DDS configuration Keel uses (for CYCLONEDDS_URI of DDS tools,
//       e.g. ddsperf, so they run pinned exactly like Keel's nodes).
//
// Every participant uses domain_config_xml(): interface lo, no multicast, peer 127.0.0.1.
#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "core/fsm/codec.hpp"
#include "core/net/dds/dds_transport.hpp"
#include "core/net/dds/security_qos.hpp"
#include "core/net/endpoint.hpp"
#include "keel.h"

namespace {

using namespace keel::net;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr NodeAddress ping_address = 1;
constexpr NodeAddress pong_address = 2;
constexpr Port echo_port = 1;
constexpr Port sink_port = 2;
constexpr std::size_t large_threshold_bytes = 1024 * 1024;

std::atomic<bool> stop_requested{false};
// DDS Security: the credentials directory (keel-cluster credentials) and the identity this
// process takes from it; empty directory: insecure.
std::string security_dir;
std::string identity;
extern "C" void on_signal(int) { stop_requested = true; }

dds::DdsConfig bench_config(NodeAddress address, std::uint32_t domain_id,
                            const std::string& interface_name) {
    dds::DdsConfig config;
    config.address = address;
    config.domain_id = domain_id;
    config.network_interface = interface_name;
    config.max_blocking_time = 10s;
    if (!security_dir.empty()) {
        const std::string name =
            // prototype3's nodes at addresses 1 and 2: the sender partitions their
            // permissions grant (keel.from.1, keel.from.2).
            !identity.empty() ? identity : (address == pong_address ? "PN3" : "PN2");
        config.security = dds::security_files_in(security_dir, name);
    }
    return config;
}

// Payloads of 1 MiB and more go on KeelLarge; smaller ones on `small_kind`.
MessageKind small_kind = MessageKind::reliable_data;
MessageKind kind_for(std::size_t payload_bytes) {
    return payload_bytes >= large_threshold_bytes ? MessageKind::large : small_kind;
}

const char* topic_for(MessageKind kind) {
    for (const auto& row : dds::topic_table()) {
        if (row.kind == kind) return row.topic_name;
    }
    return "?";
}

int run_pong(std::uint32_t domain_id, const std::string& interface_name, double duration_s) {
    auto transport = std::make_unique<dds::DdsTransport>(
        bench_config(pong_address, domain_id, interface_name));
    Endpoint endpoint(std::move(transport), FilterConfig{.known_nodes = {ping_address, pong_address}});
    const auto end = Clock::now() + std::chrono::duration<double>(duration_s);
    std::uint64_t echoed = 0;
    std::uint64_t sunk = 0;
    while (!stop_requested && Clock::now() < end) {
        endpoint.wait(100ms);
        endpoint.poll([&](Envelope&& envelope) {
            if (envelope.port != echo_port) {
                ++sunk;
                return;
            }
            Envelope echo = endpoint.make_envelope(envelope.kind, envelope.source, envelope.port,
                                                   std::move(envelope.payload));
            echo.sequence = envelope.sequence;  // the pinger matches echoes by sequence
            if (endpoint.send(echo) == SendResult::sent) ++echoed;
        });
    }
    std::fprintf(stderr, "pong: echoed %llu, discarded %llu\n",
                 static_cast<unsigned long long>(echoed), static_cast<unsigned long long>(sunk));
    return 0;
}

double percentile(std::vector<double> values, double fraction) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    // Nearest rank.
    auto rank = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(values.size())));
    rank = std::clamp<std::size_t>(rank, 1, values.size());
    return values[rank - 1];
}

std::string number(double value) {
    std::ostringstream out;
    out.precision(3);
    out << std::fixed << value;
    return out.str();
}

// Round trips of `rounds` envelopes of `payload_bytes`, after `warmup` unrecorded ones.
std::string measure_latency(Endpoint& endpoint, std::size_t payload_bytes, std::size_t warmup,
                            std::size_t rounds, std::size_t& total_timeouts) {
    const MessageKind kind = kind_for(payload_bytes);
    std::vector<std::uint8_t> payload(payload_bytes);
    for (std::size_t i = 0; i < payload_bytes; ++i) payload[i] = static_cast<std::uint8_t>(i);
    std::vector<double> rtt_us;
    rtt_us.reserve(rounds);
    std::size_t timeouts = 0;
    const auto round_timeout = payload_bytes >= large_threshold_bytes ? 10s : 2s;
    for (std::size_t round = 0; round < warmup + rounds; ++round) {
        // The envelope (and its payload copy) is built before the clock starts.
        Envelope envelope = endpoint.make_envelope(kind, pong_address, echo_port, payload);
        const Sequence sequence = envelope.sequence;
        bool echoed = false;
        const auto start = Clock::now();
        if (endpoint.send(envelope) != SendResult::sent) {
            ++timeouts;
            continue;
        }
        const auto give_up = start + round_timeout;
        while (!echoed && Clock::now() < give_up) {
            endpoint.wait(give_up - Clock::now());
            endpoint.poll([&](Envelope&& reply) {
                if (reply.sequence == sequence && reply.payload.size() == payload_bytes) {
                    echoed = true;
                }
            });
        }
        const auto stop = Clock::now();
        if (!echoed) {
            ++timeouts;
            continue;
        }
        if (round >= warmup) {
            rtt_us.push_back(std::chrono::duration<double, std::micro>(stop - start).count());
        }
    }
    total_timeouts += timeouts;
    double sum = 0;
    for (double value : rtt_us) sum += value;
    const double mean = rtt_us.empty() ? 0.0 : sum / static_cast<double>(rtt_us.size());
    std::ostringstream json;
    json << "{\"payload_bytes\": " << payload_bytes << ", \"kind\": \"" << to_string(kind)
         << "\", \"topic\": \"" << topic_for(kind) << "\", \"rounds\": " << rtt_us.size()
         << ", \"timeouts\": " << timeouts << ", \"rtt_us\": {\"p50\": "
         << number(percentile(rtt_us, 0.50)) << ", \"p99\": " << number(percentile(rtt_us, 0.99))
         << ", \"mean\": " << number(mean) << ", \"min\": " << number(percentile(rtt_us, 0.0))
         << ", \"max\": " << number(percentile(rtt_us, 1.0)) << "}, \"one_way_us\": {\"p50\": "
         << number(percentile(rtt_us, 0.50) / 2) << ", \"p99\": "
         << number(percentile(rtt_us, 0.99) / 2) << "}}";
    return json.str();
}

// Sends small probes to pong's echo port until one comes back or `timeout` passes.
bool echo_path_ready(Endpoint& endpoint, std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    const std::vector<std::uint8_t> payload(8, 0x11);
    while (Clock::now() < deadline) {
        Envelope probe = endpoint.make_envelope(kind_for(payload.size()), pong_address, echo_port, payload);
        const Sequence sequence = probe.sequence;
        if (endpoint.send(probe) != SendResult::sent) {
            std::this_thread::sleep_for(20ms);
            continue;
        }
        const auto give_up = std::min(deadline, Clock::now() + std::chrono::milliseconds(200));
        bool echoed = false;
        while (!echoed && Clock::now() < give_up) {
            endpoint.wait(give_up - Clock::now());
            endpoint.poll([&](Envelope&& reply) { echoed = echoed || reply.sequence == sequence; });
        }
        if (echoed) return true;
    }
    return false;
}

std::uint64_t interface_tx_bytes(const std::string& interface_name) {
    std::ifstream in("/sys/class/net/" + interface_name + "/statistics/tx_bytes");
    std::uint64_t bytes = 0;
    in >> bytes;
    return bytes;
}

// Bytes on the wire per best-effort KeelData message: bursts of `messages`, the smallest
// per-message value over `repeats` bursts (other traffic on the interface only adds).
std::string measure_wire(Endpoint& endpoint, const std::string& interface_name,
                         std::size_t payload_bytes, std::size_t messages, std::size_t repeats) {
    std::vector<std::uint8_t> payload(payload_bytes, 0x5A);
    double best = 1e18;
    for (std::size_t repeat = 0; repeat < repeats; ++repeat) {
        std::vector<Envelope> burst;
        burst.reserve(messages);
        for (std::size_t i = 0; i < messages; ++i) {
            burst.push_back(endpoint.make_envelope(MessageKind::unreliable_data, pong_address,
                                                   sink_port, payload));
        }
        const std::uint64_t before = interface_tx_bytes(interface_name);
        for (const Envelope& envelope : burst) endpoint.send(envelope);
        const std::uint64_t after = interface_tx_bytes(interface_name);
        best = std::min(best, static_cast<double>(after - before) / static_cast<double>(messages));
        std::this_thread::sleep_for(50ms);
        endpoint.poll([](Envelope&&) {});
    }
    std::ostringstream json;
    json << "{\"payload_bytes\": " << payload_bytes << ", \"messages_per_burst\": " << messages
         << ", \"bursts\": " << repeats << ", \"interface_tx_bytes_per_message\": " << number(best)
         << "}";
    return json.str();
}

std::vector<std::size_t> parse_sizes(const std::string& text) {
    std::vector<std::size_t> sizes;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) sizes.push_back(std::stoull(item));
    return sizes;
}

int run_ping(std::uint32_t domain_id, const std::string& interface_name,
             const std::string& sizes_text, std::size_t rounds_small, std::size_t rounds_large,
             std::size_t wire_messages) {
    auto transport = std::make_unique<dds::DdsTransport>(
        bench_config(ping_address, domain_id, interface_name));
    if (!transport->wait_for_peers(1, 30s)) {
        std::cerr << "ping: no pong found in domain " << domain_id << "\n";
        return 1;
    }
    Endpoint endpoint(std::move(transport), FilterConfig{.known_nodes = {ping_address, pong_address}});
    // Our writers matching pong's readers does not mean pong's writers match ours yet (with
    // DDS Security the two directions finish their handshakes apart), and an echo written
    // before that is not delivered: probe until one echo comes back before measuring.
    if (!echo_path_ready(endpoint, 30s)) {
        std::cerr << "ping: pong in domain " << domain_id << " never echoed a probe\n";
        return 1;
    }
    std::ostringstream json;
    json << "{\"latency\": [";
    bool first = true;
    std::size_t timeouts = 0;
    for (std::size_t size : parse_sizes(sizes_text)) {
        const bool large = size >= large_threshold_bytes;
        const std::size_t rounds = large ? rounds_large : rounds_small;
        const std::size_t warmup = large ? 2 : std::max<std::size_t>(rounds / 20, 10);
        if (!first) json << ", ";
        first = false;
        json << measure_latency(endpoint, size, warmup, rounds, timeouts);
    }
    json << "], \"wire\": [";
    json << measure_wire(endpoint, interface_name, 64, wire_messages, 5) << ", ";
    json << measure_wire(endpoint, interface_name, 0, wire_messages, 5);
    json << "], \"counters\": {\"sent\": " << endpoint.counters().sent
         << ", \"received\": " << endpoint.counters().received
         << ", \"send_failed\": " << endpoint.counters().send_failed << "}}";
    std::cout << json.str() << std::endl;
    if (timeouts > 0) {
        std::cerr << "ping: " << timeouts << " round trips got no echo\n";
        return 1;
    }
    return 0;
}

struct BeaconOptions {
    NodeAddress address = 1;
    std::string name = "PN1";
    std::string role = "master";
    Epoch epoch = 1;
    std::uint32_t configuration_id = 1;
    std::string configuration = "C1";
    std::string phase = "observation";
    std::uint32_t period_ms = 100;
};

int run_beacon(std::uint32_t domain_id, const std::string& interface_name, double duration_s,
               const BeaconOptions& options) {
    dds::DdsConfig config = bench_config(options.address, domain_id, interface_name);
    config.heartbeat_period = std::chrono::milliseconds(options.period_ms);
    dds::DdsTransport transport(config);
    NodeState state{.node = options.address,
                    .name = options.name,
                    .role = Role::unknown,
                    .epoch = options.epoch,
                    .configuration_id = options.configuration_id,
                    .configuration = options.configuration,
                    .phase = options.phase};
    for (Role role : {Role::master, Role::observer, Role::worker, Role::storage, Role::interface}) {
        if (to_string(role) == options.role) state.role = role;
    }
    transport.publish_node_state(state);
    Envelope heartbeat;
    heartbeat.kind = MessageKind::heartbeat;
    heartbeat.source = options.address;
    heartbeat.epoch = options.epoch;
    const auto end = Clock::now() + std::chrono::duration<double>(duration_s);
    std::uint32_t beat = 0;
    while (!stop_requested && Clock::now() < end) {
        ++heartbeat.sequence;
        // KeelHeartbeat is typed: the beacon says what a node's heartbeat says.
        heartbeat.payload = keel::fsm::encode(keel::fsm::Heartbeat{options.address, options.epoch, 1, false,
                                                       ++beat, {}, false});
        transport.send(heartbeat);
        std::this_thread::sleep_for(std::chrono::milliseconds(options.period_ms));
    }
    return 0;
}

void dds_check(dds_return_t rc, const char* what) {
    if (rc < 0) throw dds::DdsError(std::string(what) + ": " + dds_strretcode(-rc));
}

// Serialized sizes of KeelData samples, measured by Cyclone itself: a writer and a reader in
// one participant, the sample taken back as serialized data.
int run_cdr_size(std::uint32_t domain_id, const std::string& interface_name) {
    dds::DdsConfig config = bench_config(ping_address, domain_id, interface_name);
    const std::string xml = dds::domain_config_xml(config);
    const dds_entity_t domain = dds_create_domain(domain_id, xml.c_str());
    dds_check(domain, "dds_create_domain");
    const dds_entity_t participant = dds_create_participant(domain_id, nullptr, nullptr);
    dds_check(participant, "dds_create_participant");
    const dds_entity_t topic =
        dds_create_topic(participant, &keel_wire_Message_desc, "KeelData", nullptr, nullptr);
    dds_check(topic, "dds_create_topic");
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    const dds_entity_t writer = dds_create_writer(participant, topic, qos, nullptr);
    dds_check(writer, "dds_create_writer");
    const dds_entity_t reader = dds_create_reader(participant, topic, qos, nullptr);
    dds_check(reader, "dds_create_reader");
    dds_delete_qos(qos);
    std::ostringstream json;
    json << "{\"topic\": \"KeelData\", \"samples\": [";
    bool first = true;
    for (std::uint32_t payload_bytes : {0u, 64u, 65536u}) {
        std::vector<std::uint8_t> payload(payload_bytes, 1);
        keel_wire_Message sample{};
        sample.source = 1;
        sample.destination = 2;
        sample.payload._buffer = payload.data();
        sample.payload._length = payload_bytes;
        sample.payload._maximum = payload_bytes;
        dds_check(dds_write(writer, &sample), "dds_write");
        struct ddsi_serdata* serdata = nullptr;
        dds_sample_info_t info{};
        dds_return_t taken = 0;
        for (int attempt = 0; attempt < 1000 && taken == 0; ++attempt) {
            taken = dds_takecdr(reader, &serdata, 1, &info, DDS_ANY_STATE);
            dds_check(taken, "dds_takecdr");
            if (taken == 0) std::this_thread::sleep_for(1ms);
        }
        if (taken != 1) throw dds::DdsError("sample did not come back");
        // Includes the 4-byte CDR encapsulation header that precedes every serialized payload.
        const std::uint32_t serialized = ddsi_serdata_size(serdata);
        ddsi_serdata_unref(serdata);
        if (!first) json << ", ";
        first = false;
        json << "{\"payload_bytes\": " << payload_bytes << ", \"serialized_bytes\": " << serialized
             << ", \"encapsulation_header_bytes\": 4, \"keel_fields_bytes\": "
             << (serialized - payload_bytes - 4) << "}";
    }
    json << "], \"codec_header_bytes\": " << header_size_bytes << "}";
    dds_check(dds_delete(domain), "dds_delete");
    std::cout << json.str() << std::endl;
    return 0;
}

// -- The bare libddsc floor (bare-pong, bare-ping) ----------------------------------------

struct Bare {
    dds_entity_t participant = 0;
    dds_entity_t writer = 0;
    dds_entity_t reader = 0;
    dds_entity_t waitset = 0;
    ~Bare() {
        if (participant > 0) dds_delete(participant);
    }
};

// The participant, writer and reader Keel's transport makes for reliable_data (dds_transport.cpp:
// make_qos, the sender partitions), without the rest of the transport.
void open_bare(Bare& bare, NodeAddress address, std::uint32_t domain_id,
               const std::string& interface_name, bool keep_last) {
    const dds::DdsConfig config = bench_config(address, domain_id, interface_name);
    const std::string xml = dds::domain_config_xml(config);
    dds_check(dds_create_domain(domain_id, xml.c_str()), "dds_create_domain");
    dds_qos_t* participant_qos =
        config.security.enabled() ? dds::new_security_qos(config.security) : nullptr;
    bare.participant = dds_create_participant(domain_id, participant_qos, nullptr);
    if (participant_qos) dds_delete_qos(participant_qos);
    dds_check(bare.participant, "dds_create_participant");
    const dds_entity_t topic = dds_create_topic(bare.participant, &keel_wire_Message_desc,
                                                topic_for(MessageKind::reliable_data), nullptr, nullptr);
    dds_check(topic, "dds_create_topic");
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(config.max_blocking_time.count()));
    dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
    if (keep_last) {
        dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
    } else {
        dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
        dds_qset_resource_limits(qos, config.reliable_max_samples, DDS_LENGTH_UNLIMITED,
                                 config.reliable_max_samples);
    }
    dds_qset_ownership(qos, DDS_OWNERSHIP_SHARED);
    dds_qset_destination_order(qos, DDS_DESTINATIONORDER_BY_RECEPTION_TIMESTAMP);
    dds_qset_ignorelocal(qos, DDS_IGNORELOCAL_PARTICIPANT);
    const std::string own = dds::sender_partition(address);
    const std::string any = own.substr(0, own.find_last_of('.') + 1) + "*";  // keel.from.*
    auto in_partition = [&](const std::string& name, bool publisher) {
        dds_qos_t* partition_qos = dds_create_qos();
        const char* names[] = {name.c_str()};
        dds_qset_partition(partition_qos, 1, names);
        const dds_entity_t entity =
            publisher ? dds_create_publisher(bare.participant, partition_qos, nullptr)
                      : dds_create_subscriber(bare.participant, partition_qos, nullptr);
        dds_delete_qos(partition_qos);
        dds_check(entity, publisher ? "dds_create_publisher" : "dds_create_subscriber");
        return entity;
    };
    bare.writer = dds_create_writer(in_partition(own, true), topic, qos, nullptr);
    dds_check(bare.writer, "dds_create_writer");
    bare.reader = dds_create_reader(in_partition(any, false), topic, qos, nullptr);
    dds_check(bare.reader, "dds_create_reader");
    dds_delete_qos(qos);
    bare.waitset = dds_create_waitset(bare.participant);
    dds_check(bare.waitset, "dds_create_waitset");
    const dds_entity_t condition = dds_create_readcondition(bare.reader, DDS_ANY_STATE);
    dds_check(condition, "dds_create_readcondition");
    dds_check(dds_waitset_attach(bare.waitset, condition, bare.reader), "dds_waitset_attach");
}

int run_bare_pong(std::uint32_t domain_id, const std::string& interface_name, double duration_s,
                  bool keep_last) {
    Bare bare;
    open_bare(bare, pong_address, domain_id, interface_name, keep_last);
    const auto end = Clock::now() + std::chrono::duration<double>(duration_s);
    std::uint64_t echoed = 0;
    while (!stop_requested && Clock::now() < end) {
        dds_check(dds_waitset_wait(bare.waitset, nullptr, 0, DDS_MSECS(100)), "dds_waitset_wait");
        void* sample = nullptr;
        dds_sample_info_t info{};
        while (dds_take(bare.reader, &sample, &info, 1, 1) == 1) {
            if (info.valid_data) {
                auto* message = static_cast<keel_wire_Message*>(sample);
                message->destination = message->source;
                message->source = pong_address;
                if (dds_write(bare.writer, message) >= 0) ++echoed;
            }
            dds_return_loan(bare.reader, &sample, 1);
            sample = nullptr;
        }
    }
    std::fprintf(stderr, "bare-pong: echoed %llu\n", static_cast<unsigned long long>(echoed));
    return 0;
}

// One round trip of `payload`: false if no echo came back by `give_up`.
bool bare_round(Bare& bare, keel_wire_Message& sample, Clock::time_point give_up) {
    dds_check(dds_write(bare.writer, &sample), "dds_write");
    while (Clock::now() < give_up) {
        const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(give_up - Clock::now());
        dds_check(dds_waitset_wait(bare.waitset, nullptr, 0, left.count()), "dds_waitset_wait");
        ddsi_serdata* serdata = nullptr;
        dds_sample_info_t info{};
        // The echo's payload is not deserialised: as keel-net-bench ping, only its size and
        // sequence number are looked at, from the serialized sample.
        while (dds_takecdr(bare.reader, &serdata, 1, &info, DDS_ANY_STATE) == 1) {
            const bool valid = info.valid_data;
            const std::uint32_t size = ddsi_serdata_size(serdata);
            ddsi_serdata_unref(serdata);
            if (valid && size >= sample.payload._length) return true;
        }
    }
    return false;
}

int run_bare_ping(std::uint32_t domain_id, const std::string& interface_name,
                  const std::string& sizes_text, std::size_t rounds, bool keep_last) {
    Bare bare;
    open_bare(bare, ping_address, domain_id, interface_name, keep_last);
    std::vector<std::uint8_t> probe_bytes(8, 1);
    keel_wire_Message sample{};
    sample.source = ping_address;
    sample.destination = pong_address;
    sample.port = echo_port;
    // Probe until an echo comes back (discovery, and with DDS Security both handshakes).
    sample.payload = {static_cast<std::uint32_t>(probe_bytes.size()),
                      static_cast<std::uint32_t>(probe_bytes.size()), probe_bytes.data(), false};
    bool ready = false;
    for (int attempt = 0; attempt < 300 && !ready && !stop_requested; ++attempt) {
        ready = bare_round(bare, sample, Clock::now() + 100ms);
    }
    if (!ready) {
        std::cerr << "bare-ping: no bare-pong echoed in domain " << domain_id << "\n";
        return 1;
    }
    std::ostringstream json;
    json << "{\"floor\": \"bare libddsc\", \"history\": \""
         << (keep_last ? "keep-last 1" : "keep-all") << "\", \"latency\": [";
    std::size_t timeouts = 0;
    bool first = true;
    for (std::size_t size : parse_sizes(sizes_text)) {
        std::vector<std::uint8_t> payload(size);
        for (std::size_t i = 0; i < size; ++i) payload[i] = static_cast<std::uint8_t>(i);
        sample.payload = {static_cast<std::uint32_t>(size), static_cast<std::uint32_t>(size),
                          payload.data(), false};
        std::vector<double> rtt_us;
        const std::size_t warmup = std::max<std::size_t>(rounds / 20, 10);
        for (std::size_t round = 0; round < warmup + rounds; ++round) {
            ++sample.sequence_number;
            const auto start = Clock::now();
            if (!bare_round(bare, sample, start + 2s)) {
                ++timeouts;
                continue;
            }
            const auto stop = Clock::now();
            if (round >= warmup) {
                rtt_us.push_back(std::chrono::duration<double, std::micro>(stop - start).count());
            }
        }
        if (!first) json << ", ";
        first = false;
        json << "{\"payload_bytes\": " << size << ", \"rounds\": " << rtt_us.size()
             << ", \"rtt_us\": {\"p50\": " << number(percentile(rtt_us, 0.50))
             << ", \"p99\": " << number(percentile(rtt_us, 0.99)) << "}, \"one_way_us\": {\"p50\": "
             << number(percentile(rtt_us, 0.50) / 2) << ", \"p99\": "
             << number(percentile(rtt_us, 0.99) / 2) << "}}";
    }
    json << "], \"timeouts\": " << timeouts << "}";
    std::cout << json.str() << std::endl;
    if (timeouts > 0) {
        std::cerr << "bare-ping: " << timeouts << " round trips got no echo\n";
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Keel network layer benchmark (Cyclone DDS on loopback)"};
    app.require_subcommand(1);
    std::uint32_t domain_id = 42;
    std::string interface_name = "lo";
    double duration_s = 120;
    std::string sizes = "64,65536,16777216";
    std::size_t rounds_small = 2000;
    std::size_t rounds_large = 20;
    std::size_t wire_messages = 2000;

    auto* pong = app.add_subcommand("pong", "echo server (node 2)");
    pong->add_option("--domain", domain_id, "DDS domain id")->check(CLI::Range(0, 232));
    pong->add_option("--interface", interface_name, "network interface");
    pong->add_option("--duration", duration_s, "seconds before stopping");
    for (CLI::App* secured : {pong}) {
        secured->add_option("--security", security_dir,
                            "credentials directory (keel-cluster credentials): run secured");
        secured->add_option("--identity", identity, "node name in it, at address 2 (default PN3)");
    }
    auto* ping = app.add_subcommand("ping", "latency and wire-size measurement (node 1)");
    ping->add_option("--security", security_dir,
                     "credentials directory (keel-cluster credentials): run secured");
    ping->add_option("--identity", identity, "node name in it, at address 1 (default PN2)");
    ping->add_option("--domain", domain_id, "DDS domain id")->check(CLI::Range(0, 232));
    ping->add_option("--interface", interface_name, "network interface");
    ping->add_option("--sizes", sizes, "payload sizes in bytes, comma-separated");
    ping->add_option("--rounds-small", rounds_small, "round trips per size below 1 MiB");
    ping->add_option("--rounds-large", rounds_large, "round trips per size of 1 MiB or more");
    ping->add_option("--wire-messages", wire_messages, "messages per wire-size burst");
    std::string small_kind_name = "reliable_data";
    ping->add_option("--small-kind", small_kind_name, "message kind for payloads below 1 MiB")
        ->check(CLI::IsMember({"unreliable_data", "reliable_data", "request", "response",
                               "error_notification"}));  // the typed topics carry messages only
    auto* cdr = app.add_subcommand("cdr-size", "serialized size of KeelData samples");
    cdr->add_option("--domain", domain_id, "DDS domain id")->check(CLI::Range(0, 232));
    BeaconOptions beacon_options;
    auto* beacon = app.add_subcommand("beacon", "publish a NodeState and heartbeats");
    beacon->add_option("--domain", domain_id, "DDS domain id")->check(CLI::Range(0, 232));
    beacon->add_option("--interface", interface_name, "network interface");
    beacon->add_option("--duration", duration_s, "seconds before stopping");
    beacon->add_option("--address", beacon_options.address, "node logical address")
        ->check(CLI::Range(0, 254));
    beacon->add_option("--name", beacon_options.name, "node name");
    beacon->add_option("--role", beacon_options.role, "role")
        ->check(CLI::IsMember({"master", "observer", "worker", "storage", "interface"}));
    beacon->add_option("--epoch", beacon_options.epoch, "epoch")->check(CLI::Range(0u, max_epoch));
    beacon->add_option("--configuration-id", beacon_options.configuration_id, "configuration id");
    beacon->add_option("--configuration", beacon_options.configuration, "configuration name");
    beacon->add_option("--phase", beacon_options.phase, "phase name");
    beacon->add_option("--period-ms", beacon_options.period_ms, "heartbeat period")
        ->check(CLI::Range(1u, 60000u));
    bool keep_last = false;
    auto* bare_pong = app.add_subcommand("bare-pong", "the bare libddsc floor: echo server");
    auto* bare_ping = app.add_subcommand("bare-ping", "the bare libddsc floor: round trips");
    for (CLI::App* bare : {bare_pong, bare_ping}) {
        bare->add_option("--domain", domain_id, "DDS domain id")->check(CLI::Range(0, 232));
        bare->add_option("--interface", interface_name, "network interface");
        bare->add_option("--security", security_dir,
                         "credentials directory (keel-cluster credentials): run secured");
        bare->add_option("--identity", identity, "node name in it (default PN2 ping, PN3 pong)");
        bare->add_flag("--keep-last", keep_last,
                       "reliable keep-last 1 (ddsperf's ping/pong) instead of Keel's keep-all");
    }
    bare_pong->add_option("--duration", duration_s, "seconds before stopping");
    bare_ping->add_option("--sizes", sizes, "payload sizes in bytes, comma-separated");
    bare_ping->add_option("--rounds", rounds_small, "round trips per size");
    auto* xml = app.add_subcommand("config-xml", "print the DDS configuration Keel uses");
    xml->add_option("--interface", interface_name, "network interface");
    std::vector<std::string> peers;
    xml->add_option("--peer", peers, "peer address (repeatable; default 127.0.0.1)");
    CLI11_PARSE(app, argc, argv);

    std::signal(SIGTERM, on_signal);
    std::signal(SIGINT, on_signal);
    try {
        if (*pong) return run_pong(domain_id, interface_name, duration_s);
        if (*ping) {
            for (MessageKind kind : all_message_kinds) {
                if (to_string(kind) == small_kind_name) small_kind = kind;
            }
            return run_ping(domain_id, interface_name, sizes, rounds_small, rounds_large,
                            wire_messages);
        }
        if (*bare_pong) return run_bare_pong(domain_id, interface_name, duration_s, keep_last);
        if (*bare_ping) {
            return run_bare_ping(domain_id, interface_name, sizes == "64,65536,16777216" ? "64,65536" : sizes,
                                 rounds_small, keep_last);
        }
        if (*cdr) return run_cdr_size(domain_id, interface_name);
        if (*beacon) return run_beacon(domain_id, interface_name, duration_s, beacon_options);
        if (*xml) {
            dds::DdsConfig config = bench_config(ping_address, 0, interface_name);
            if (!peers.empty()) config.peers = peers;
            std::cout << dds::domain_config_xml(config) << std::endl;
            return 0;
        }
    } catch (const std::exception& error) {
        std::cerr << "keel-net-bench: " << error.what() << "\n";
        return 2;
    }
    return 1;
}
