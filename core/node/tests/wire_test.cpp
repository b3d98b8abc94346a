#include "core/node/wire.hpp"

#include "core/fsm/codec.hpp"
#include "core/node/data_plane.hpp"

#include <numeric>
#include <algorithm>

#include <gtest/gtest.h>

namespace keel::node {
namespace {

TEST(Wire, SampleRoundTrip) {
    tasking::Sample sample;
    sample.type_id = 7;
    sample.sequence = 42;
    sample.timestamp_ns = -5;
    sample.payload = tasking::make_payload({1, 2, 3});
    const auto bytes = encode_sample(sample);
    const auto decoded = decode_sample(bytes, 100);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded->type_id, 7u);
    EXPECT_EQ(decoded->sequence, 42u);
    EXPECT_EQ(decoded->timestamp_ns, -5);
    EXPECT_EQ(decoded->source_port, 100);
    EXPECT_EQ(*decoded->payload, (std::vector<std::uint8_t>{1, 2, 3}));
}

TEST(Wire, TruncatedSampleIsRefused) {
    tasking::Sample sample;
    sample.payload = tasking::make_payload({});
    auto bytes = encode_sample(sample);
    for (std::size_t size = 0; size < bytes.size(); ++size) {
        EXPECT_FALSE(decode_sample(std::span(bytes.data(), size), 1)) << size;
    }
}

TEST(Wire, SnapshotRoundTrip) {
    tasking::Snapshot snapshot{"taskB", 9, 3, {4, 5}};
    const auto decoded = decode_snapshot(encode_snapshot(snapshot), "taskB");
    ASSERT_TRUE(decoded);
    EXPECT_EQ(*decoded, snapshot);
    EXPECT_FALSE(decode_snapshot(std::vector<std::uint8_t>{1, 2, 3}, "taskB"));
}

fsm::NodeSet nodes(std::initializer_list<fsm::NodeId> ids) {
    fsm::NodeSet set;
    for (fsm::NodeId id : ids) set.insert(id);
    return set;
}

TEST(Wire, ViewRoundTripAndExactLength) {
    fsm::View view{3, 4, 2, 1, 5, nodes({1, 3})};
    auto bytes = encode_view(view);
    EXPECT_EQ(bytes.size(), 23u);  // 15, and one word of failed nodes
    const auto decoded = decode_view(bytes);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(*decoded, view);
    bytes.push_back(0);
    std::string why;
    EXPECT_FALSE(decode_view(bytes, &why));
    EXPECT_EQ(why, "1 bytes after the view");
    bytes.resize(10);
    EXPECT_FALSE(decode_view(bytes, &why));
    EXPECT_EQ(why, "input ends inside view.base");
}

TEST(Wire, AViewOfTheFullCapacityRoundTrips) {
    fsm::View view{3, 4, 2, 1, 255, nodes({0, 63, 64, 255})};
    const auto bytes = encode_view(view);
    EXPECT_EQ(bytes.size(), 15u + 32u);
    EXPECT_EQ(decode_view(bytes), view);
    const fsm::View none{1, 0, 0, 0, fsm::kNoNode, {}};
    EXPECT_EQ(encode_view(none).size(), 15u);
    EXPECT_EQ(decode_view(encode_view(none)), none);
}

// The persisted view of Keel before its capacity grew (StateDb's view format 1).
TEST(Wire, AViewOfFormatOneIsRead) {
    const std::vector<std::uint8_t> bytes = {0, 0, 0, 3, 0, 0, 0, 4, 0, 2, 0, 1, 5,
                                             0, 0, 0, 0, 0, 0, 0, 0b1010};
    EXPECT_EQ(decode_view_format1(bytes), (fsm::View{3, 4, 2, 1, 5, nodes({1, 3})}));
    std::vector<std::uint8_t> no_master = bytes;
    no_master[12] = 0xFF;
    EXPECT_EQ(decode_view_format1(no_master)->master, fsm::kNoNode);
    EXPECT_FALSE(decode_view_format1(std::span(bytes.data(), 20)));
}

// The protocol participant admits the largest protocol message the capacity allows, and
// nothing larger; the data plane keeps the network layer's own bound (scenes of tens of MB).
fsm::Heartbeat reply_to_a_heartbeat() {
    fsm::Heartbeat reply;
    reply.reply = true;
    return reply;
}

TEST(Wire, TheProtocolParticipantsLimitDerivesFromTheCapacity) {
    const net::dds::DdsConfig protocol = protocol_dds_config({}, {0, 1, 2});
    EXPECT_EQ(protocol.limits.max_payload_bytes, fsm::kMaxMessageBytes);
    EXPECT_GE(protocol.limits.max_payload_bytes, fsm::kMaxHeartbeatBytes);
    EXPECT_GE(protocol.limits.max_payload_bytes, fsm::kMaxCommandBytes);
    EXPECT_EQ(protocol.max_sample_bytes, net::dds::max_sample_bytes_for(fsm::kMaxMessageBytes));
    // The kinds of checkpoint writes, requests (checkpoint and phase), replies and
    // acknowledgements, and only they, go to their destination alone: a monitor's reply to
    // a heartbeat reaches that heartbeat's sender, not every node (N^2 a period).
    EXPECT_EQ(protocol.addressed_kinds,
              (std::vector{net::MessageKind::reliable_data, net::MessageKind::request,
                           net::MessageKind::response, net::MessageKind::acknowledgement}));
    // Heartbeats and Commands are read through a reader per node of the mission, so no
    // node's samples keyed as another displace that node's own.
    EXPECT_EQ(protocol.keyed_senders, (std::vector<net::NodeAddress>{0, 1, 2}));
    for (const fsm::Message& message :
         {fsm::Message{fsm::CheckpointWrite{}}, fsm::Message{fsm::CheckpointReply{}},
          fsm::Message{fsm::CheckpointRequest{}}, fsm::Message{fsm::PhaseRequest{}},
          fsm::Message{fsm::Ack{}}, fsm::Message{fsm::CheckpointAck{}},
          fsm::Message{reply_to_a_heartbeat()}}) {
        EXPECT_NE(std::ranges::find(protocol.addressed_kinds, kind_of(message)),
                  protocol.addressed_kinds.end());
    }
    EXPECT_EQ(protocol.addressed_destinations, (std::vector<net::NodeAddress>{0, 1, 2}));
    // A Master's Commands and Activates to every member of a 34-node cluster fit KeelCommand's
    // history of its sender: none displaces another before the member's loop takes it.
    std::vector<net::NodeAddress> cluster(34);
    std::iota(cluster.begin(), cluster.end(), net::NodeAddress{0});
    EXPECT_GE(protocol_dds_config({}, cluster).command_history_depth, 2 * 34);
    EXPECT_EQ(protocol.command_history_depth, 8);
    const net::dds::DdsConfig data = data_plane_dds_config({}, {0, 255}, 117);
    EXPECT_EQ(data.limits.max_payload_bytes, net::default_max_payload_bytes);
    EXPECT_EQ(data.domain_id, 117u);
    EXPECT_EQ(data.max_sample_bytes, 0u);  // the network layer's default bound
}

// When every checkpointed task states its max_state_bytes, the protocol's domain admits no
// checkpoint with a larger state, but never less than the largest heartbeat, command or
// typed sample; a checkpointed task without it keeps the capacity's 16 MiB, and tasks that
// are not checkpointed do not count.
TEST(Wire, TheProtocolsLimitFollowsTheMissionsLargestStatedState) {
    mission::Mission stated;
    stated.tasks.resize(3);
    stated.tasks[0].checkpoint = true;
    stated.tasks[0].max_state_bytes = 1000;
    stated.tasks[1].checkpoint = true;
    stated.tasks[1].max_state_bytes = 4 * 1024 * 1024;
    ASSERT_EQ(largest_stated_state(stated), std::optional<std::size_t>(4 * 1024 * 1024));
    const net::dds::DdsConfig large = protocol_dds_config({}, {0, 1}, largest_stated_state(stated));
    EXPECT_EQ(large.limits.max_payload_bytes,
              fsm::kCheckpointOverheadBytes + fsm::kSnapshotHeaderBytes + 4u * 1024 * 1024);
    EXPECT_EQ(large.max_sample_bytes, net::dds::max_sample_bytes_for(large.limits.max_payload_bytes));
    EXPECT_NE(net::dds::domain_config_xml(large).find(
                  "<MaxSampleSize>" + std::to_string(large.max_sample_bytes) + "B</MaxSampleSize>"),
              std::string::npos);
    // Small states: the largest heartbeat or command bounds the payload, the typed samples'
    // bound the sample.
    stated.tasks[1].max_state_bytes = 16;
    const net::dds::DdsConfig small = protocol_dds_config({}, {0, 1}, largest_stated_state(stated));
    EXPECT_EQ(small.limits.max_payload_bytes,
              std::max({fsm::kMaxHeartbeatBytes, fsm::kMaxCommandBytes,
                        fsm::kCheckpointOverheadBytes + fsm::kSnapshotHeaderBytes + 1000}));
    EXPECT_EQ(small.max_sample_bytes, net::dds::max_typed_sample_bytes);
    mission::Mission none;
    none.tasks.resize(1);
    none.tasks[0].max_state_bytes = 1;  // not checkpointed: not counted
    EXPECT_EQ(largest_stated_state(none), std::optional<std::size_t>(0));
    stated.tasks[2].checkpoint = true;  // checkpointed, no bound stated
    EXPECT_EQ(largest_stated_state(stated), std::nullopt);
    EXPECT_EQ(protocol_dds_config({}, {0, 1}, largest_stated_state(stated)).limits.max_payload_bytes,
              fsm::kMaxMessageBytes);
}

// When every task states its max_sample_bytes, the data plane admits no larger sample: the
// envelope limit and Cyclone's MaxSampleSize follow the largest; one task without it keeps
// the network layer's bound.
TEST(Wire, TheDataPlanesLimitFollowsTheMissionsLargestStatedSample) {
    mission::Mission stated;
    stated.tasks.resize(2);
    stated.tasks[0].max_sample_bytes = 1000;
    stated.tasks[1].max_sample_bytes = 16 * 1024 * 1024;
    ASSERT_EQ(largest_stated_sample(stated), std::optional<std::size_t>(16 * 1024 * 1024));
    const net::dds::DdsConfig data =
        data_plane_dds_config({}, {0, 1}, 117, largest_stated_sample(stated));
    EXPECT_EQ(data.limits.max_payload_bytes, 16u * 1024 * 1024 + kSampleHeaderBytes);
    EXPECT_EQ(data.max_sample_bytes, net::dds::max_sample_bytes_for(data.limits.max_payload_bytes));
    EXPECT_NE(net::dds::domain_config_xml(data).find(
                  "<MaxSampleSize>" + std::to_string(data.max_sample_bytes) + "B</MaxSampleSize>"),
              std::string::npos);
    mission::Mission partly = stated;
    partly.tasks[1].max_sample_bytes.reset();
    EXPECT_EQ(largest_stated_sample(partly), std::nullopt);
    EXPECT_EQ(largest_stated_sample(mission::Mission{}), std::nullopt);
}

TEST(Wire, EveryProtocolMessageHasATransmissionType) {
    EXPECT_EQ(kind_of(fsm::Heartbeat{}), net::MessageKind::heartbeat);
    EXPECT_EQ(kind_of(fsm::Command{}), net::MessageKind::reconfiguration_command);
    EXPECT_EQ(kind_of(fsm::Ack{}), net::MessageKind::acknowledgement);
    EXPECT_EQ(kind_of(fsm::ErrorNotification{}), net::MessageKind::error_notification);
    EXPECT_EQ(kind_of(fsm::CheckpointWrite{}), net::MessageKind::reliable_data);
    EXPECT_EQ(kind_of(fsm::CheckpointRequest{}), net::MessageKind::request);
    EXPECT_EQ(kind_of(fsm::CheckpointReply{}), net::MessageKind::response);
    EXPECT_TRUE(carries_protocol(net::MessageKind::heartbeat));
    EXPECT_FALSE(carries_protocol(net::MessageKind::unreliable_data));
}

}  // namespace
}  // namespace keel::node
