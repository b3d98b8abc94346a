#include "core/net/dds/dds_transport.hpp"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <unordered_map>
#include <mutex>
#include <optional>
#include <thread>

#include "core/fsm/types.hpp"
#include "core/net/bytes.hpp"
#include "core/net/dds/security_qos.hpp"
#include "core/net/dds/typed_wire.hpp"
#include "keel.h"

namespace keel::net::dds {

namespace {

// The C types generated from keel.idl share one layout for the header fields; the code
// below relies on it to handle keyed and unkeyed topics with one template.
static_assert(offsetof(keel_wire_Message, payload) == offsetof(keel_wire_SourcedMessage, payload));
static_assert(sizeof(keel_wire_Message) == sizeof(keel_wire_SourcedMessage));
static_assert(static_cast<int>(keel_wire_ROLE_INTERFACE) == static_cast<int>(Role::interface));
static_assert(static_cast<int>(keel_wire_ROLE_MASTER) == static_cast<int>(Role::master));
static_assert(static_cast<int>(keel_wire_ROLE_RESIGNED) == static_cast<int>(Role::resigned));

constexpr std::size_t kind_count = std::size(all_message_kinds);
// A serialized keel::wire::Message before its payload: the 4-byte CDR encapsulation, then
// source 2, destination 2, port 2, padding 2, epoch 4, sequence_number 4, payload length 4.
constexpr std::size_t sample_header_bytes = 4 + 20;
// Cyclone's MaxSampleSize: the largest payload plus the header, CDR's trailing padding and
// DDS Security's payload protection (a crypto header and footer, about 44 bytes, which a
// receiver may count in the sample's size).
constexpr std::size_t sample_overhead_bytes = 128;
static_assert(sample_header_bytes + 3 <= sample_overhead_bytes);
constexpr std::size_t take_batch = 64;

using Clock = std::chrono::steady_clock;

std::size_t kind_index(MessageKind kind) { return static_cast<std::size_t>(kind) - 1; }

// Every dds_* call that can fail goes through here: errors become DdsError with DDS's text.
dds_return_t check(dds_return_t rc, const char* what) {
    if (rc < 0) {
        throw DdsError(std::string(what) + " failed: " + dds_strretcode(-rc));
    }
    return rc;
}

bool plain_token(const std::string& text) {
    return !text.empty() && text.find_first_of("<>&\"' ") == std::string::npos;
}

// Participants of one process share the domain entity of their domain id: Cyclone allows
// one per id per process. Counted so the last transport deletes it.
struct DomainRegistry {
    struct Entry {
        dds_entity_t domain;
        int users;
        std::string xml;
    };
    std::mutex mutex;
    std::map<std::uint32_t, Entry> domains;

    static DomainRegistry& instance() {
        static DomainRegistry registry;
        return registry;
    }
    void acquire(std::uint32_t domain_id, const std::string& xml) {
        std::lock_guard lock(mutex);
        auto found = domains.find(domain_id);
        if (found != domains.end()) {
            // The domain exists with its configuration; a different one would be ignored.
            if (found->second.xml != xml) {
                throw std::invalid_argument("DDS domain " + std::to_string(domain_id) +
                                            " is already configured differently in this process");
            }
            ++found->second.users;
            return;
        }
        const dds_entity_t domain = check(dds_create_domain(domain_id, xml.c_str()),
                                          "dds_create_domain");
        domains.emplace(domain_id, Entry{domain, 1, xml});
    }
    void release(std::uint32_t domain_id) {
        std::lock_guard lock(mutex);
        auto found = domains.find(domain_id);
        if (found == domains.end()) return;
        if (--found->second.users == 0) {
            dds_return_t rc = dds_delete(found->second.domain);
            if (rc < 0) spdlog::warn("dds_delete(domain) failed: {}", dds_strretcode(-rc));
            domains.erase(found);
        }
    }
};

struct QosDeleter {
    void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

// The QoS of every Keel topic is built here and nowhere else. Readers and writers of a
// topic get the same policies, except the deadline, which the writer offers at the
// heartbeat period and the reader requests at period x miss limit (a node is suspect
// only after the same number of silent periods the heartbeat protocol tolerates).
QosPtr make_qos(bool reliable, bool transient_local, std::int32_t history_depth,
                std::int32_t max_samples, dds_duration_t deadline, dds_duration_t max_blocking) {
    QosPtr qos(dds_create_qos());
    if (!qos) throw DdsError("dds_create_qos returned nothing");
    if (reliable) {
        dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, max_blocking);
    } else {
        dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
    }
    dds_qset_durability(qos.get(),
                        transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
    if (history_depth > 0) {
        dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, history_depth);
    } else {
        dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
        dds_qset_resource_limits(qos.get(), max_samples, DDS_LENGTH_UNLIMITED, max_samples);
    }
    if (deadline > 0) dds_qset_deadline(qos.get(), deadline);
    // No liveliness QoS (DDS's default: automatic, infinite lease): Keel's own heartbeats
    // say whether a node lives, and nothing read DDS's verdict on them. An automatic lease
    // made every participant announce its writers' liveliness to every other participant
    // once within each lease (a reliable ParticipantMessageData and its acknowledgements): a
    // fifth of a 16-node cluster's CPU at rest. A writer's liveliness is its
    // participant's, which DDS drops after participant_lease_ms() without announcements.
    // Shared ownership everywhere: a second master must be heard (its epoch decides), not
    // hidden by exclusive ownership.
    dds_qset_ownership(qos.get(), DDS_OWNERSHIP_SHARED);
    dds_qset_destination_order(qos.get(), DDS_DESTINATIONORDER_BY_RECEPTION_TIMESTAMP);
    // A node does not receive its own messages; broadcasts reach the other nodes.
    dds_qset_ignorelocal(qos.get(), DDS_IGNORELOCAL_PARTICIPANT);
    return qos;
}

// A publisher or subscriber in the given partitions.
dds_entity_t create_in_partitions(dds_entity_t participant, bool publisher,
                                  const std::vector<std::string>& names) {
    QosPtr qos(dds_create_qos());
    if (!qos) throw DdsError("dds_create_qos returned nothing");
    std::vector<const char*> pointers;
    for (const std::string& name : names) pointers.push_back(name.c_str());
    dds_qset_partition(qos.get(), static_cast<uint32_t>(pointers.size()), pointers.data());
    return publisher ? check(dds_create_publisher(participant, qos.get(), nullptr), "dds_create_publisher")
                     : check(dds_create_subscriber(participant, qos.get(), nullptr), "dds_create_subscriber");
}

constexpr std::string_view sender_prefix = "keel.from.";

// The node a publication speaks for: the one sender partition among its partitions.
std::optional<NodeAddress> sender_of_partitions(const dds_qos_t* qos) {
    uint32_t count = 0;
    char** names = nullptr;
    if (qos == nullptr || !dds_qget_partition(qos, &count, &names)) return std::nullopt;
    std::optional<NodeAddress> sender;
    int found = 0;
    for (uint32_t i = 0; i < count; ++i) {
        const std::string_view name(names[i]);
        if (name.substr(0, sender_prefix.size()) != sender_prefix) continue;
        const std::string_view digits = name.substr(sender_prefix.size());
        unsigned value = 0;
        bool ok = !digits.empty() && digits.size() <= 5;  // 65535 at most: a NodeAddress
        for (char c : digits) {
            ok = ok && c >= '0' && c <= '9';
            value = value * 10 + static_cast<unsigned>(c - '0');
        }
        if (ok && value < broadcast_address) {
            sender = static_cast<NodeAddress>(value);
            ++found;
        } else {
            found = 2;  // a malformed sender partition: speaks for no one
        }
    }
    for (uint32_t i = 0; i < count; ++i) dds_free(names[i]);
    dds_free(names);
    if (found != 1) return std::nullopt;  // none, or two: a writer speaks for one node
    return sender;
}

std::string guid_text(const dds_guid_t& guid) {
    static const char* digits = "0123456789abcdef";
    std::string text;
    for (std::size_t i = 0; i < sizeof(guid.v); ++i) {
        text += digits[guid.v[i] >> 4];
        text += digits[guid.v[i] & 15];
        if (i == 3 || i == 7 || i == 11) text += ':';
    }
    return text;
}

template <class Sample>
void fill_sample(Sample& sample, const Envelope& envelope) {
    typed::fill_header(sample, envelope);
    // The payload is borrowed for the duration of dds_write (which serialises it).
    sample.payload._buffer = const_cast<std::uint8_t*>(envelope.payload.data());
    sample.payload._length = static_cast<std::uint32_t>(envelope.payload.size());
    sample.payload._maximum = sample.payload._length;
    sample.payload._release = false;
}

}  // namespace

// Reads the serialized sample straight into an Envelope (one copy of the payload) instead
// of letting Cyclone deserialise it into a DDS sample and copying out of that.
Inbound parse_serialized_message(std::span<const std::uint8_t> serialized, MessageKind kind,
                                 const EnvelopeLimits& limits, const char* topic_name) {
    if (serialized.size() < sample_header_bytes) {
        return Inbound::rejected(EnvelopeError::truncated,
                                 "serialized sample of " + std::to_string(serialized.size()) +
                                     " bytes is shorter than its header",
                                 topic_name);
    }
    // The encapsulation identifier: plain CDR or XCDR2, big- (even) or little-endian (odd).
    const std::uint8_t identifier = serialized[1];
    if (serialized[0] != 0 || (identifier != 0 && identifier != 1 && identifier != 6 &&
                               identifier != 7)) {
        return Inbound::rejected(EnvelopeError::bad_version,
                                 "unexpected CDR encapsulation " + std::to_string(serialized[0]) +
                                     "/" + std::to_string(identifier),
                                 topic_name);
    }
    ByteReader reader(serialized.subspan(4),
                      (identifier & 1) != 0 ? ByteOrder::little : ByteOrder::big);
    Envelope envelope;
    envelope.kind = kind;
    envelope.source = reader.u16("source");
    envelope.destination = reader.u16("destination");
    envelope.port = reader.u16("port");
    reader.raw(2, "padding");  // CDR aligns the epoch on four bytes
    envelope.epoch = reader.u32("epoch");
    envelope.sequence = reader.u32("sequence_number");
    const std::uint32_t payload_bytes = reader.u32("payload length");
    // The fields are all there (checked above): the reader cannot have failed.
    if (payload_bytes > limits.max_payload_bytes) {
        return Inbound::rejected(EnvelopeError::oversized,
                                 "payload of " + std::to_string(payload_bytes) +
                                     " bytes from node " + std::to_string(envelope.source) +
                                     " exceeds the maximum of " +
                                     std::to_string(limits.max_payload_bytes),
                                 topic_name);
    }
    if (payload_bytes > reader.remaining()) {
        return Inbound::rejected(EnvelopeError::truncated,
                                 "payload of " + std::to_string(payload_bytes) + " bytes but " +
                                     std::to_string(reader.remaining()) + " present",
                                 topic_name);
    }
    // Up to 3 bytes of CDR padding may follow the payload; they are not part of it.
    const auto payload = reader.raw(payload_bytes, "payload");
    envelope.payload.assign(payload.begin(), payload.end());
    return Inbound::accepted(std::move(envelope), topic_name);
}

SecurityFiles security_files_in(const std::string& dir, const std::string& node_name) {
    const std::filesystem::path root = std::filesystem::absolute(dir);
    const std::filesystem::path node = root / "nodes" / node_name;
    SecurityFiles files;
    files.identity_ca = (root / "ca.pem").string();
    files.permissions_ca = files.identity_ca;
    files.governance = (root / "governance.p7s").string();
    files.identity_certificate = (node / "cert.pem").string();
    files.private_key = (node / "key.pem").string();
    files.permissions = (node / "permissions.p7s").string();
    std::error_code ignored;
    if (std::filesystem::exists(root / "crl.pem", ignored)) files.crl = (root / "crl.pem").string();
    return files;
}

std::int32_t command_history_for(int nodes) {
    const std::int64_t burst = 2 * static_cast<std::int64_t>(std::max(nodes, 0));
    return static_cast<std::int32_t>(std::clamp<std::int64_t>(burst, 8, max_command_history));
}

std::uint32_t participant_indices_for(int nodes) {
    const auto wanted = static_cast<std::uint32_t>(std::max(0, nodes)) + 16;
    return std::clamp<std::uint32_t>(wanted, 30, max_participant_indices);
}

std::string sender_partition(NodeAddress node) {
    return std::string(sender_prefix) + std::to_string(node);
}

std::string domain_config_xml(const DdsConfig& config) {
    if (!plain_token(config.network_interface)) {
        throw std::invalid_argument("network interface name must be a plain word");
    }
    if (config.peers.empty()) throw std::invalid_argument("DDS needs at least one peer address");
    std::string peers;
    for (const std::string& peer : config.peers) {
        if (!plain_token(peer)) throw std::invalid_argument("peer address must be a plain word");
        peers += "<Peer address=\"" + peer + "\"/>";
    }
    // Fragments of 62000 bytes in datagrams of up to 65500: loopback and veth carry them
    // without IP fragmentation (MTU 65536 on lo), which keeps 16 MB messages to ~270
    // datagrams. Socket buffers are raised up to 4 MB where the kernel allows.
    return "<CycloneDDS><Domain Id=\"any\">"
           "<General><Interfaces><NetworkInterface name=\"" +
           config.network_interface +
           "\"/></Interfaces>"
           "<AllowMulticast>false</AllowMulticast>"
           "<MaxMessageSize>65500B</MaxMessageSize><FragmentSize>62000B</FragmentSize>"
           "</General>"
           "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
           "<MaxAutoParticipantIndex>" +
           std::to_string(config.max_auto_participant_index) +
           "</MaxAutoParticipantIndex>"
           "<Peers>" +
           peers +
           "</Peers>"
           // A reliable writer waits for the acknowledgements of a dead participant's readers
           // (keep-all history, bounded) until DDS forgets the participant: that must happen
           // soon after Keel declares the node failed, not after the default 10 s lease. The
           // lease is renewed by participant announcements, so they come four times a lease.
           "<SPDPInterval>" +
           std::to_string(participant_lease_ms(config) / 4) +
           "ms</SPDPInterval><LeaseDuration>" +
           std::to_string(participant_lease_ms(config)) +
           "ms</LeaseDuration></Discovery>"
           // Larger samples are dropped before reassembly: no peer makes a node hold more.
           "<Internal><MaxSampleSize>" +
           std::to_string(config.max_sample_bytes != 0
                              ? config.max_sample_bytes
                              : max_sample_bytes_for(default_max_payload_bytes)) +
           "B</MaxSampleSize>"
           "<SocketReceiveBufferSize min=\"default\" max=\"4MB\"/>"
           "<SocketSendBufferSize min=\"default\" max=\"4MB\"/></Internal>"
           "</Domain></CycloneDDS>";
}

std::int64_t participant_lease_ms(const DdsConfig& config) {
    const std::int64_t heartbeat_lease_ms =
        config.heartbeat_period.count() * static_cast<std::int64_t>(config.heartbeat_miss_limit);
    return std::max<std::int64_t>(1000, 3 * heartbeat_lease_ms);
}

std::uint32_t data_domain_for(std::uint32_t domain) { return (domain + 116) % 231; }

std::size_t max_sample_bytes_for(std::size_t max_payload_bytes) {
    return max_payload_bytes + sample_overhead_bytes;
}

std::uint32_t domain_id_for(std::string_view name) {
    const std::size_t hash = std::hash<std::string_view>{}(name) ^
                             (static_cast<std::size_t>(::getpid()) * 0x9E3779B97F4A7C15ull);
    return 1 + static_cast<std::uint32_t>(hash % 150);
}

const std::vector<TopicQos>& topic_table() {
    // kind, topic, keyed, reliable, transient-local, depth (0 = keep-all), deadline
    static const std::vector<TopicQos> table = {
        {MessageKind::unreliable_data, "KeelData", false, false, false, 64, false},
        {MessageKind::reliable_data, "KeelReliableData", false, true, false, 0, false},
        {MessageKind::request, "KeelRequest", false, true, false, 0, false},
        {MessageKind::response, "KeelResponse", false, true, false, 0, false},
        // KeelCommand's depth is DdsConfig::command_history_depth (8 unless a mission sets it).
        {MessageKind::reconfiguration_command, "KeelCommand", true, true, true, 8, false},
        {MessageKind::acknowledgement, "KeelAck", false, true, false, 0, false},
        {MessageKind::heartbeat, "KeelHeartbeat", true, false, false, 1, true},
        {MessageKind::error_notification, "KeelError", false, true, false, 0, false},
        {MessageKind::large, "KeelLarge", false, true, false, 0, false},
    };
    return table;
}

std::string addressed_partition(NodeAddress node) {
    return node == broadcast_address ? std::string("keel.broadcast")
                                     : "keel.node." + std::to_string(node);
}

struct DdsTransport::Impl {
    DdsConfig config;
    dds_entity_t participant = 0;
    dds_entity_t waitset = 0;
    dds_entity_t wake_condition = 0;  // guard condition on the waitset, set by wake()
    std::array<dds_entity_t, kind_count> writers{};  // 0: not carried, or addressed
    // The readers of each kind (none: not carried): one, or one per sender for the keyed
    // kinds when DdsConfig::keyed_senders names them; taken in turn from a rotating start.
    std::array<std::vector<dds_entity_t>, kind_count> readers{};
    std::array<std::size_t, kind_count> reader_turn{};
    std::array<const TopicQos*, kind_count> rows{};
    // Addressed kinds: the topic and writer QoS to create writers with, and the writer of
    // each destination's partition (a publisher per destination, shared by the kinds).
    std::array<bool, kind_count> addressed{};
    std::array<dds_entity_t, kind_count> topics{};
    std::array<QosPtr, kind_count> writer_qos{};
    std::array<std::map<NodeAddress, dds_entity_t>, kind_count> addressed_writers{};
    std::map<NodeAddress, dds_entity_t> publishers;
    dds_entity_t tool_publisher = 0;  // also the default partition: the typed topics' writers
    dds_entity_t own_publisher = 0;   // partition sender_partition(address): every writer's
    dds_entity_t sender_subscriber = 0;  // partition "keel.from.*": non-addressed readers
    // For the keyed kinds' readers of one sender each: a subscriber in its sender partition.
    std::map<NodeAddress, dds_entity_t> one_sender_subscribers;
    dds_entity_t addressed_writer(std::size_t index, NodeAddress destination);
    // What is known of each publication samples came from: the node it speaks for (its
    // sender partition), its participant, and the last sequence number taken from it.
    struct Publication {
        std::optional<NodeAddress> sender;
        dds_guid_t participant{};
        bool known = false;  // DDS still had the publication when it was first seen
        bool any = false;    // a sequence number was taken
        Sequence last = 0;
    };
    std::unordered_map<dds_instance_handle_t, Publication> publications;
    // Without DDS Security nothing stops another participant from publishing in a node's
    // sender partition: a node is bound to the first participant that spoke for it, and
    // another one is refused while that one is still matched.
    struct Binding {
        dds_guid_t participant{};
        dds_entity_t reader = 0;
        dds_instance_handle_t publication = 0;
    };
    std::map<NodeAddress, Binding> bindings;
    Publication& publication(dds_entity_t reader, dds_instance_handle_t handle);
    std::optional<std::string> judge_sender(dds_entity_t reader, dds_instance_handle_t handle,
                                            const Envelope& envelope, bool& replayed);
    dds_entity_t state_writer = 0;
    dds_entity_t state_reader = 0;
    std::size_t next_reader = 0;  // round-robin start, so no topic starves the others
    std::atomic<std::uint64_t> sent{0};
    std::atomic<std::uint64_t> send_failed{0};
    std::atomic<std::uint64_t> received{0};
    std::atomic<std::uint64_t> received_bytes{0};  // serialized bytes taken from the readers
    bool domain_acquired = false;
    std::mutex state_mutex;
    std::optional<NodeState> last_state;
    Clock::time_point last_state_write{};

    void write_state(const NodeState& state);

    // The sample of a typed topic being written (write() runs on the loop thread only).
    typed::Outgoing outgoing;

    SendResult write(const Envelope& envelope, std::span<const NodeAddress> destinations = {});
    void take_from(std::size_t index, std::vector<Inbound>& out, std::size_t max_items,
                   std::size_t& taken);
    void take_typed(std::size_t index, dds_entity_t reader, std::vector<Inbound>& out,
                    std::size_t max_items, std::size_t& taken);
    void take_bytes(std::size_t index, dds_entity_t reader, std::vector<Inbound>& out,
                    std::size_t max_items, std::size_t& taken);
};

DdsTransport::DdsTransport(DdsConfig config) : impl_(std::make_unique<Impl>()) {
    Impl& impl = *impl_;
    impl.config = std::move(config);
    const DdsConfig& cfg = impl.config;
    if (cfg.address == broadcast_address) {
        throw std::invalid_argument("a node cannot have the broadcast address");
    }
    if (cfg.domain_id > 232) throw std::invalid_argument("DDS domain ids above 232 have no ports");
    const std::string xml = domain_config_xml(cfg);
    try {
        DomainRegistry::instance().acquire(cfg.domain_id, xml);
        impl.domain_acquired = true;
        QosPtr participant_qos;
        if (cfg.security.enabled()) participant_qos.reset(new_security_qos(cfg.security));
        impl.participant = dds_create_participant(cfg.domain_id, participant_qos.get(), nullptr);
        if (impl.participant < 0) {
            const std::string reason = dds_strretcode(-impl.participant);
            impl.participant = 0;
            throw DdsError(cfg.security.enabled()
                               ? "DDS refused the secured participant (" + reason +
                                     "): its certificate, key, governance or permissions were "
                                     "not accepted (Cyclone's log says which)"
                               : "dds_create_participant failed: " + reason);
        }
        impl.own_publisher = create_in_partitions(impl.participant, true,
                                                  {sender_partition(cfg.address)});
        impl.sender_subscriber = create_in_partitions(impl.participant, false,
                                                      {std::string(sender_prefix) + "*"});
        impl.waitset = check(dds_create_waitset(impl.participant), "dds_create_waitset");
        impl.wake_condition =
            check(dds_create_guardcondition(impl.participant), "dds_create_guardcondition");
        check(dds_waitset_attach(impl.waitset, impl.wake_condition, impl.wake_condition),
              "dds_waitset_attach(guard condition)");

        const dds_duration_t period = DDS_MSECS(cfg.heartbeat_period.count());
        const dds_duration_t lease = period * static_cast<dds_duration_t>(cfg.heartbeat_miss_limit);  // deadline
        const dds_duration_t blocking = DDS_MSECS(cfg.max_blocking_time.count());
        auto listed = [](const std::vector<MessageKind>& kinds, MessageKind kind) {
            return std::find(kinds.begin(), kinds.end(), kind) != kinds.end();
        };
        for (MessageKind kind : cfg.addressed_kinds) {
            if (!is_valid_kind(static_cast<std::uint8_t>(kind)) ||
                (!cfg.kinds.empty() && !listed(cfg.kinds, kind))) {
                throw std::invalid_argument("addressed message kind " +
                                            std::to_string(static_cast<int>(kind)) +
                                            " is not one this participant carries");
            }
            if (kind == MessageKind::heartbeat || kind == MessageKind::reconfiguration_command) {
                // Keyed by sender, transient-local or with deadlines: one topic for everyone.
                throw std::invalid_argument("heartbeats and commands cannot be addressed");
            }
        }
        // Readers of addressed kinds see their own node's partition and the broadcast one.
        dds_entity_t addressed_subscriber = 0;
        if (!cfg.addressed_kinds.empty()) {
            addressed_subscriber = create_in_partitions(
                impl.participant, false,
                {addressed_partition(cfg.address), addressed_partition(broadcast_address)});
        }
        for (const TopicQos& row : topic_table()) {
            const std::size_t index = kind_index(row.kind);
            impl.rows[index] = &row;
            if (!cfg.kinds.empty() && !listed(cfg.kinds, row.kind)) continue;
            impl.addressed[index] = listed(cfg.addressed_kinds, row.kind);
            const std::int32_t max_samples =
                row.kind == MessageKind::large ? cfg.large_max_samples : cfg.reliable_max_samples;
            const std::int32_t depth = row.kind == MessageKind::reconfiguration_command
                                           ? std::max(1, cfg.command_history_depth)
                                           : row.history_depth;
            QosPtr writer_qos =
                make_qos(row.reliable, row.transient_local, depth, max_samples,
                         row.deadline_is_heartbeat_period ? period : 0, blocking);
            // An observer's readers are best-effort and ask for no deadline or liveliness:
            // they match every node's writers whatever the mission's period (a reader that
            // asks for a shorter lease than a writer offers never matches it), and a reliable
            // writer never waits for an observer that reads slowly.
            QosPtr reader_qos =
                cfg.read_only
                    ? make_qos(false, row.transient_local, depth, max_samples, 0, blocking)
                    : make_qos(row.reliable, row.transient_local, depth, max_samples,
                               row.deadline_is_heartbeat_period ? lease : 0, blocking);
            // The protocol's own topics are typed (typed_wire.hpp); the rest carry envelopes
            // of bytes.
            const dds_topic_descriptor_t* descriptor = typed::descriptor(row.kind);
            if (descriptor == nullptr) {
                descriptor = row.keyed_by_source ? &keel_wire_SourcedMessage_desc
                                                 : &keel_wire_Message_desc;
            }
            const dds_entity_t topic =
                check(dds_create_topic(impl.participant, descriptor, row.topic_name, nullptr,
                                       nullptr),
                      "dds_create_topic");
            impl.topics[index] = topic;
            if (impl.addressed[index]) {
                impl.writer_qos[index] = std::move(writer_qos);
                for (NodeAddress destination : cfg.addressed_destinations) {
                    if (destination != cfg.address) impl.addressed_writer(index, destination);
                }
            } else if (!cfg.read_only && !listed(cfg.receive_only_kinds, row.kind)) {
                // The typed topics are for tools too: also in the default partition, where a
                // DDS tool's reader is unless told otherwise (as KeelNodeState).
                if (typed::is_typed(row.kind) && impl.tool_publisher == 0) {
                    impl.tool_publisher = create_in_partitions(
                        impl.participant, true, {sender_partition(cfg.address), std::string()});
                }
                impl.writers[index] = check(
                    dds_create_writer(typed::is_typed(row.kind) ? impl.tool_publisher
                                                                : impl.own_publisher,
                                      topic, writer_qos.get(), nullptr),
                    "dds_create_writer");
            }
            std::vector<dds_entity_t> subscribers;
            if (impl.addressed[index]) {
                subscribers.push_back(addressed_subscriber);
            } else if (row.keyed_by_source && !cfg.keyed_senders.empty()) {
                std::set<NodeAddress> senders(cfg.keyed_senders.begin(), cfg.keyed_senders.end());
                senders.erase(cfg.address);  // one reader per other node, named once or twice
                for (NodeAddress sender : senders) {
                    auto [at, added] = impl.one_sender_subscribers.try_emplace(sender, 0);
                    if (added) {  // one subscriber per sender, for every keyed kind
                        at->second = create_in_partitions(impl.participant, false,
                                                          {sender_partition(sender)});
                    }
                    subscribers.push_back(at->second);
                }
            } else {
                subscribers.push_back(impl.sender_subscriber);
            }
            for (const dds_entity_t subscriber : subscribers) {
                const dds_entity_t reader = check(
                    dds_create_reader(subscriber, topic, reader_qos.get(), nullptr),
                    "dds_create_reader");
                impl.readers[index].push_back(reader);
                const dds_entity_t condition = check(
                    dds_create_readcondition(reader, DDS_ANY_STATE), "dds_create_readcondition");
                check(dds_waitset_attach(impl.waitset, condition, reader), "dds_waitset_attach");
            }
        }
        // The node's own state is worth reading back (node_states() lists the whole
        // cluster), so KeelNodeState does not ignore the local participant.
        QosPtr state_qos = make_qos(true, true, 1, 0, 0, blocking);
        dds_qset_ignorelocal(state_qos.get(), DDS_IGNORELOCAL_NONE);
        const dds_entity_t state_topic =
            check(dds_create_topic(impl.participant, &keel_wire_NodeState_desc,
                                   node_state_topic_name, nullptr, nullptr),
                  "dds_create_topic(KeelNodeState)");
        // The node's state is for tools too: its writer is also in the default partition,
        // where a DDS tool's reader is unless told otherwise. (Nothing in Keel decides on it.)
        if (!cfg.read_only) {
            const dds_entity_t state_publisher = create_in_partitions(
                impl.participant, true, {sender_partition(cfg.address), std::string()});
            impl.state_writer =
                check(dds_create_writer(state_publisher, state_topic, state_qos.get(), nullptr),
                      "dds_create_writer(KeelNodeState)");
        }
        QosPtr observer_state_qos = make_qos(false, true, 1, 0, 0, blocking);
        dds_qset_ignorelocal(observer_state_qos.get(), DDS_IGNORELOCAL_NONE);
        impl.state_reader = check(dds_create_reader(impl.sender_subscriber, state_topic,
                                                    cfg.read_only ? observer_state_qos.get() : state_qos.get(),
                                                    nullptr),
                                  "dds_create_reader(KeelNodeState)");
    } catch (...) {
        if (impl.participant > 0) dds_delete(impl.participant);
        if (impl.domain_acquired) DomainRegistry::instance().release(cfg.domain_id);
        throw;
    }
}

DdsTransport::~DdsTransport() {
    dds_return_t rc = dds_delete(impl_->participant);
    if (rc < 0) spdlog::warn("dds_delete(participant) failed: {}", dds_strretcode(-rc));
    DomainRegistry::instance().release(impl_->config.domain_id);
}

NodeAddress DdsTransport::local_address() const { return impl_->config.address; }

dds_entity_t DdsTransport::Impl::addressed_writer(std::size_t index, NodeAddress destination) {
    auto& by_destination = addressed_writers[index];
    if (auto found = by_destination.find(destination); found != by_destination.end()) {
        return found->second;
    }
    auto publisher = publishers.find(destination);
    if (publisher == publishers.end()) {
        const dds_entity_t created = create_in_partitions(
            participant, true, {addressed_partition(destination), sender_partition(config.address)});
        publisher = publishers.emplace(destination, created).first;
    }
    const dds_entity_t writer =
        check(dds_create_writer(publisher->second, topics[index], writer_qos[index].get(), nullptr),
              "dds_create_writer(addressed)");
    by_destination.emplace(destination, writer);
    return writer;
}

SendResult DdsTransport::Impl::write(const Envelope& envelope,
                                     std::span<const NodeAddress> destinations) {
    const std::size_t index = kind_index(envelope.kind);
    dds_entity_t writer = writers[index];
    if (addressed[index]) {
        try {
            writer = addressed_writer(index, envelope.destination);
        } catch (const DdsError& error) {
            ++send_failed;
            spdlog::warn("node {}: no writer to node {} on {}: {}", config.address,
                         envelope.destination, rows[index]->topic_name, error.what());
            return SendResult::failed;
        }
    }
    if (writer == 0) {
        ++send_failed;  // a kind this participant does not carry
        return SendResult::rejected_invalid;
    }
    dds_return_t rc;
    if (typed::is_typed(envelope.kind)) {
        if (auto why = outgoing.build(envelope, destinations)) {
            const std::uint64_t failures = ++send_failed;
            if (failures <= 10 || failures % 1000 == 0) {
                spdlog::warn("node {}: not sent on {} (#{}): {}", config.address,
                             rows[index]->topic_name, failures, *why);
            }
            return SendResult::rejected_invalid;
        }
        rc = dds_write(writer, outgoing.sample());
    } else if (rows[index]->keyed_by_source) {
        keel_wire_SourcedMessage sample{};
        fill_sample(sample, envelope);
        rc = dds_write(writer, &sample);
    } else {
        keel_wire_Message sample{};
        fill_sample(sample, envelope);
        rc = dds_write(writer, &sample);
    }
    if (rc < 0) {
        const std::uint64_t failures = ++send_failed;
        if (failures <= 10 || failures % 1000 == 0) {
            spdlog::warn("node {}: dds_write on {} failed (#{}): {}", config.address,
                         rows[index]->topic_name, failures, dds_strretcode(-rc));
        }
        return SendResult::failed;
    }
    ++sent;
    return SendResult::sent;
}

SendResult DdsTransport::send(const Envelope& envelope) {
    Impl& impl = *impl_;
    if (impl.config.read_only) {
        ++impl.send_failed;
        return SendResult::rejected_invalid;
    }
    if (auto problem = validate(envelope, impl.config.limits)) {
        ++impl.send_failed;
        return problem->error == EnvelopeError::oversized ? SendResult::rejected_oversized
                                                          : SendResult::rejected_invalid;
    }
    if (envelope.kind == MessageKind::heartbeat && impl.config.node_state_refresh.count() > 0) {
        std::lock_guard lock(impl.state_mutex);
        if (impl.last_state &&
            Clock::now() - impl.last_state_write >= impl.config.node_state_refresh) {
            impl.write_state(*impl.last_state);
        }
    }
    return impl.write(envelope);
}

SendResult DdsTransport::send_to_each(const Envelope& envelope,
                                      std::span<const NodeAddress> destinations) {
    Impl& impl = *impl_;
    if (envelope.kind != MessageKind::reconfiguration_command || destinations.size() < 2 ||
        destinations.size() > static_cast<std::size_t>(fsm::kMaxNodes) || impl.config.read_only) {
        return Transport::send_to_each(envelope, destinations);
    }
    if (std::ranges::find(destinations, broadcast_address) != destinations.end()) {
        ++impl.send_failed;
        return SendResult::rejected_invalid;
    }
    Envelope one = envelope;
    one.destination = broadcast_address;
    if (auto problem = validate(one, impl.config.limits)) {
        ++impl.send_failed;
        return problem->error == EnvelopeError::oversized ? SendResult::rejected_oversized
                                                          : SendResult::rejected_invalid;
    }
    return impl.write(one, destinations);
}

SendResult DdsTransport::send_unchecked(const Envelope& envelope) {
    if (impl_->config.read_only || !is_valid_kind(static_cast<std::uint8_t>(envelope.kind))) {
        return SendResult::rejected_invalid;  // there is no topic to write it on
    }
    return impl_->write(envelope);
}

void DdsTransport::Impl::take_typed(std::size_t index, dds_entity_t reader,
                                    std::vector<Inbound>& out, std::size_t max_items,
                                    std::size_t& taken) {
    const TopicQos& row = *rows[index];
    while (taken < max_items) {
        std::array<void*, take_batch> samples{};
        std::array<dds_sample_info_t, take_batch> infos;
        const std::size_t want = std::min(take_batch, max_items - taken);
        const dds_return_t count = dds_take(reader, samples.data(), infos.data(), want,
                                            static_cast<uint32_t>(want));
        if (count < 0) {
            spdlog::warn("node {}: dds_take on {} failed: {}", config.address, row.topic_name,
                         dds_strretcode(-count));
            return;
        }
        for (dds_return_t i = 0; i < count; ++i) {
            const auto at = static_cast<std::size_t>(i);
            if (!infos[at].valid_data) continue;  // a writer left
            // Who may say it first (as for envelopes of bytes), then what it says.
            const typed::Header head = typed::header(row.kind, samples[at]);
            Envelope claimed;
            claimed.source = head.source;
            claimed.sequence = head.sequence;
            bool replayed = false;
            Inbound item;
            if (auto why = judge_sender(reader, infos[at].publication_handle, claimed,
                                        replayed)) {
                item = Inbound::rejected(
                    replayed ? EnvelopeError::replayed : EnvelopeError::forged_sender,
                    std::move(*why), row.topic_name);
            } else {
                typed::Incoming incoming = typed::read(
                    row.kind, samples[at],
                    config.read_only ? std::nullopt : std::optional<NodeAddress>(config.address));
                item = incoming.envelope
                           ? Inbound::accepted(std::move(*incoming.envelope), row.topic_name)
                           : Inbound::rejected(EnvelopeError::bad_message,
                                               "from node " + std::to_string(head.source) + ": " +
                                                   incoming.error,
                                               row.topic_name);
                if (item.ok) received_bytes += item.envelope.payload.size();
            }
            out.push_back(std::move(item));
            ++taken;
            ++received;
        }
        if (count > 0) dds_return_loan(reader, samples.data(), count);
        if (static_cast<std::size_t>(count) < want) return;
    }
}

void DdsTransport::Impl::take_from(std::size_t index, std::vector<Inbound>& out,
                                   std::size_t max_items, std::size_t& taken) {
    const std::vector<dds_entity_t>& kind_readers = readers[index];
    if (kind_readers.empty()) return;  // a kind this participant does not carry
    // One batch from each reader in turn, until they are drained or max_items is reached:
    // a sender whose reader is full (a flood of its own instances) delays no other sender's.
    const std::size_t count = kind_readers.size();
    const std::size_t start = reader_turn[index]++ % count;
    while (taken < max_items) {
        const std::size_t before = taken;
        for (std::size_t step = 0; step < count && taken < max_items; ++step) {
            const dds_entity_t reader = kind_readers[(start + step) % count];
            const std::size_t batch_end = std::min(max_items, taken + take_batch);
            if (typed::is_typed(rows[index]->kind)) {
                take_typed(index, reader, out, batch_end, taken);
            } else {
                take_bytes(index, reader, out, batch_end, taken);
            }
        }
        if (taken == before) return;  // every reader drained
    }
}

void DdsTransport::Impl::take_bytes(std::size_t index, dds_entity_t reader,
                                    std::vector<Inbound>& out, std::size_t max_items,
                                    std::size_t& taken) {
    const TopicQos& row = *rows[index];
    while (taken < max_items) {
        std::array<ddsi_serdata*, take_batch> samples;
        std::array<dds_sample_info_t, take_batch> infos;
        const std::size_t want = std::min(take_batch, max_items - taken);
        // Serialized samples, not deserialised ones: parse_serialized() copies the payload
        // once, straight into the Envelope.
        const dds_return_t count =
            dds_takecdr(reader, samples.data(), static_cast<uint32_t>(want), infos.data(),
                        DDS_ANY_STATE);
        if (count < 0) {
            spdlog::warn("node {}: dds_takecdr on {} failed: {}", config.address, row.topic_name,
                         dds_strretcode(-count));
            return;
        }
        for (dds_return_t i = 0; i < count; ++i) {
            ddsi_serdata* sample = samples[static_cast<std::size_t>(i)];
            // Samples without valid data announce instance state changes (a writer left).
            if (infos[static_cast<std::size_t>(i)].valid_data) {
                const std::uint32_t size = ddsi_serdata_size(sample);
                ddsrt_iovec_t bytes{};
                ddsi_serdata* reference = ddsi_serdata_to_ser_ref(sample, 0, size, &bytes);
                Inbound item = parse_serialized_message(
                    {static_cast<const std::uint8_t*>(bytes.iov_base), bytes.iov_len}, row.kind,
                    config.limits, row.topic_name);
                ddsi_serdata_to_ser_unref(reference, &bytes);
                if (item.ok) {
                    bool replayed = false;
                    if (auto why = judge_sender(reader,
                                                infos[static_cast<std::size_t>(i)].publication_handle,
                                                item.envelope, replayed)) {
                        item = Inbound::rejected(
                            replayed ? EnvelopeError::replayed : EnvelopeError::forged_sender,
                            std::move(*why), row.topic_name);
                    }
                }
                out.push_back(std::move(item));
                ++taken;
                ++received;
                received_bytes += size;
            }
            ddsi_serdata_unref(sample);
        }
        if (static_cast<std::size_t>(count) < want) return;
    }
}

DdsTransport::Impl::Publication& DdsTransport::Impl::publication(dds_entity_t reader,
                                                                   dds_instance_handle_t handle) {
    if (auto found = publications.find(handle); found != publications.end()) return found->second;
    // Instance handles are never reused; a node meets a few writers per peer and restart.
    if (publications.size() >= 4096) publications.clear();
    Publication entry;
    if (dds_builtintopic_endpoint_t* data = dds_get_matched_publication_data(reader, handle)) {
        entry.known = true;
        entry.sender = sender_of_partitions(data->qos);
        std::memcpy(&entry.participant, &data->participant_key, sizeof(entry.participant));
        dds_builtintopic_free_endpoint(data);
    }
    return publications.emplace(handle, entry).first->second;
}

// Whether a sample's envelope may be believed: its source must be the node its writer
// speaks for (the writer's sender partition; with DDS Security access control admits a
// writer in that partition only from that node's identity), and its sequence number must
// be new for that writer (a captured message sent again is refused). Returns why not.
std::optional<std::string> DdsTransport::Impl::judge_sender(dds_entity_t reader,
                                                            dds_instance_handle_t handle,
                                                            const Envelope& envelope,
                                                            bool& replayed) {
    Publication& entry = publication(reader, handle);
    if (!entry.known) {
        return "a sample claiming node " + std::to_string(envelope.source) +
               " from a writer DDS no longer knows (its sender cannot be established)";
    }
    if (!entry.sender) {
        return "a sample claiming node " + std::to_string(envelope.source) +
               " from a writer that speaks for no node (no single keel.from.N partition)";
    }
    if (*entry.sender != envelope.source) {
        return "a sample claiming node " + std::to_string(envelope.source) +
               " from a writer of node " + std::to_string(*entry.sender);
    }
    if (!config.security.enabled()) {
        auto bound = bindings.find(envelope.source);
        if (bound == bindings.end()) {
            bindings[envelope.source] = {entry.participant, reader, handle};
        } else if (std::memcmp(&bound->second.participant, &entry.participant,
                               sizeof(entry.participant)) != 0) {
            dds_builtintopic_endpoint_t* previous =
                dds_get_matched_publication_data(bound->second.reader, bound->second.publication);
            if (previous != nullptr) {
                dds_builtintopic_free_endpoint(previous);
                return "a sample claiming node " + std::to_string(envelope.source) +
                       " from participant " + guid_text(entry.participant) +
                       " while the node's participant " + guid_text(bound->second.participant) +
                       " is still present";
            }
            bound->second = {entry.participant, reader, handle};  // the node restarted
        }
    }
    // Serial-number order (RFC 1982): a writer's sequence numbers only grow.
    if (entry.any && static_cast<std::int32_t>(envelope.sequence - entry.last) <= 0) {
        replayed = true;
        return "sequence number " + std::to_string(envelope.sequence) + " of node " +
               std::to_string(envelope.source) + " at or below its writer's last, " +
               std::to_string(entry.last);
    }
    entry.any = true;
    entry.last = envelope.sequence;
    return std::nullopt;
}

std::size_t DdsTransport::receive(std::vector<Inbound>& out, std::size_t max_items) {
    Impl& impl = *impl_;
    std::size_t taken = 0;
    for (std::size_t step = 0; step < kind_count && taken < max_items; ++step) {
        impl.take_from((impl.next_reader + step) % kind_count, out, max_items, taken);
    }
    impl.next_reader = (impl.next_reader + 1) % kind_count;
    return taken;
}

bool DdsTransport::wait(std::chrono::nanoseconds timeout) {
    const dds_return_t rc =
        dds_waitset_wait(impl_->waitset, nullptr, 0, static_cast<dds_duration_t>(timeout.count()));
    // Consume the wake-up (if any) before the caller looks at what it was woken for: a
    // wake() after this point stays set and ends the next wait().
    bool woken = false;
    const dds_return_t taken = dds_take_guardcondition(impl_->wake_condition, &woken);
    if (taken < 0) {
        spdlog::warn("node {}: dds_take_guardcondition failed: {}", impl_->config.address,
                     dds_strretcode(-taken));
    }
    if (rc < 0) {
        spdlog::warn("node {}: dds_waitset_wait failed: {}", impl_->config.address,
                     dds_strretcode(-rc));
        return false;
    }
    return rc > 0;
}

void DdsTransport::wake() {
    const dds_return_t rc = dds_set_guardcondition(impl_->wake_condition, true);
    if (rc < 0) {
        spdlog::warn("node {}: dds_set_guardcondition failed: {}", impl_->config.address,
                     dds_strretcode(-rc));
    }
}

void DdsTransport::Impl::write_state(const NodeState& state) {
    if (config.read_only) {
        ++send_failed;
        return;
    }
    keel_wire_NodeState sample{};
    sample.node = state.node;
    sample.name = const_cast<char*>(state.name.c_str());
    sample.role = static_cast<keel_wire_Role>(state.role);
    sample.epoch = state.epoch;
    sample.configuration_id = state.configuration_id;
    sample.configuration = const_cast<char*>(state.configuration.c_str());
    sample.phase = const_cast<char*>(state.phase.c_str());
    const dds_return_t rc = dds_write(state_writer, &sample);
    if (rc < 0) {
        ++send_failed;
        spdlog::warn("node {}: publishing node state failed: {}", config.address,
                     dds_strretcode(-rc));
    }
    last_state_write = Clock::now();
}

void DdsTransport::publish_node_state(const NodeState& state) {
    std::lock_guard lock(impl_->state_mutex);
    impl_->last_state = state;
    impl_->write_state(state);
}

std::vector<NodeState> DdsTransport::node_states() {
    std::vector<NodeState> states;
    std::array<void*, 256> samples{};
    std::array<dds_sample_info_t, 256> infos{};
    const dds_return_t count =
        dds_read(impl_->state_reader, samples.data(), infos.data(), samples.size(), samples.size());
    if (count < 0) {
        spdlog::warn("node {}: dds_read(KeelNodeState) failed: {}", impl_->config.address,
                     dds_strretcode(-count));
        return states;
    }
    for (dds_return_t i = 0; i < count; ++i) {
        if (!infos[static_cast<std::size_t>(i)].valid_data) continue;
        const auto& sample = *static_cast<const keel_wire_NodeState*>(samples[static_cast<std::size_t>(i)]);
        NodeState state;
        state.node = sample.node;
        state.name = sample.name ? sample.name : "";
        const auto role = static_cast<int>(sample.role);
        state.role = (role >= 0 && role <= static_cast<int>(Role::resigned))
                         ? static_cast<Role>(role)
                         : Role::unknown;
        state.epoch = sample.epoch;
        state.configuration_id = sample.configuration_id;
        state.configuration = sample.configuration ? sample.configuration : "";
        state.phase = sample.phase ? sample.phase : "";
        states.push_back(std::move(state));
    }
    if (count > 0) dds_return_loan(impl_->state_reader, samples.data(), count);
    return states;
}

TransportCounters DdsTransport::counters() const {
    TransportCounters counters;
    counters.sent = impl_->sent.load();
    counters.send_failed = impl_->send_failed.load();
    counters.received = impl_->received.load();
    counters.received_bytes = impl_->received_bytes.load();
    for (const dds_entity_t heartbeats : impl_->readers[kind_index(MessageKind::heartbeat)]) {
        dds_requested_deadline_missed_status_t status{};
        if (dds_get_requested_deadline_missed_status(heartbeats, &status) >= 0) {
            counters.deadline_missed += status.total_count;
        }
    }
    return counters;
}

bool DdsTransport::wait_for_peers(std::size_t remote_readers, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
        bool all = true;
        auto matched = [&](dds_entity_t writer, std::size_t wanted) {
            dds_publication_matched_status_t status{};
            check(dds_get_publication_matched_status(writer, &status),
                  "dds_get_publication_matched_status");
            return status.current_count >= wanted;
        };
        for (std::size_t index = 0; index < kind_count && all; ++index) {
            if (impl_->writers[index] != 0) all = matched(impl_->writers[index], remote_readers);
            for (const auto& [destination, writer] : impl_->addressed_writers[index]) {
                const std::size_t wanted =
                    destination == broadcast_address ? remote_readers : std::min<std::size_t>(1, remote_readers);
                if (!(all = all && matched(writer, wanted))) break;
            }
        }
        if (all) return true;
        if (std::chrono::steady_clock::now() >= deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
}

}  // namespace keel::net::dds
