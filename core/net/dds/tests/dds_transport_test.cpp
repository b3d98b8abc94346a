// DDS transport tests: real Cyclone DDS participants pinned to loopback, each test in its
// own domain (domain_id_for(test name) mixes in the process id) so ctest -j runs apart.
#include "core/net/dds/dds_transport.hpp"

#include <arpa/inet.h>
#include <dds/dds.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <future>
#include <map>
#include <random>
#include <thread>

#include "core/fsm/codec.hpp"
#include "core/net/endpoint.hpp"
#include "core/net/fault_transport.hpp"
#include "core/net/dds/tests/support.hpp"
#include "keel.h"

namespace keel::net::dds {
namespace {

using namespace std::chrono_literals;
using testing::config_for;
using testing::eventually;
using testing::test_name;

// Polls `endpoint` until `count` envelopes arrived or 10 s passed.
std::vector<Envelope> collect(Endpoint& endpoint, std::size_t count) {
    std::vector<Envelope> got;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (got.size() < count && std::chrono::steady_clock::now() < deadline) {
        endpoint.wait(50ms);
        endpoint.poll([&](Envelope&& envelope) { got.push_back(std::move(envelope)); });
    }
    return got;
}

// A payload a kind's topic carries: the protocol's typed topics (heartbeats, commands,
// acknowledgements) carry protocol messages only; the others any bytes.
std::vector<std::uint8_t> payload_for(MessageKind kind, std::vector<std::uint8_t> bytes) {
    switch (kind) {
        case MessageKind::heartbeat:
            return fsm::encode(fsm::Heartbeat{1, 3, 1, false, 7, {{2, 1, 6}}, false});
        case MessageKind::reconfiguration_command:
            return fsm::encode(fsm::ActivateCommand{1, 3, 2});
        case MessageKind::acknowledgement:
            return fsm::encode(fsm::Ack{1, 3, 2, fsm::AckKind::Activated});
        default:
            return bytes;
    }
}


TEST(DdsConfigXml, PinsTheInterfaceAndPeersAndDisablesMulticast) {
    DdsConfig config;
    const std::string xml = domain_config_xml(config);
    EXPECT_NE(xml.find("<NetworkInterface name=\"lo\"/>"), std::string::npos);
    EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
    EXPECT_NE(xml.find("<Peers><Peer address=\"127.0.0.1\"/></Peers>"), std::string::npos);
    config.network_interface = "veth-pn1";
    config.peers = {"10.0.0.1", "10.0.0.2"};
    const std::string namespaced = domain_config_xml(config);
    EXPECT_NE(namespaced.find("name=\"veth-pn1\""), std::string::npos);
    EXPECT_NE(namespaced.find("<Peer address=\"10.0.0.2\"/>"), std::string::npos);
    config.peers = {"127.0.0.1\"/><Peer address=\"239.255.0.1"};
    EXPECT_THROW(domain_config_xml(config), std::invalid_argument);
}

// The data plane's domain is another domain than the protocol's, inside what the
// credentials cover (0..230), and no two protocol domains of 0..230 share one.
TEST(DdsConfigXml, ParticipantIndicesCoverEveryNodeOfAMissionOnOneHost) {
    // Cyclone's default, 30, left a 32-node mission's nodes beyond the 30th without a
    // participant: the mission's nodes and 16 more for tools, within [30, 300].
    EXPECT_EQ(participant_indices_for(4), 30u);
    EXPECT_EQ(participant_indices_for(32), 48u);
    EXPECT_EQ(participant_indices_for(256), 272u);
    EXPECT_EQ(participant_indices_for(100'000), max_participant_indices);
    EXPECT_EQ(participant_indices_for(-1), 30u);
    DdsConfig config;
    config.max_auto_participant_index = participant_indices_for(32);
    EXPECT_NE(domain_config_xml(config).find("<MaxAutoParticipantIndex>48</MaxAutoParticipantIndex>"),
              std::string::npos);
}

TEST(DdsConfigXml, EveryProtocolDomainHasADataDomainOfItsOwn) {
    std::set<std::uint32_t> data_domains;
    for (std::uint32_t domain = 0; domain <= 230; ++domain) {
        const std::uint32_t data = data_domain_for(domain);
        EXPECT_NE(data, domain);
        EXPECT_LE(data, 230u);
        data_domains.insert(data);
    }
    EXPECT_EQ(data_domains.size(), 231u);
    EXPECT_LE(data_domain_for(232), 230u);
}

TEST(DdsTransport, OneProcessCannotConfigureADomainTwoWays) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport first(config_for(1, domain));
    DdsConfig other = config_for(2, domain);
    other.max_auto_participant_index = 5;
    EXPECT_THROW(DdsTransport second(other), std::invalid_argument);
    EXPECT_NO_THROW(DdsTransport third(config_for(3, domain)));
}

TEST(DdsTopicTable, EveryKindHasOneTopic) {
    std::set<MessageKind> kinds;
    std::set<std::string> names;
    for (const TopicQos& row : topic_table()) {
        kinds.insert(row.kind);
        names.insert(row.topic_name);
    }
    EXPECT_EQ(kinds.size(), std::size(all_message_kinds));
    EXPECT_EQ(names.size(), std::size(all_message_kinds));
}

TEST(DdsTransport, TwoParticipantsExchangeEveryKindIncludingSixteenMegabytes) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto one = std::make_unique<DdsTransport>(config_for(1, domain));
    auto two = std::make_unique<DdsTransport>(config_for(2, domain));
    ASSERT_TRUE(one->wait_for_peers(1, 20s));
    ASSERT_TRUE(two->wait_for_peers(1, 20s));
    const FilterConfig filter{.known_nodes = {1, 2}};
    Endpoint sender(std::move(one), filter);
    Endpoint receiver(std::move(two), filter);

    std::map<MessageKind, Envelope> expected;
    for (MessageKind kind : all_message_kinds) {
        std::vector<std::uint8_t> payload(kind == MessageKind::large ? 16u * 1024u * 1024u : 100u);
        for (std::size_t i = 0; i < payload.size(); ++i) {
            payload[i] = static_cast<std::uint8_t>((i * 31) ^ static_cast<std::size_t>(kind));
        }
        const NodeAddress destination =
            kind == MessageKind::heartbeat ? broadcast_address : NodeAddress{2};
        expected[kind] =
            sender.make_envelope(kind, destination, 40, payload_for(kind, std::move(payload)));
        ASSERT_EQ(sender.send(expected[kind]), SendResult::sent) << to_string(kind);
    }
    // Best-effort kinds (unreliable data, heartbeat) may be lost by contract: they are sent
    // again until they arrive; reliable ones are sent once.
    std::map<MessageKind, Envelope> got;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (got.size() < expected.size() && std::chrono::steady_clock::now() < deadline) {
        receiver.wait(100ms);
        receiver.poll([&](Envelope&& envelope) { got[envelope.kind] = std::move(envelope); });
        for (MessageKind kind : {MessageKind::unreliable_data, MessageKind::heartbeat}) {
            if (!got.contains(kind)) sender.send(expected[kind]);
        }
    }
    for (const auto& [kind, envelope] : expected) {
        ASSERT_TRUE(got.contains(kind)) << to_string(kind) << " never arrived";
        EXPECT_EQ(got[kind], envelope) << to_string(kind);
    }
    EXPECT_GE(receiver.counters().received, expected.size());
}

// Missions of up to 256 nodes: node 255 (the broadcast address when addresses were one
// byte) speaks and is spoken to like any other, through the real DDS serialization.
TEST(DdsTransport, NodeAddressesBeyondOneByteTravel) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto high_owner = std::make_unique<DdsTransport>(config_for(255, domain));
    auto low_owner = std::make_unique<DdsTransport>(config_for(1, domain));
    ASSERT_TRUE(high_owner->wait_for_peers(1, 20s));
    ASSERT_TRUE(low_owner->wait_for_peers(1, 20s));
    const FilterConfig filter{.known_nodes = {1, 255}};
    Endpoint high(std::move(high_owner), filter);
    Endpoint low(std::move(low_owner), filter);
    const Envelope up = low.make_envelope(MessageKind::request, 255, 7, {1, 2, 3});
    const Envelope down = high.make_envelope(MessageKind::response, 1, 7, {4, 5});
    ASSERT_EQ(low.send(up), SendResult::sent);
    ASSERT_EQ(high.send(down), SendResult::sent);
    const std::vector<Envelope> at_high = collect(high, 1);
    const std::vector<Envelope> at_low = collect(low, 1);
    ASSERT_EQ(at_high.size(), 1u);
    ASSERT_EQ(at_low.size(), 1u);
    EXPECT_EQ(at_high[0], up);
    EXPECT_EQ(at_high[0].destination, 255);
    EXPECT_EQ(at_low[0], down);
    EXPECT_EQ(at_low[0].source, 255);
}

TEST(DdsTransport, MalformedOversizedUnknownAndStaleSamplesAreCountedAndDropped) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsConfig receiver_config = config_for(2, domain);
    receiver_config.limits.max_payload_bytes = 1024;
    auto hostile_owner = std::make_unique<DdsTransport>(config_for(1, domain));
    auto stranger_owner = std::make_unique<DdsTransport>(config_for(9, domain));
    auto receiver_owner = std::make_unique<DdsTransport>(receiver_config);
    DdsTransport& hostile = *hostile_owner;
    DdsTransport& stranger = *stranger_owner;
    ASSERT_TRUE(hostile.wait_for_peers(2, 20s));
    ASSERT_TRUE(stranger.wait_for_peers(2, 20s));
    Endpoint receiver(std::move(receiver_owner),
                      FilterConfig{.known_nodes = {1, 2}, .limits = EnvelopeLimits{1024}});
    receiver.set_epoch_floor(5);

    Envelope base;
    base.kind = MessageKind::reliable_data;
    base.source = 1;
    base.destination = 2;
    base.epoch = 5;

    // Each with a new sequence number, as a node's endpoint stamps them (a repeated one is
    // a replay, counted apart).
    Envelope broadcast_source = base;
    broadcast_source.source = broadcast_address;
    broadcast_source.sequence = 1;
    Envelope epoch_too_wide = base;
    epoch_too_wide.epoch = max_epoch + 1;
    epoch_too_wide.sequence = 2;
    Envelope oversized = base;
    oversized.payload.resize(4096);
    oversized.sequence = 3;
    Envelope stale = base;
    stale.epoch = 4;
    stale.sequence = 4;
    Envelope unknown = base;
    unknown.source = 9;
    unknown.sequence = 5;
    Envelope good = base;
    good.payload = {7};
    good.sequence = 6;

    ASSERT_EQ(hostile.send_unchecked(broadcast_source), SendResult::sent);
    ASSERT_EQ(hostile.send_unchecked(epoch_too_wide), SendResult::sent);
    ASSERT_EQ(hostile.send_unchecked(oversized), SendResult::sent);
    ASSERT_EQ(hostile.send(stale), SendResult::sent);
    ASSERT_EQ(stranger.send(unknown), SendResult::sent);
    ASSERT_EQ(hostile.send(good), SendResult::sent);

    const std::vector<Envelope> got = collect(receiver, 1);
    ASSERT_TRUE(eventually([&] {
        receiver.poll([](Envelope&&) { ADD_FAILURE() << "a bad sample was delivered"; });
        const TransportCounters counters = receiver.counters();
        // The broadcast source is not the node the writer speaks for: forged, not malformed.
        return counters.dropped_malformed == 1 && counters.dropped_forged_sender == 1 &&
               counters.dropped_oversized == 1 && counters.dropped_stale_epoch == 1 &&
               counters.dropped_unknown_sender == 1;
    }));
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].payload, std::vector<std::uint8_t>{7});
    EXPECT_EQ(receiver.counters().received, 1u);
}

// A participant that is not a DdsTransport: it writes KeelReliableData samples in the
// partitions it is given, with the fields it is given (what a hostile program on the domain
// can do without DDS Security).
class RawWriter {
public:
    RawWriter(std::uint32_t domain, std::vector<const char*> partitions) {
        participant_ = dds_create_participant(domain, nullptr, nullptr);
        dds_qos_t* qos = dds_create_qos();
        dds_qset_partition(qos, static_cast<uint32_t>(partitions.size()), partitions.data());
        const dds_entity_t publisher = dds_create_publisher(participant_, qos, nullptr);
        dds_delete_qos(qos);
        const dds_entity_t topic = dds_create_topic(participant_, &keel_wire_Message_desc,
                                                    "KeelReliableData", nullptr, nullptr);
        dds_qos_t* writer_qos = dds_create_qos();
        dds_qset_reliability(writer_qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
        dds_qset_history(writer_qos, DDS_HISTORY_KEEP_ALL, 0);
        dds_qset_destination_order(writer_qos, DDS_DESTINATIONORDER_BY_RECEPTION_TIMESTAMP);
        writer_ = dds_create_writer(publisher, topic, writer_qos, nullptr);
        dds_delete_qos(writer_qos);
    }
    ~RawWriter() { dds_delete(participant_); }
    RawWriter(const RawWriter&) = delete;
    RawWriter& operator=(const RawWriter&) = delete;

    bool ready() const { return participant_ > 0 && writer_ > 0; }
    bool matched() const {
        dds_publication_matched_status_t status{};
        return dds_get_publication_matched_status(writer_, &status) >= 0 && status.current_count > 0;
    }
    void write(NodeAddress source, Sequence sequence, std::uint8_t marker) {
        std::uint8_t payload[1] = {marker};
        keel_wire_Message sample{};
        sample.source = source;
        sample.destination = broadcast_address;
        sample.epoch = 5;
        sample.sequence_number = sequence;
        sample.payload._buffer = payload;
        sample.payload._length = sample.payload._maximum = 1;
        ASSERT_GE(dds_write(writer_, &sample), 0);
    }

private:
    dds_entity_t participant_ = 0;
    dds_entity_t writer_ = 0;
};

// A sample's sender is its writer's sender partition (keel.from.N), not the source field:
// a writer of node 3 that claims node 1 is forged; a writer in two sender partitions speaks
// for no one; and without DDS Security a second participant speaking for a node whose own
// participant is present is refused too (bound at discovery).
TEST(DdsTransport, ASampleSpeaksOnlyForTheNodeItsWriterSpeaksFor) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto receiver_owner = std::make_unique<DdsTransport>(config_for(2, domain));
    DdsTransport node1(config_for(1, domain));
    Endpoint receiver(std::move(receiver_owner), FilterConfig{.known_nodes = {1, 2, 3}});
    RawWriter three(domain, {"keel.from.3"});
    RawWriter both(domain, {"keel.from.3", "keel.from.1"});
    RawWriter impostor(domain, {"keel.from.1"});
    ASSERT_TRUE(three.ready() && both.ready() && impostor.ready());
    ASSERT_TRUE(node1.wait_for_peers(1, 20s));
    ASSERT_TRUE(eventually([&] { return three.matched() && both.matched() && impostor.matched(); }));

    Envelope real;
    real.kind = MessageKind::reliable_data;
    real.source = 1;
    real.destination = broadcast_address;
    real.epoch = 5;
    real.sequence = 1;
    real.payload = {1};
    ASSERT_EQ(node1.send(real), SendResult::sent);  // binds node 1 to its own participant
    ASSERT_EQ(collect(receiver, 1).size(), 1u);

    three.write(1, 10, 0xA);     // claims node 1 from node 3's partition
    both.write(3, 10, 0xB);      // two sender partitions
    impostor.write(1, 10, 0xC);  // node 1's partition, another participant
    three.write(3, 11, 0xD);     // node 3 speaking for itself: delivered
    const std::vector<Envelope> got = collect(receiver, 1);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].source, 3);
    EXPECT_EQ(got[0].payload, std::vector<std::uint8_t>{0xD});
    EXPECT_TRUE(eventually([&] {
        receiver.poll([](Envelope&&) { ADD_FAILURE() << "a forged sample was delivered"; });
        return receiver.counters().dropped_forged_sender == 3;
    }));
}

// Heartbeats and Commands are keyed by sender and keep the latest samples per instance, and
// the instance is the key its writer wrote. Node 3 writes heartbeats keyed as node 1 after
// each of node 1's own: through one reader of every sender partition (keyed_senders empty,
// as a tool reads), node 1's heartbeat is displaced before it is taken and only the forged
// one arrives, to be dropped; through a reader per sender (a node's protocol participant),
// node 3's samples land in node 3's reader and every heartbeat of node 1 is delivered.
TEST(DdsTransport, ANodesSamplesKeyedAsAnotherNodeNeverDisplaceThatNodesOwn) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport node1(config_for(1, domain));
    DdsTransport node3(config_for(3, domain));
    auto heartbeat = [](NodeAddress source, std::uint32_t seq) {
        Envelope envelope;
        envelope.kind = MessageKind::heartbeat;
        envelope.source = source;
        envelope.destination = broadcast_address;
        envelope.epoch = 3;
        envelope.sequence = seq;
        envelope.payload = fsm::encode(fsm::Heartbeat{static_cast<fsm::NodeId>(source), 3, 1,
                                                      false, seq, {}, false});
        return envelope;
    };
    // Returns how many of node 1's heartbeats node 2 took, and how many samples it dropped
    // as forged and as replayed, over 5 rounds of one real heartbeat and 20 keyed as node 1
    // by node 3.
    auto run = [&](std::vector<NodeAddress> keyed_senders, std::uint32_t first_seq) {
        DdsConfig config = config_for(2, domain);
        config.keyed_senders = std::move(keyed_senders);
        DdsTransport node2(config);
        // Each heartbeat writer matches node 2's reader and the other writer's node's.
        EXPECT_TRUE(node1.wait_for_peers(2, 20s));
        EXPECT_TRUE(node3.wait_for_peers(2, 20s));
        std::vector<Inbound> drain;
        node2.receive(drain, 1'000'000);
        std::size_t real = 0;
        std::size_t forged = 0;
        std::size_t replayed = 0;
        std::uint32_t forged_seq = first_seq * 100;
        for (std::uint32_t round = 0; round < 5; ++round) {
            EXPECT_EQ(node1.send(heartbeat(1, first_seq + round)), SendResult::sent);
            std::this_thread::sleep_for(20ms);
            for (int i = 0; i < 20; ++i) node3.send_unchecked(heartbeat(1, ++forged_seq));
            std::this_thread::sleep_for(100ms);  // a node's loop busy elsewhere
            std::vector<Inbound> got;
            node2.receive(got, 1'000'000);
            for (const Inbound& item : got) {
                if (item.ok && item.envelope.source == 1) ++real;
                if (!item.ok && item.error == EnvelopeError::forged_sender) ++forged;
                if (!item.ok && item.error == EnvelopeError::replayed) ++replayed;
            }
        }
        return std::tuple{real, forged, replayed};
    };
    const auto [shared_real, shared_forged, shared_replayed] = run({}, 10);
    EXPECT_EQ(shared_real, 0u) << "one reader of every sender: node 3 displaced node 1";
    EXPECT_GE(shared_forged, 1u);
    // Named twice, and node 2 itself: still one reader per other node, each sample once.
    const auto [own_real, own_forged, own_replayed] = run({1, 3, 1, 2}, 20);
    EXPECT_EQ(own_real, 5u);
    EXPECT_GE(own_forged, 1u);  // node 3's samples still arrive, in its own reader: dropped
    EXPECT_EQ(shared_replayed + own_replayed, 0u);
}

// The loop takes one batch from each sender's reader in turn: node 3 fills its own reader
// with 150 heartbeats keyed as other nodes (150 instances, one each), then node 1 sends one.
// A receive of at most 100 items delivers node 1's heartbeat whichever reader it starts
// with: the turn moves one reader per receive, and the second round drains once more, so
// the two rounds start at different readers. Draining node 3's reader first would not.
TEST(DdsTransport, ASendersFullReaderDelaysNoOtherSenderInOneReceive) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport node1(config_for(1, domain));
    DdsTransport node3(config_for(3, domain));
    DdsConfig config = config_for(2, domain);
    config.keyed_senders = {1, 3};
    DdsTransport node2(config);
    ASSERT_TRUE(node1.wait_for_peers(2, 20s));
    ASSERT_TRUE(node3.wait_for_peers(2, 20s));
    auto heartbeat = [](NodeAddress source, std::uint32_t seq) {
        return Envelope{MessageKind::heartbeat, source, broadcast_address, 0, 3, seq,
                        fsm::encode(fsm::Heartbeat{static_cast<fsm::NodeId>(source), 3, 1,
                                                   false, seq, {}, false})};
    };
    std::uint32_t seq = 0;
    for (int round = 0; round < 2; ++round) {
        std::vector<Inbound> drained;
        for (int drain = 0; drain <= round; ++drain) node2.receive(drained, 1'000'000);
        for (NodeAddress key = 100; key < 250; ++key) node3.send_unchecked(heartbeat(key, ++seq));
        ASSERT_EQ(node1.send(heartbeat(1, ++seq)), SendResult::sent);
        std::this_thread::sleep_for(200ms);
        std::vector<Inbound> got;
        node2.receive(got, 100);
        EXPECT_EQ(got.size(), 100u) << "round " << round;
        EXPECT_TRUE(std::ranges::any_of(got, [](const Inbound& item) {
            return item.ok && item.envelope.source == 1;
        })) << "round " << round << ": node 1's heartbeat waited behind node 3's reader";
    }
}

// A Master writes a switch's Commands one per member, in a burst, on its one sender key. A
// member whose loop takes them only after the burst still finds its own when KeelCommand's
// depth is command_history_for() the cluster; at the old fixed depth of 8, the burst to 20
// members displaced the first members' Commands (a 34-node cluster's switches waited a
// heartbeat period for the Master's retransmission).
TEST(DdsTransport, ABurstOfCommandsToEveryMemberDisplacesNoMembersOwn) {
    const std::uint32_t domain = domain_id_for(test_name());
    static constexpr int members = 20;
    auto burst_reaches_the_first_member = [&](std::int32_t depth) {
        DdsConfig master_config = config_for(1, domain);
        master_config.command_history_depth = depth;
        DdsConfig member_config = config_for(2, domain);
        member_config.command_history_depth = depth;
        member_config.keyed_senders = {1};
        DdsTransport master(master_config);
        DdsTransport member(member_config);
        EXPECT_TRUE(master.wait_for_peers(1, 20s));
        EXPECT_TRUE(member.wait_for_peers(1, 20s));
        std::this_thread::sleep_for(200ms);  // the Command reader matched, too
        static std::uint32_t seq = 0;
        for (NodeAddress to = 2; to < 2 + members; ++to) {
            EXPECT_EQ(master.send(Envelope{MessageKind::reconfiguration_command, 1, to, 0, 3, ++seq,
                                           fsm::encode(fsm::ActivateCommand{3, 9, to})}),
                      SendResult::sent);
        }
        std::vector<Inbound> got;
        const auto deadline = std::chrono::steady_clock::now() + 5s;
        while (std::chrono::steady_clock::now() < deadline) {
            member.wait(100ms);
            member.receive(got, 1000);
            if (std::ranges::any_of(got, [](const Inbound& item) {
                    return item.ok && item.envelope.destination == 2 + members - 1;
                })) {
                break;  // the burst's last Command is in: nothing more comes
            }
        }
        return std::ranges::any_of(got, [](const Inbound& item) {
            return item.ok && item.envelope.destination == 2;
        });
    };
    EXPECT_GE(command_history_for(members + 1), 2 * members);
    EXPECT_TRUE(burst_reaches_the_first_member(command_history_for(members + 1)));
    // The witness: at a depth below the burst, the first member's Command is displaced.
    EXPECT_FALSE(burst_reaches_the_first_member(8));
    EXPECT_EQ(command_history_for(2), 8);
    EXPECT_EQ(command_history_for(256), max_command_history);
}

// A Command for several members is one sample (send_to_each): each member listed takes it
// once, addressed to itself; a node not listed takes it as addressed to another node (the
// endpoint then ignores it); a tool sees it for broadcast. The member's reader takes one
// sample where one per member used to arrive.
TEST(DdsTransport, ACommandForSeveralMembersIsOneSampleEachTakesAsItsOwn) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport master(config_for(1, domain));
    DdsTransport member(config_for(5, domain));
    DdsTransport outsider(config_for(9, domain));
    DdsConfig tool_config = config_for(30, domain);
    tool_config.read_only = true;
    DdsTransport tool(tool_config);
    ASSERT_TRUE(master.wait_for_peers(2, 20s));
    ASSERT_TRUE(member.wait_for_peers(2, 20s));
    ASSERT_TRUE(outsider.wait_for_peers(2, 20s));
    std::this_thread::sleep_for(200ms);  // the tool's readers matched, too
    const std::vector<std::uint8_t> payload = fsm::encode(fsm::ActivateCommand{1, 3, 2});
    const Envelope command{MessageKind::reconfiguration_command, 1, broadcast_address, 0, 3, 41, payload};
    const std::vector<NodeAddress> members{2, 5, 7};
    ASSERT_EQ(master.send_to_each(command, members), SendResult::sent);
    EXPECT_EQ(master.counters().sent, 1u);  // one sample
    auto first_command = [](DdsTransport& transport) -> std::optional<Envelope> {
        const auto deadline = std::chrono::steady_clock::now() + 5s;
        while (std::chrono::steady_clock::now() < deadline) {
            transport.wait(100ms);
            std::vector<Inbound> items;
            transport.receive(items, 1000);
            for (Inbound& item : items) {
                if (item.ok && item.envelope.kind == MessageKind::reconfiguration_command) {
                    return std::move(item.envelope);
                }
            }
        }
        return std::nullopt;
    };
    const auto mine = first_command(member);
    ASSERT_TRUE(mine.has_value());
    EXPECT_EQ(mine->destination, 5u);
    EXPECT_EQ(mine->sequence, 41u);
    EXPECT_EQ(mine->payload, payload);
    EXPECT_EQ(member.counters().received, 1u);
    const auto theirs = first_command(outsider);
    ASSERT_TRUE(theirs.has_value());
    EXPECT_EQ(theirs->destination, 2u);  // another node's: the endpoint ignores it
    const auto seen = first_command(tool);
    ASSERT_TRUE(seen.has_value());
    EXPECT_EQ(seen->destination, broadcast_address);
    // A list naming broadcast is refused; one destination is an ordinary send.
    EXPECT_EQ(master.send_to_each(command, std::vector<NodeAddress>{2, broadcast_address}),
              SendResult::rejected_invalid);
    Envelope single = command;
    single.sequence = 42;
    ASSERT_EQ(master.send_to_each(single, std::vector<NodeAddress>{5}), SendResult::sent);
    const auto alone = first_command(member);
    ASSERT_TRUE(alone.has_value());
    EXPECT_EQ(alone->destination, 5u);
}

// Keel's writers offer no liveliness lease of their own: DDS then announces no writer's
// liveliness to every participant a few times a lease (ParticipantMessageData, reliable,
// N^2 a period: a quarter of a 16-node cluster's CPU at rest), and Keel's heartbeats say
// whether a node lives. Read from DDS's own list of publications, as any DDS tool would.
TEST(DdsTransport, KeelsWritersOfferNoLivelinessLeaseOfTheirOwn) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport node(config_for(1, domain));
    const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
    ASSERT_GT(participant, 0);
    const dds_entity_t publications =
        dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
    ASSERT_GT(publications, 0);
    std::map<std::string, dds_duration_t> leases;
    eventually([&] {
        std::array<void*, 64> samples{};
        std::array<dds_sample_info_t, 64> infos{};
        const dds_return_t count = dds_read(publications, samples.data(), infos.data(), 64, 64);
        for (dds_return_t i = 0; i < count; ++i) {
            if (!infos[static_cast<std::size_t>(i)].valid_data) continue;
            const auto* endpoint =
                static_cast<const dds_builtintopic_endpoint_t*>(samples[static_cast<std::size_t>(i)]);
            dds_liveliness_kind_t kind{};
            dds_duration_t lease = DDS_INFINITY;
            dds_qget_liveliness(endpoint->qos, &kind, &lease);
            leases[endpoint->topic_name] = lease;
        }
        if (count > 0) dds_return_loan(publications, samples.data(), count);
        return leases.contains("KeelHeartbeat") && leases.contains("KeelNodeState") &&
               leases.contains("KeelCommand");
    }, 10s);
    ASSERT_TRUE(leases.contains("KeelHeartbeat"));
    ASSERT_TRUE(leases.contains("KeelNodeState"));
    for (const auto& [topic, lease] : leases) {
        if (topic.starts_with("Keel")) {
            EXPECT_EQ(lease, DDS_INFINITY) << topic;
        }
    }
    dds_delete(participant);
}

// A writer's sequence numbers only grow: the same message again, or an older one, is a
// replay and is dropped and counted; the next new one is delivered.
TEST(DdsTransport, ACapturedMessageSentAgainIsRefusedAsAReplay) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto receiver_owner = std::make_unique<DdsTransport>(config_for(2, domain));
    Endpoint receiver(std::move(receiver_owner), FilterConfig{.known_nodes = {2, 3}});
    RawWriter three(domain, {"keel.from.3"});
    ASSERT_TRUE(three.ready());
    ASSERT_TRUE(eventually([&] { return three.matched(); }));
    three.write(3, 100, 1);
    three.write(3, 100, 2);  // the same sequence number again
    three.write(3, 99, 3);   // an older one
    three.write(3, 101, 4);
    const std::vector<Envelope> got = collect(receiver, 2);
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0].payload, std::vector<std::uint8_t>{1});
    EXPECT_EQ(got[1].payload, std::vector<std::uint8_t>{4});
    EXPECT_EQ(receiver.counters().dropped_replayed, 2u);
    EXPECT_EQ(receiver.counters().dropped_forged_sender, 0u);
}

// Without DDS Security, a node is bound to the participant that first spoke for it; once
// that participant is gone (the node restarted), the new one takes its place.
TEST(DdsTransport, ARestartedNodesNewParticipantSpeaksForItOnceTheOldOneIsGone) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto receiver_owner = std::make_unique<DdsTransport>(config_for(2, domain));
    Endpoint receiver(std::move(receiver_owner), FilterConfig{.known_nodes = {1, 2}});
    Envelope message;
    message.kind = MessageKind::reliable_data;
    message.source = 1;
    message.destination = broadcast_address;
    message.epoch = 5;
    for (std::uint8_t incarnation = 1; incarnation <= 2; ++incarnation) {
        DdsTransport node1(config_for(1, domain));
        ASSERT_TRUE(node1.wait_for_peers(1, 20s));
        message.sequence = 1;  // a new process counts from 1 again: a new writer, no replay
        message.payload = {incarnation};
        ASSERT_EQ(node1.send(message), SendResult::sent);
        const std::vector<Envelope> got = collect(receiver, 1);
        ASSERT_EQ(got.size(), 1u) << "incarnation " << int{incarnation};
        EXPECT_EQ(got[0].payload, std::vector<std::uint8_t>{incarnation});
    }
    EXPECT_EQ(receiver.counters().dropped_forged_sender, 0u);
    EXPECT_EQ(receiver.counters().dropped_replayed, 0u);
}

// DDS drops a sample above the domain's maximum sample size before reassembly, so no peer
// makes a node hold it; a sample within it is delivered.
TEST(DdsTransport, ASampleAboveTheMaximumSampleSizeIsNeverDelivered) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsConfig receiver_config = config_for(2, domain);
    receiver_config.max_sample_bytes = 4096;
    DdsConfig sender_config = config_for(1, domain);
    sender_config.max_sample_bytes = 4096;  // one process, one domain configuration
    auto receiver_owner = std::make_unique<DdsTransport>(receiver_config);
    DdsTransport sender(sender_config);
    Endpoint receiver(std::move(receiver_owner), FilterConfig{.known_nodes = {1, 2}});
    ASSERT_TRUE(sender.wait_for_peers(1, 20s));
    Envelope big;
    big.kind = MessageKind::unreliable_data;
    big.source = 1;
    big.destination = broadcast_address;
    big.epoch = 5;
    big.sequence = 1;
    big.payload.assign(8000, 0xAB);
    Envelope small = big;
    small.sequence = 2;
    small.payload.assign(1000, 0xCD);
    sender.send(big);  // refused by DDS, on either side
    ASSERT_EQ(sender.send(small), SendResult::sent);
    // The big one, sent first, would arrive first: the first delivered is the small one,
    // and nothing follows.
    const std::vector<Envelope> got = collect(receiver, 1);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].payload.size(), 1000u);
    EXPECT_FALSE(eventually([&] {
        bool more = false;
        receiver.poll([&](Envelope&&) { more = true; });
        return more;
    }, 500ms));
}

// PN1's state as the node-state tests publish it.
NodeState pn1_state() {
    return NodeState{.node = 1,
                     .name = "PN1",
                     .role = Role::master,
                     .epoch = 3,
                     .configuration_id = 2,
                     .configuration = "C2",
                     .phase = "observation"};
}

// Whether `transport` reads `state` on KeelNodeState.
bool sees(DdsTransport& transport, const NodeState& state) {
    for (const NodeState& seen : transport.node_states()) {
        if (seen == state) return true;
    }
    return false;
}

TEST(DdsTransport, NodeStateReachesLateJoinersAndHeartbeatDeadlinesAreCounted) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsTransport one(config_for(1, domain));
    const NodeState state = pn1_state();
    one.publish_node_state(state);
    // Node 2 joins after the state was published: transient-local durability delivers it.
    DdsTransport two(config_for(2, domain));
    ASSERT_TRUE(eventually([&] { return sees(two, state); }));
    ASSERT_TRUE(one.wait_for_peers(1, 20s));
    Envelope heartbeat;
    heartbeat.kind = MessageKind::heartbeat;
    heartbeat.source = 1;
    heartbeat.payload = payload_for(MessageKind::heartbeat, {});
    ASSERT_EQ(one.send(heartbeat), SendResult::sent);
    // Node 1 falls silent: the reader's deadline (period x miss limit = 40 ms) expires.
    EXPECT_TRUE(eventually([&] { return two.counters().deadline_missed >= 1; }));
}

// An observer (keel-observe): it reads what the nodes publish, its own state and its
// messages are never written, and it creates no writer a peer could match.
TEST(DdsTransport, AReadOnlyObserverReadsAndWritesNothing) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsConfig node_config = config_for(1, domain);
    const auto node_period_for_test = node_config.heartbeat_period;
    DdsTransport node(node_config);
    DdsConfig observing = config_for(900, domain);
    observing.read_only = true;
    // A lease shorter than the node's: an observer's readers ask for none, so they match.
    observing.heartbeat_period = node_period_for_test / 2;
    DdsTransport observer(observing);
    const NodeState state = pn1_state();
    node.publish_node_state(state);
    ASSERT_TRUE(eventually([&] { return sees(observer, state); }));
    Envelope heartbeat;
    heartbeat.kind = MessageKind::heartbeat;
    heartbeat.source = 1;
    heartbeat.payload = payload_for(MessageKind::heartbeat, {});
    ASSERT_TRUE(eventually([&] {
        node.send(heartbeat);
        std::vector<Inbound> got;
        observer.receive(got, 16);
        return std::any_of(got.begin(), got.end(), [](const Inbound& in) {
            return in.ok && in.envelope.source == 1 && in.envelope.kind == MessageKind::heartbeat;
        });
    }));
    // Nothing it would say leaves it: the node sees no state of its, and no heartbeat.
    Envelope own = heartbeat;
    own.source = 900;
    EXPECT_EQ(observer.send(own), SendResult::rejected_invalid);
    EXPECT_EQ(observer.send_unchecked(own), SendResult::rejected_invalid);
    observer.publish_node_state(NodeState{.node = 900, .name = "observer"});
    std::this_thread::sleep_for(300ms);
    for (const NodeState& seen : node.node_states()) EXPECT_NE(seen.node, 900);
    std::vector<Inbound> heard;
    node.receive(heard, 64);
    for (const Inbound& in : heard) {
        if (in.ok) {
            EXPECT_NE(in.envelope.source, 900);
        }
    }
    EXPECT_EQ(observer.counters().send_failed, 2u);  // send() and the state (send_unchecked counts nothing)
}

// What a generic DDS tool does: a plain volatile reader on KeelNodeState, created after the
// node published its state. It still sees the state, because the node writes it again
// with its heartbeats.
TEST(DdsTransport, NodeStateReachesVolatileToolReadersThroughRefresh) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsConfig config = config_for(1, domain);
    config.node_state_refresh = 30ms;
    DdsTransport node(config);
    node.publish_node_state(NodeState{.node = 1, .name = "PN1", .role = Role::worker});

    const dds_entity_t participant = dds_create_participant(domain, nullptr, nullptr);
    ASSERT_GT(participant, 0);
    const dds_entity_t topic = dds_create_topic(participant, &keel_wire_NodeState_desc,
                                                node_state_topic_name, nullptr, nullptr);
    ASSERT_GT(topic, 0);
    // A tool's reader in the default partition sees the node's state (its writer is in the
    // node's sender partition and the default one).
    const dds_entity_t reader = dds_create_reader(participant, topic, nullptr, nullptr);
    ASSERT_GT(reader, 0);
    Envelope heartbeat;
    heartbeat.kind = MessageKind::heartbeat;
    heartbeat.source = 1;
    heartbeat.payload = payload_for(MessageKind::heartbeat, {});
    std::string seen_name;
    EXPECT_TRUE(eventually([&] {
        node.send(heartbeat);
        void* samples[1] = {nullptr};
        dds_sample_info_t info;
        const dds_return_t count = dds_take(reader, samples, &info, 1, 1);
        if (count == 1 && info.valid_data) {
            seen_name = static_cast<const keel_wire_NodeState*>(samples[0])->name;
        }
        if (count > 0) dds_return_loan(reader, samples, count);
        return !seen_name.empty();
    }));
    EXPECT_EQ(seen_name, "PN1");
    EXPECT_EQ(dds_delete(participant), DDS_RETCODE_OK);
}

// Garbage on the domain's UDP ports of 127.0.0.1 (random bytes, and RTPS headers followed by
// random submessages): Cyclone rejects what does not parse before any reader sees it, the
// node keeps running, and the next good message is delivered, alone.
TEST(DdsTransport, GarbageDatagramsOnTheDomainPortsNeitherCrashNorDeliver) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto one = std::make_unique<DdsTransport>(config_for(1, domain));
    auto two = std::make_unique<DdsTransport>(config_for(2, domain));
    ASSERT_TRUE(one->wait_for_peers(1, 20s));
    const FilterConfig filter{.known_nodes = {1, 2}};
    Endpoint sender(std::move(one), filter);
    Endpoint receiver(std::move(two), filter);

    const int sock = ::socket(AF_INET, SOCK_DGRAM, 0);
    ASSERT_GE(sock, 0);
    std::mt19937_64 random(domain);
    // RTPS ports of a domain: 7400 + 250 * domain + offsets below 100 (DDSI-RTPS 9.6.1.1).
    const int base_port = 7400 + 250 * static_cast<int>(domain);
    for (int datagram = 0; datagram < 3000; ++datagram) {
        std::vector<std::uint8_t> bytes(8 + random() % 300);
        for (auto& byte : bytes) byte = static_cast<std::uint8_t>(random());
        if (datagram % 2 == 0 && bytes.size() >= 20) {
            const std::uint8_t header[] = {'R', 'T', 'P', 'S', 2, 1, 1, 16};
            std::copy(std::begin(header), std::end(header), bytes.begin());
        }
        sockaddr_in address{};
        address.sin_family = AF_INET;
        address.sin_port = htons(static_cast<std::uint16_t>(base_port + datagram % 100));
        address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        ::sendto(sock, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&address),
                 sizeof(address));
    }
    ::close(sock);

    ASSERT_EQ(sender.send(sender.make_envelope(MessageKind::reliable_data, 2, 5, {9, 9})),
              SendResult::sent);
    const auto got = collect(receiver, 1);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].payload, (std::vector<std::uint8_t>{9, 9}));
    std::this_thread::sleep_for(100ms);
    receiver.poll([](Envelope&&) { ADD_FAILURE() << "garbage became a message"; });
    EXPECT_EQ(receiver.counters().received, 1u);
}

TEST(DdsTransport, FaultDecoratorPartitionsRealDds) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto plan = std::make_shared<FaultPlan>();
    auto one = std::make_unique<DdsTransport>(config_for(1, domain));
    auto two = std::make_unique<DdsTransport>(config_for(2, domain));
    ASSERT_TRUE(one->wait_for_peers(1, 20s));
    const FilterConfig filter{.known_nodes = {1, 2}};
    Endpoint sender(std::move(one), filter);
    Endpoint receiver(std::make_unique<FaultTransport>(std::move(two), FaultConfig{.plan = plan}),
                      filter);
    plan->block(1, 2);
    ASSERT_EQ(sender.send(sender.make_envelope(MessageKind::reliable_data, 2, 1, {1})),
              SendResult::sent);
    ASSERT_TRUE(eventually([&] {
        receiver.poll([](Envelope&&) { ADD_FAILURE() << "delivered across a partition"; });
        return receiver.counters().fault_partitioned == 1;
    }));
    plan->heal();
    ASSERT_EQ(sender.send(sender.make_envelope(MessageKind::reliable_data, 2, 1, {2})),
              SendResult::sent);
    const auto got = collect(receiver, 1);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].payload, std::vector<std::uint8_t>{2});
}

// The guard condition on the waitset: wake() ends a wait with a minute's timeout (checked
// well before it), through the fault decorator and the Endpoint as the node uses it.
TEST(DdsTransport, WakeEndsAWaitThroughTheDecoratorAndIsConsumed) {
    const std::uint32_t domain = domain_id_for(test_name());
    Endpoint endpoint(std::make_unique<FaultTransport>(
                          std::make_unique<DdsTransport>(config_for(1, domain)), FaultConfig{}),
                      FilterConfig{.known_nodes = {1}});
    for (int round = 0; round < 3; ++round) {
        auto waiting = std::async(std::launch::async, [&] { return endpoint.wait(60s); });
        endpoint.wake();
        ASSERT_EQ(waiting.wait_for(30s), std::future_status::ready)
            << "wait() did not return after wake() in round " << round;
        EXPECT_TRUE(waiting.get());
    }
    EXPECT_FALSE(endpoint.wait(0ms)) << "one wake-up ends one wait";
}

// Addressed kinds: a sample travels in its destination's DDS partition, so DDS delivers it
// to that node's participant only (no other node takes, copies and drops it); broadcasts
// reach every node; a participant that does not carry a kind neither sends nor reads it.
TEST(DdsTransport, AddressedKindsReachTheirDestinationOnly) {
    const std::uint32_t domain = domain_id_for(test_name());
    auto addressed = [&](NodeAddress address) {
        DdsConfig config = config_for(address, domain);
        config.kinds = {MessageKind::unreliable_data, MessageKind::large};
        config.addressed_kinds = config.kinds;
        config.addressed_destinations = {1, 2, 3};
        return std::make_unique<DdsTransport>(config);
    };
    DdsConfig protocol_only = config_for(4, domain);
    protocol_only.kinds = {MessageKind::heartbeat, MessageKind::acknowledgement};
    auto one = addressed(1);
    auto two = addressed(2);
    auto three = addressed(3);
    auto four = std::make_unique<DdsTransport>(protocol_only);
    ASSERT_TRUE(one->wait_for_peers(2, 20s));
    ASSERT_TRUE(four->wait_for_peers(0, 20s));
    const FilterConfig filter{.known_nodes = {1, 2, 3, 4}};
    Endpoint sender(std::move(one), filter);
    Endpoint to_two(std::move(two), filter);
    Endpoint to_three(std::move(three), filter);
    Endpoint bystander(std::move(four), filter);

    const std::vector<std::uint8_t> scene(1 << 20, 0x5A);
    ASSERT_EQ(sender.send(sender.make_envelope(MessageKind::large, 2, 9, scene)), SendResult::sent);
    const auto at_two = collect(to_two, 1);
    ASSERT_EQ(at_two.size(), 1u);
    EXPECT_EQ(at_two[0].payload.size(), scene.size());
    ASSERT_EQ(sender.send(sender.make_envelope(MessageKind::large, 3, 9, {7})), SendResult::sent);
    const auto at_three = collect(to_three, 1);
    ASSERT_EQ(at_three.size(), 1u);
    EXPECT_EQ(at_three[0].payload, std::vector<std::uint8_t>{7});
    // Node 3's participant never took node 2's megabyte.
    EXPECT_EQ(to_three.counters().ignored_not_addressed, 0u);
    EXPECT_LT(to_three.counters().received_bytes, scene.size());
    EXPECT_GE(to_two.counters().received_bytes, scene.size());

    // A broadcast's writer is made on first use; best effort, so send until both have one.
    std::size_t two_got = 0, three_got = 0;
    ASSERT_TRUE(eventually([&] {
        sender.send(sender.make_envelope(MessageKind::unreliable_data, broadcast_address, 9, {1}));
        std::this_thread::sleep_for(20ms);
        two_got += to_two.poll([](Envelope&&) {});
        three_got += to_three.poll([](Envelope&&) {});
        return two_got > 0 && three_got > 0;
    }));

    // The protocol-only participant carries no sample kind: it sends none and reads none.
    EXPECT_EQ(bystander.send(bystander.make_envelope(MessageKind::large, 1, 9, {1})),
              SendResult::rejected_invalid);
    EXPECT_EQ(bystander.poll([](Envelope&&) {}), 0u);
    EXPECT_EQ(bystander.counters().received_bytes, 0u);
}

TEST(DdsTransport, RefusesAddressedKindsItDoesNotCarryOrThatCannotBeAddressed) {
    const std::uint32_t domain = domain_id_for(test_name());
    DdsConfig config = config_for(1, domain);
    config.kinds = {MessageKind::large};
    config.addressed_kinds = {MessageKind::unreliable_data};
    EXPECT_THROW(DdsTransport{config}, std::invalid_argument);
    config.kinds.clear();
    config.addressed_kinds = {MessageKind::heartbeat};
    EXPECT_THROW(DdsTransport{config}, std::invalid_argument);
    EXPECT_EQ(addressed_partition(7), "keel.node.7");
    EXPECT_EQ(addressed_partition(broadcast_address), "keel.broadcast");
}

}  // namespace
}  // namespace keel::net::dds

namespace keel::net::dds {
namespace {

std::vector<std::uint8_t> serialized(bool little_endian, std::uint8_t identifier,
                                     std::uint32_t declared_length,
                                     const std::vector<std::uint8_t>& payload) {
    std::vector<std::uint8_t> bytes = {0, identifier, 0, 0};
    auto put = [&](std::uint64_t value, int width) {
        for (int i = 0; i < width; ++i) {
            const int shift = little_endian ? 8 * i : 8 * (width - 1 - i);
            bytes.push_back(static_cast<std::uint8_t>(value >> shift));
        }
    };
    put(3, 2);           // source
    put(0xFFFF, 2);      // destination: every node
    put(0x1234, 2);      // port
    put(0, 2);           // CDR's padding before the epoch
    put(0xABCDE, 4);     // epoch
    put(0xCAFEF00D, 4);  // sequence
    put(declared_length, 4);
    bytes.insert(bytes.end(), payload.begin(), payload.end());
    return bytes;
}

TEST(ParseSerializedMessage, ReadsBothByteOrdersAndBothCdrVersions) {
    const std::vector<std::uint8_t> payload = {1, 2, 3, 4, 5};
    for (const auto& [identifier, little] :
         std::vector<std::pair<std::uint8_t, bool>>{{0, false}, {1, true}, {6, false}, {7, true}}) {
        const auto bytes = serialized(little, identifier, 5, payload);
        const Inbound item = parse_serialized_message(bytes, MessageKind::request, {});
        ASSERT_TRUE(item.ok) << item.detail;
        EXPECT_EQ(item.envelope.kind, MessageKind::request);
        EXPECT_EQ(item.envelope.source, 3);
        EXPECT_EQ(item.envelope.destination, broadcast_address);
        EXPECT_EQ(item.envelope.port, 0x1234);
        EXPECT_EQ(item.envelope.epoch, 0xABCDEu);
        EXPECT_EQ(item.envelope.sequence, 0xCAFEF00Du);
        EXPECT_EQ(item.envelope.payload, payload);
    }
    // CDR may pad the sample to a multiple of 4 after the payload.
    auto padded = serialized(true, 1, 5, payload);
    padded.insert(padded.end(), {0, 0, 0});
    EXPECT_EQ(parse_serialized_message(padded, MessageKind::request, {}).envelope.payload, payload);
}

TEST(ParseSerializedMessage, RejectsTruncatedOversizedAndUnknownEncapsulations) {
    const std::vector<std::uint8_t> payload(100, 7);
    const auto good = serialized(true, 1, 100, payload);
    for (std::size_t cut = 0; cut < good.size(); ++cut) {
        const Inbound item = parse_serialized_message(std::span(good.data(), cut),
                                                      MessageKind::large, {});
        ASSERT_FALSE(item.ok) << cut;
        EXPECT_EQ(item.error, EnvelopeError::truncated);
    }
    const auto huge = serialized(true, 1, 0xFFFFFFF0u, {});
    EXPECT_EQ(parse_serialized_message(huge, MessageKind::large, {}).error,
              EnvelopeError::oversized);
    EXPECT_EQ(parse_serialized_message(good, MessageKind::large, EnvelopeLimits{99}).error,
              EnvelopeError::oversized);
    for (std::uint8_t identifier : std::vector<std::uint8_t>{2, 3, 8, 9, 11}) {
        EXPECT_EQ(parse_serialized_message(serialized(true, identifier, 100, payload),
                                           MessageKind::large, {})
                      .error,
                  EnvelopeError::bad_version);
    }
}

TEST(ParseSerializedMessage, RandomBytesNeverCrash) {
    std::mt19937_64 random(7);
    std::size_t accepted = 0;
    for (int round = 0; round < 20000; ++round) {
        std::vector<std::uint8_t> bytes;
        if (round % 2 == 0) {
            bytes.resize(random() % 64);
            for (auto& byte : bytes) byte = static_cast<std::uint8_t>(random());
        } else {
            // A good sample with a few flipped bits, sometimes cut short.
            bytes = serialized(true, 1, 12, std::vector<std::uint8_t>(12, 5));
            for (int flip = 0; flip < 2; ++flip) {
                bytes[random() % bytes.size()] ^= static_cast<std::uint8_t>(1u << (random() % 8));
            }
            if (random() % 4 == 0) bytes.resize(random() % (bytes.size() + 1));
        }
        const Inbound item = parse_serialized_message(bytes, MessageKind::reliable_data, {});
        if (item.ok) {
            ++accepted;
            EXPECT_LE(item.envelope.payload.size() + 24, bytes.size());
        } else {
            EXPECT_FALSE(item.detail.empty());
        }
    }
    EXPECT_GT(accepted, 0u);
}

}  // namespace
}  // namespace keel::net::dds
