// The protocol's typed topics (typed_wire.hpp): every protocol message of KeelHeartbeat,
// KeelCommand and KeelAck crosses real DDS as fields and arrives as the codec's bytes; a
// payload that is no message of its topic is not sent; a sample whose fields the codec
// refuses, written by a plain DDS participant, is dropped as malformed; and what a DDS tool
// reads is the message's fields.
#include <dds/dds.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <map>
#include <set>
#include <thread>
#include <vector>

#include "core/fsm/codec.hpp"
#include "core/net/dds/dds_transport.hpp"
#include "core/net/dds/typed_wire.hpp"
#include "core/net/endpoint.hpp"
#include "core/net/dds/tests/support.hpp"
#include "keel.h"

namespace keel::net::dds {
namespace {

using namespace std::chrono_literals;
using testing::eventually;
using testing::test_name;

// A long miss limit: these tests judge samples, never liveliness.
DdsConfig config_for(NodeAddress address, std::uint32_t domain_id) {
    return testing::config_for(address, domain_id, 50);
}


fsm::View view(fsm::Epoch epoch, fsm::Seq seq, std::initializer_list<fsm::NodeId> failed) {
    fsm::View v;
    v.epoch = epoch;
    v.seq = seq;
    v.config = 4;
    v.base = 2;
    v.master = 1;
    for (const fsm::NodeId node : failed) v.failed.insert(node);
    return v;
}

// Every message each typed topic carries, at its corners: acknowledgements, failed nodes
// beyond the first word of a set, joint views, SAFE, the largest ids.
std::vector<std::pair<MessageKind, fsm::Message>> protocol_messages() {
    fsm::Heartbeat monitor{1, 9, 3, false, 41, {{2, 1, 40}, {255, 7, 2}}, false};
    fsm::Heartbeat excluded{1, 9, 4, true, 1, {}, false};
    fsm::Heartbeat reply{1, 9, 3, false, 42, {{2, 1, 41}}, true};
    fsm::View safe = view(9, 3, {0, 2, 200});
    safe.config = fsm::kSafeConfig;
    // A hand-over: the view's master is not its sender, and it names its receiver's boot.
    fsm::Command handed(1, view(10, 0, {}));
    handed.view.master = 2;
    handed.boot = 0xDEADBEEF;
    return {
        {MessageKind::heartbeat, monitor},
        {MessageKind::heartbeat, excluded},
        {MessageKind::reconfiguration_command, fsm::Command(1, view(9, 2, {3}))},
        {MessageKind::reconfiguration_command,
         fsm::Command(1, safe, {view(9, 1, {}), view(9, 2, {3, 130})})},
        {MessageKind::reconfiguration_command, handed},
        {MessageKind::reconfiguration_command, fsm::ActivateCommand{1, 9, 2}},
        {MessageKind::acknowledgement, fsm::Ack{2, 9, 2, fsm::AckKind::Prepared}},
        {MessageKind::acknowledgement, fsm::Ack{2, 9, 2, fsm::AckKind::Activated}},
        {MessageKind::acknowledgement,
         fsm::CheckpointAck{3, 9, 1, fsm::Version(fsm::lineage_of(9, 2), 17)}},
        {MessageKind::acknowledgement, reply},
    };
}

TEST(TypedWire, EveryProtocolMessageCrossesDdsAsFieldsAndArrivesAsTheCodecsBytes) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto one = std::make_unique<DdsTransport>(config_for(1, domain));
    auto two = std::make_unique<DdsTransport>(config_for(2, domain));
    ASSERT_TRUE(one->wait_for_peers(1, 20s));
    ASSERT_TRUE(two->wait_for_peers(1, 20s));
    const FilterConfig filter{.known_nodes = {1, 2, 3}};
    Endpoint sender(std::move(one), filter);
    Endpoint receiver(std::move(two), filter);
    std::map<Sequence, Envelope> sent;
    for (const auto& [kind, message] : protocol_messages()) {
        const NodeAddress to = kind == MessageKind::heartbeat ? broadcast_address : NodeAddress{2};
        Envelope envelope = sender.make_envelope(kind, to, 3, fsm::encode(message));
        sent[envelope.sequence] = envelope;
    }
    // The reliable kinds are sent once. Heartbeats are best-effort and keyed (a reader keeps
    // the latest of each sender): each is sent, alone, until it arrived.
    for (const auto& [sequence, envelope] : sent) {
        if (envelope.kind != MessageKind::heartbeat) {
            ASSERT_EQ(sender.send(envelope), SendResult::sent);
        }
    }
    std::map<Sequence, Envelope> got;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (got.size() < sent.size() && std::chrono::steady_clock::now() < deadline) {
        for (const auto& [sequence, envelope] : sent) {
            if (envelope.kind == MessageKind::heartbeat && !got.contains(sequence)) {
                ASSERT_EQ(sender.send(envelope), SendResult::sent);
                break;
            }
        }
        receiver.wait(50ms);
        receiver.poll([&](Envelope&& envelope) { got[envelope.sequence] = std::move(envelope); });
    }
    for (const auto& [sequence, envelope] : sent) {
        ASSERT_TRUE(got.contains(sequence)) << "message " << sequence << " never arrived";
        EXPECT_EQ(got[sequence], envelope) << "message " << sequence;
    }
    EXPECT_EQ(receiver.counters().dropped_malformed, 0u);
}

// The largest typed messages the capacity allows (a Command whose kMaxJointViews joint
// views each fail every node and carry an online configuration of every node and task, a
// heartbeat acknowledging every node) arrive in a domain whose
// MaxSampleSize is max_typed_sample_bytes; the Command does not arrive in one bounded by
// the codec's own sizes (a failed set is 33 bytes there, 512 in CDR): the protocol's domain
// needs the typed bound, however small the mission's checkpoints are.
TEST(TypedWire, TheLargestTypedMessagesNeedTheTypedSampleBound) {
    fsm::View full;
    full.epoch = 9;
    full.seq = 2;
    full.config = 4;
    full.master = 1;
    for (int node = 0; node < fsm::kMaxNodes; ++node) full.failed.insert(static_cast<fsm::NodeId>(node));
    // An online configuration at the capacity (every node an observer, every task placed).
    auto online = std::make_shared<fsm::OnlineConfig>();
    online->master = 1;
    online->observers.assign(fsm::kMaxNodes, fsm::NodeId{2});
    online->host.assign(fsm::kMaxTasks, fsm::NodeId{3});
    full.config = full.base = fsm::kOnlineConfig;
    full.online = fsm::OnlinePtr(online);
    std::vector<fsm::View> joint(fsm::kMaxJointViews, full);
    fsm::Heartbeat heartbeat{1, 9, 3, false, 41, {}, false};
    for (int node = 0; node < fsm::kMaxNodes; ++node) {
        heartbeat.acks.push_back({static_cast<fsm::NodeId>(node), 1, 40});
    }
    const std::vector<std::pair<MessageKind, fsm::Message>> largest = {
        {MessageKind::reconfiguration_command, fsm::Command(1, full, joint)},
        {MessageKind::heartbeat, heartbeat},
    };
    for (const auto& [kind, message] : largest) {
        ASSERT_LE(fsm::encode(message).size(), std::max(fsm::kMaxCommandBytes, fsm::kMaxHeartbeatBytes));
    }
    auto arrived = [&](std::size_t max_sample_bytes, const std::string& name) {
        DdsConfig one_config = config_for(1, domain_id_for(test_name() + name));
        one_config.max_sample_bytes = max_sample_bytes;
        DdsConfig two_config = one_config;
        two_config.address = 2;
        auto one = std::make_unique<DdsTransport>(one_config);
        auto two = std::make_unique<DdsTransport>(two_config);
        EXPECT_TRUE(one->wait_for_peers(1, 20s));
        EXPECT_TRUE(two->wait_for_peers(1, 20s));
        const FilterConfig filter{.known_nodes = {1, 2}};
        Endpoint sender(std::move(one), filter);
        Endpoint receiver(std::move(two), filter);
        std::set<MessageKind> got;
        const auto deadline = std::chrono::steady_clock::now() + 4s;
        while (got.size() < largest.size() && std::chrono::steady_clock::now() < deadline) {
            for (const auto& [kind, message] : largest) {
                if (got.contains(kind)) continue;
                const NodeAddress to = kind == MessageKind::heartbeat ? broadcast_address : NodeAddress{2};
                // Too large for the domain, DDS refuses the write itself.
                (void)sender.send(sender.make_envelope(kind, to, 3, fsm::encode(message)));
            }
            receiver.wait(200ms);
            receiver.poll([&](Envelope&& envelope) { got.insert(envelope.kind); });
        }
        return got;
    };
    EXPECT_EQ(arrived(max_typed_sample_bytes, "-typed").size(), largest.size());
    EXPECT_FALSE(arrived(max_sample_bytes_for(std::max(fsm::kMaxCommandBytes, fsm::kMaxHeartbeatBytes)),
                         "-codec")
                     .contains(MessageKind::reconfiguration_command));
}

TEST(TypedWire, APayloadThatIsNoMessageOfItsTopicIsNotSent) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport node(config_for(1, domain));
    Envelope garbage{MessageKind::heartbeat, 1, broadcast_address, 0, 1, 1, {0xde, 0xad}};
    EXPECT_EQ(node.send(garbage), SendResult::rejected_invalid);
    Envelope error_on_command{MessageKind::reconfiguration_command, 1, broadcast_address, 0, 1, 2,
                              fsm::encode(fsm::ErrorNotification{1, 1, 2})};
    EXPECT_EQ(node.send(error_on_command), SendResult::rejected_invalid);
    Envelope command_on_ack{MessageKind::acknowledgement, 1, 2, 0, 1, 3,
                            fsm::encode(fsm::ActivateCommand{1, 1, 1})};
    EXPECT_EQ(node.send(command_on_ack), SendResult::rejected_invalid);
    EXPECT_EQ(node.counters().send_failed, 3u);
    // The same messages on their own topics are sent.
    Envelope heartbeat{MessageKind::heartbeat, 1, broadcast_address, 0, 1, 4,
                       fsm::encode(fsm::Heartbeat{1, 1, 1, false, 1, {}, false})};
    EXPECT_EQ(node.send(heartbeat), SendResult::sent);
}

// A plain DDS participant in node 5's sender partition writes KeelAck and KeelCommand
// samples whose fields no codec message has: each is taken and dropped as malformed
// (bad_message), never delivered; a well-formed one after them is.
class RawTyped {
public:
    RawTyped(std::uint32_t domain, const char* partition) {
        participant_ = dds_create_participant(domain, nullptr, nullptr);
        dds_qos_t* qos = dds_create_qos();
        dds_qset_partition(qos, 1, &partition);
        const dds_entity_t publisher = dds_create_publisher(participant_, qos, nullptr);
        dds_delete_qos(qos);
        dds_qos_t* writer_qos = dds_create_qos();
        dds_qset_reliability(writer_qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
        dds_qset_history(writer_qos, DDS_HISTORY_KEEP_ALL, 0);
        dds_qset_destination_order(writer_qos, DDS_DESTINATIONORDER_BY_RECEPTION_TIMESTAMP);
        const dds_entity_t ack_topic =
            dds_create_topic(participant_, &keel_wire_Ack_desc, "KeelAck", nullptr, nullptr);
        ack_writer_ = dds_create_writer(publisher, ack_topic, writer_qos, nullptr);
        dds_qset_history(writer_qos, DDS_HISTORY_KEEP_LAST, 16);
        dds_qset_durability(writer_qos, DDS_DURABILITY_TRANSIENT_LOCAL);
        const dds_entity_t command_topic = dds_create_topic(participant_, &keel_wire_Command_desc,
                                                            "KeelCommand", nullptr, nullptr);
        command_writer_ = dds_create_writer(publisher, command_topic, writer_qos, nullptr);
        dds_delete_qos(writer_qos);
    }
    ~RawTyped() { dds_delete(participant_); }
    RawTyped(const RawTyped&) = delete;
    RawTyped& operator=(const RawTyped&) = delete;

    bool matched() const {
        dds_publication_matched_status_t a{};
        dds_publication_matched_status_t c{};
        return dds_get_publication_matched_status(ack_writer_, &a) >= 0 && a.current_count > 0 &&
               dds_get_publication_matched_status(command_writer_, &c) >= 0 && c.current_count > 0;
    }
    void ack(keel_wire_Ack sample) { ASSERT_GE(dds_write(ack_writer_, &sample), 0); }
    void command(keel_wire_Command sample) { ASSERT_GE(dds_write(command_writer_, &sample), 0); }

private:
    dds_entity_t participant_ = 0;
    dds_entity_t ack_writer_ = 0;
    dds_entity_t command_writer_ = 0;
};

// An IDL enum field holding a value outside its enum, as another DDS program may write it.
template <class Enum>
void set_enum(Enum& field, std::int32_t value) {
    static_assert(sizeof(Enum) == sizeof(std::int32_t));
    std::memcpy(&field, &value, sizeof value);
}

TEST(TypedWire, FieldsTheCodecRefusesAreDroppedAsMalformed) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsConfig receiver_config = config_for(2, domain);
    receiver_config.command_history_depth = 16;  // the nine Commands below, in one burst
    auto receiver_owner = std::make_unique<DdsTransport>(receiver_config);
    Endpoint receiver(std::move(receiver_owner), FilterConfig{.known_nodes = {2, 5}});
    RawTyped five(domain, "keel.from.5");
    ASSERT_TRUE(eventually([&] { return five.matched(); }));

    Sequence sequence = 0;
    auto ack = [&](keel_wire_AckKind kind) {
        keel_wire_Ack sample{};
        sample.source = 5;
        sample.destination = 2;
        sample.epoch = 3;
        sample.sequence_number = ++sequence;
        sample.kind = kind;
        sample.sender = 5;
        sample.ack_epoch = 3;
        sample.seq = 1;
        return sample;
    };
    // (An enum value outside its IDL enum cannot be written at all: Cyclone's serializer
    // refuses the sample, TypedWire.AnEnumOutsideItsIdlEnumIsNeverWritten.)
    five.ack(ack(keel_wire_ACK_HEARTBEAT));              // a reply without its heartbeat
    keel_wire_HeartbeatAck far{999, 1, 1};               // an acknowledged node beyond 256
    keel_wire_HeartbeatBody body{};
    body.sender = 5;
    body.reply = true;
    body.acks._buffer = &far;
    body.acks._length = body.acks._maximum = 1;
    keel_wire_Ack reply = ack(keel_wire_ACK_HEARTBEAT);
    reply.heartbeat_reply._buffer = &body;
    reply.heartbeat_reply._length = reply.heartbeat_reply._maximum = 1;
    five.ack(reply);
    keel_wire_Ack unknown_sender = ack(keel_wire_ACK_PREPARED);  // `from` is a node beyond 256
    unknown_sender.sender = 4000;
    five.ack(unknown_sender);
    std::uint16_t failed[] = {300};  // a failed node beyond the capacity
    keel_wire_Command command{};
    command.source = 5;
    command.destination = broadcast_address;
    command.epoch = 3;
    command.sequence_number = ++sequence;
    command.kind = keel_wire_COMMAND_SWITCH;
    command.sender = 5;
    command.adopted.master = 5;
    command.adopted.failed._buffer = failed;
    command.adopted.failed._length = command.adopted.failed._maximum = 1;
    five.command(command);
    // Fault model 3: a view whose epoch does not fit the envelope's 24 bits (once adopted,
    // every node's own sends failed for good), and an Activate with one.
    keel_wire_Command wide = command;
    wide.sequence_number = ++sequence;
    wide.adopted.failed._length = 0;
    wide.adopted.epoch = fsm::kMaxEpoch + 2;
    five.command(wide);
    keel_wire_Command activate{};
    activate.source = 5;
    activate.destination = broadcast_address;
    activate.epoch = 3;
    activate.sequence_number = ++sequence;
    activate.kind = keel_wire_COMMAND_ACTIVATE;
    activate.sender = 5;
    activate.activate_epoch = 0xFFFF'FFFFu;
    activate.activate_seq = 1;
    five.command(activate);
    // Online configurations (View.online, flat): one whose counts do not add up to its
    // length (3 observers announced, 1 given); one whose host is a node beyond the
    // capacity (the codec's read_node); and a view naming one (base 0xFFFD) that carries
    // none (the codec finds its bytes missing).
    keel_wire_Command online = command;
    online.adopted.failed._length = 0;
    online.adopted.configuration = online.adopted.base = fsm::kOnlineConfig;
    std::uint16_t short_flat[] = {0, 5, 3, 1, 1, 2};
    online.sequence_number = ++sequence;
    online.adopted.online._buffer = short_flat;
    online.adopted.online._length = online.adopted.online._maximum = 6;
    five.command(online);
    std::uint16_t far_host[] = {0, 5, 0, 2, 300, 1};
    online.sequence_number = ++sequence;
    online.adopted.online._buffer = far_host;
    five.command(online);
    online.sequence_number = ++sequence;
    online.adopted.online._buffer = nullptr;
    online.adopted.online._length = online.adopted.online._maximum = 0;
    five.command(online);
    // A Command for a list of nodes (one sample for several members): one whose own
    // destination is not broadcast, one whose list names broadcast, one of 257 nodes.
    keel_wire_Command listed = activate;
    listed.activate_epoch = 3;
    std::uint16_t two[] = {2, 7};
    listed.destinations._buffer = two;
    listed.destinations._length = listed.destinations._maximum = 2;
    listed.destination = 7;
    listed.sequence_number = ++sequence;
    five.command(listed);
    std::uint16_t with_broadcast[] = {broadcast_address, 2};
    listed.destination = broadcast_address;
    listed.destinations._buffer = with_broadcast;
    listed.sequence_number = ++sequence;
    five.command(listed);
    std::vector<std::uint16_t> too_many(257, 2);
    listed.destinations._buffer = too_many.data();
    listed.destinations._length = listed.destinations._maximum = 257;
    listed.sequence_number = ++sequence;
    five.command(listed);
    five.ack(ack(keel_wire_ACK_ACTIVATED));  // well-formed: delivered

    std::vector<Envelope> got;
    ASSERT_TRUE(eventually([&] {
        receiver.wait(20ms);
        receiver.poll([&](Envelope&& envelope) { got.push_back(std::move(envelope)); });
        return receiver.counters().dropped_malformed >= 12 && !got.empty();
    })) << "malformed " << receiver.counters().dropped_malformed << ", delivered " << got.size();
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].payload, fsm::encode(fsm::Ack{5, 3, 1, fsm::AckKind::Activated}));
    EXPECT_EQ(receiver.counters().dropped_malformed, 12u);
    EXPECT_EQ(receiver.counters().dropped_forged_sender, 0u);
}

TEST(TypedWire, AnEnumOutsideItsIdlEnumIsNeverWritten) {
    const std::uint32_t domain = domain_id_for(test_name());
    const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
    ASSERT_GT(participant, 0);
    const dds_entity_t topic =
        dds_create_topic(participant, &keel_wire_Ack_desc, "KeelAck", nullptr, nullptr);
    const dds_entity_t writer = dds_create_writer(participant, topic, nullptr, nullptr);
    ASSERT_GT(writer, 0);
    keel_wire_Ack sample{};
    set_enum(sample.kind, 7);
    EXPECT_EQ(dds_write(writer, &sample), DDS_RETCODE_BAD_PARAMETER);
    sample.kind = keel_wire_ACK_PREPARED;
    EXPECT_EQ(dds_write(writer, &sample), DDS_RETCODE_OK);
    dds_delete(participant);
}

// What `cyclonedds subscribe KeelHeartbeat` shows: a plain reader of the topic's type,
// in the default partition, reads the heartbeat's fields.
TEST(TypedWire, ADdsToolReadsTheHeartbeatsFields) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport node(config_for(1, domain));
    const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
    ASSERT_GT(participant, 0);
    // A tool's reader in the default partition: the typed topics' writers are there too.
    const dds_entity_t subscriber = dds_create_subscriber(participant, nullptr, nullptr);
    const dds_entity_t topic = dds_create_topic(participant, &keel_wire_Heartbeat_desc,
                                                "KeelHeartbeat", nullptr, nullptr);
    ASSERT_GT(topic, 0) << dds_strretcode(-topic);
    const dds_entity_t reader = dds_create_reader(subscriber, topic, nullptr, nullptr);
    ASSERT_GT(reader, 0);
    const fsm::Heartbeat said{1, 12, 3, false, 77, {{2, 1, 76}}, false};
    Envelope heartbeat{MessageKind::heartbeat, 1, broadcast_address, 0, 12, 1, fsm::encode(said)};
    keel_wire_HeartbeatBody seen{};
    std::uint16_t acked = 0;
    ASSERT_TRUE(eventually([&] {
        ++heartbeat.sequence;
        node.send(heartbeat);
        void* samples[1] = {nullptr};
        dds_sample_info_t info;
        const dds_return_t count = dds_take(reader, samples, &info, 1, 1);
        bool valid = false;
        if (count == 1 && info.valid_data) {
            seen = static_cast<const keel_wire_Heartbeat*>(samples[0])->body;
            valid = true;
            if (seen.acks._length == 1) acked = seen.acks._buffer[0].node;
        }
        if (count > 0) dds_return_loan(reader, samples, count);
        return valid;
    }));
    EXPECT_EQ(seen.sender, 1);
    EXPECT_EQ(seen.seen_epoch, 12u);
    EXPECT_EQ(seen.incarnation, 3u);
    EXPECT_EQ(seen.seq, 77u);
    EXPECT_EQ(acked, 2);
    dds_delete(participant);
}

}  // namespace
}  // namespace keel::net::dds
