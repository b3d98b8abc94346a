#include "core/fsm/codec.hpp"

#include <gtest/gtest.h>

namespace keel::fsm {
namespace {

std::vector<Message> samples() {
    View view;
    view.epoch = 7;
    view.seq = 3;
    view.config = 2;
    view.base = 2;
    view.master = 1;
    view.failed.insert(0);
    view.failed.insert(5);
    View safe = view;
    safe.config = kSafeConfig;
    return {
        Heartbeat{2, 7, 3, false, 0, {}},
        Heartbeat{2, 7, 3, true, 0, {}},
        Heartbeat{2, 7, 3, false, 12, {HeartbeatAck{1, 1, 11}, HeartbeatAck{3, 2, 4}}, true},
        Command{1, view},
        Command{1, safe},
        Command{1, view, {safe, View{}}},
        ActivateCommand{1, 7, 3},
        Ack{2, 7, 3, AckKind::Prepared},
        Ack{3, 7, 3, AckKind::Activated},
        ErrorNotification{2, 7, 0},
        CheckpointWrite{2, 7, 1, {lineage_of(7, 2), 42}, true, {1, 2, 3, 4}},
        CheckpointWrite{2, 7, 1, {0, 43}, false, {}},
        CheckpointAck{3, 7, 1, {lineage_of(5, 1), 42}},
        CheckpointRequest{2, 7, 3, 1},
        CheckpointReply{3, 7, 3, 1, true, {lineage_of(7, 3), 42}, {9, 8}},
        CheckpointReply{3, 7, 3, 1, false, {}, {}},
        PhaseRequest{kNoNode, 1},
    };
}

TEST(Codec, EveryMessageRoundTrips) {
    for (const auto& message : samples()) {
        const auto bytes = encode(message);
        const auto decoded = decode(bytes);
        ASSERT_TRUE(decoded.ok()) << kind_name(message) << ": " << decoded.detail;
        EXPECT_EQ(*decoded.message, message) << kind_name(message);
    }
}

TEST(Codec, SizesAreCompact) {
    EXPECT_EQ(encode(Heartbeat{2, 7, 3, false, 0, {}}).size(), 18u);
    EXPECT_EQ(encode(Heartbeat{2, 7, 3, false, 9, {HeartbeatAck{1, 1, 8}, HeartbeatAck{3, 2, 4}}}).size(), 36u);
    EXPECT_EQ(encode(Command{1, View{}}).size(), 25u);
    EXPECT_EQ(encode(Command{1, View{}, {View{}}}).size(), 46u);
}

TEST(Codec, EveryTruncationIsRejected) {
    for (const auto& message : samples()) {
        const auto bytes = encode(message);
        for (std::size_t length = 0; length < bytes.size(); ++length) {
            const auto decoded = decode(std::span(bytes.data(), length));
            EXPECT_FALSE(decoded.ok()) << kind_name(message) << " cut at " << length;
            EXPECT_EQ(decoded.error, CodecError::truncated) << kind_name(message) << " cut at " << length;
        }
    }
}

TEST(Codec, ACommandWithTooManyJointViewsIsRejected) {
    // Joint views (spec/Quorum.tla): a count above kMaxJointViews is a bad value, named.
    auto bytes = encode(Command{1, View{}, std::vector<View>(kMaxJointViews, View{})});
    ASSERT_TRUE(decode(bytes).ok());
    bytes = encode(Command{1, View{}, std::vector<View>(kMaxJointViews + 1, View{})});
    const auto decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_NE(decoded.detail.find("joint.count"), std::string::npos) << decoded.detail;
}

TEST(Codec, TrailingBytesAreRejected) {
    auto bytes = encode(Heartbeat{2, 7, 3, false, 0, {}});
    bytes.push_back(0);
    const auto decoded = decode(bytes);
    EXPECT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error, CodecError::trailing_bytes);
}

TEST(Codec, BadVersionKindAndValuesAreRejected) {
    auto bytes = encode(Heartbeat{2, 7, 3, false, 0, {}});
    bytes[0] = 9;
    EXPECT_EQ(decode(bytes).error, CodecError::bad_version);
    bytes = encode(Heartbeat{2, 7, 3, false, 0, {}});
    bytes[1] = 0;
    EXPECT_EQ(decode(bytes).error, CodecError::bad_kind);
    bytes[1] = 200;
    EXPECT_EQ(decode(bytes).error, CodecError::bad_kind);
    bytes = encode(Ack{2, 7, 3, AckKind::Prepared});
    bytes.back() = 3;
    EXPECT_EQ(decode(bytes).error, CodecError::bad_value);
    bytes = encode(CheckpointWrite{2, 7, 1, {0, 42}, true, {}});
    bytes[2 + 1 + 4 + 1 + 8 + 8] = 2;  // the `final` flag, after the lineage and the count
    EXPECT_EQ(decode(bytes).error, CodecError::bad_value);
}

TEST(Codec, ForgedAcknowledgementsAreRejected) {
    // More acknowledgements than nodes: refused before anything is read or allocated.
    auto bytes = encode(Heartbeat{2, 7, 3, false, 1, {}});
    bytes[bytes.size() - 2] = 65;  // the count, before the reply flag
    auto decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_NE(decoded.detail.find("acks count 65"), std::string::npos) << decoded.detail;
    // An acknowledgement of a node id beyond the limit.
    bytes = encode(Heartbeat{2, 7, 3, false, 1, {HeartbeatAck{1, 1, 1}}});
    bytes[bytes.size() - 10] = 64;  // the entry's node id
    decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_NE(decoded.detail.find("acks.node 64"), std::string::npos) << decoded.detail;
}

TEST(Codec, HugeDeclaredLengthIsRejectedWithoutAllocating) {
    auto bytes = encode(CheckpointWrite{2, 7, 1, {0, 42}, true, {}});
    // The last four bytes are the state length.
    bytes[bytes.size() - 4] = 0xFF;
    bytes[bytes.size() - 3] = 0xFF;
    const auto decoded = decode(bytes);
    EXPECT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    bytes[bytes.size() - 4] = 0;
    bytes[bytes.size() - 3] = 0;
    bytes[bytes.size() - 1] = 5;  // 5 bytes declared, none present
    EXPECT_EQ(decode(bytes).error, CodecError::truncated);
}

TEST(Codec, RandomBytesNeverCrash) {
    std::uint64_t state = 0x9E3779B97F4A7C15ull;
    for (int round = 0; round < 20000; ++round) {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        std::vector<std::uint8_t> bytes(state % 40);
        for (auto& byte : bytes) {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            byte = static_cast<std::uint8_t>(state);
        }
        if (bytes.size() >= 2) {
            bytes[0] = kCodecVersion;
            bytes[1] = static_cast<std::uint8_t>(1 + bytes[1] % 10);
        }
        const auto decoded = decode(bytes);
        if (decoded.ok()) {
            EXPECT_EQ(encode(*decoded.message), bytes);
        } else {
            EXPECT_FALSE(decoded.detail.empty());
        }
    }
}

}  // namespace
}  // namespace keel::fsm
