#include "core/node/wire.hpp"

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

TEST(Wire, ViewRoundTripAndExactLength) {
    fsm::View view{3, 4, 2, 1, 5, fsm::NodeSet::from_bits(0b1010)};
    auto bytes = encode_view(view);
    EXPECT_EQ(bytes.size(), 21u);
    const auto decoded = decode_view(bytes);
    ASSERT_TRUE(decoded);
    EXPECT_EQ(*decoded, view);
    bytes.push_back(0);
    EXPECT_FALSE(decode_view(bytes));
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
