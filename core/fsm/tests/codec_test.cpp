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
        [] {  // the ground's vote for its sender: milliseconds left of it
            Heartbeat voted{2, 7, 3, false, 12, {HeartbeatAck{1, 1, 11}}};
            voted.vote_left_ms = 1999;
            return Message{voted};
        }(),
        Command{1, view},
        Command{1, safe},
        Command{1, view, {safe, View{}}},
        [&] {  // a hand-over: it names its receiver's boot
            Command handed{1, view};
            handed.view.master = 2;
            handed.view.seq = 0;
            handed.boot = 0xDEADBEEF;
            return Message{handed};
        }(),
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
    EXPECT_EQ(encode(Heartbeat{2, 7, 3, false, 0, {}}).size(), 41u);
    EXPECT_EQ(encode(Heartbeat{2, 7, 3, false, 9, {HeartbeatAck{1, 1, 8}, HeartbeatAck{3, 2, 4}}}).size(), 61u);
    EXPECT_EQ(encode(Command{1, View{}}).size(), 24u);
    EXPECT_EQ(encode(Command{1, View{}, {View{}}}).size(), 39u);
    // A small mission's failed set takes one word, whatever the capacity.
    View four_nodes;
    four_nodes.failed.insert(3);
    EXPECT_EQ(encode(Command{1, four_nodes}).size(), 32u);
    // The largest messages are what codec.hpp derives from the capacity.
    View widest;
    for (int node = 0; node < kMaxNodes; ++node) widest.failed.insert(static_cast<NodeId>(node));
    // An online configuration at the capacity: every node an observer, every task placed.
    auto online = std::make_shared<OnlineConfig>();
    online->master = 0;
    online->observers.assign(kMaxNodes, NodeId{1});
    online->host.assign(kMaxTasks, NodeId{2});
    widest.config = widest.base = kOnlineConfig;
    widest.online = OnlinePtr(online);
    EXPECT_EQ(encode(Command{1, widest, std::vector<View>(kMaxJointViews, widest)}).size(),
              kMaxCommandBytes);
    Heartbeat everyone{2, 7, 3, false, 9, {}, true};
    for (int node = 0; node < kMaxNodes; ++node) everyone.acks.push_back({static_cast<NodeId>(node), 1, 1});
    EXPECT_EQ(encode(everyone).size(), kMaxHeartbeatBytes);
    EXPECT_EQ(encode(CheckpointReply{3, 7, 3, 1, true, {}, {}}).size(), kMaxCheckpointBytes - kMaxStateBytes);
}

// A 256-node view: the master and failed nodes at the edges of the set's words.
TEST(Codec, AViewOfTheFullCapacityRoundTrips) {
    View view;
    view.epoch = 9;
    view.seq = 4;
    view.config = 1;
    view.base = 1;
    view.master = kMaxNodes - 1;
    for (NodeId node : std::initializer_list<NodeId>{0, 63, 64, 127, 128, 255}) view.failed.insert(node);
    View all = view;
    for (int node = 0; node < kMaxNodes; ++node) all.failed.insert(static_cast<NodeId>(node));
    const std::vector<Message> messages = {
        Command{255, view, {all, View{}}},
        ErrorNotification{254, 9, 255},
        Heartbeat{255, 9, 1, false, 3, {HeartbeatAck{0, 1, 1}, HeartbeatAck{255, 2, 2}}, false},
        CheckpointWrite{255, 9, kMaxTasks - 1, {lineage_of(9, 4), 1}, false, {1}},
        CheckpointAck{200, 9, 512, {0, 1}},
        CheckpointRequest{128, 9, 4, 1023},
        CheckpointReply{64, 9, 4, 1023, true, {0, 2}, {5}},
    };
    for (const Message& message : messages) {
        const auto decoded = decode(encode(message));
        ASSERT_TRUE(decoded.ok()) << kind_name(message) << ": " << decoded.detail;
        EXPECT_EQ(*decoded.message, message) << kind_name(message);
    }
    // A failed set holding node 255 takes all four words; one holding node 64, two.
    View one;
    one.failed.insert(64);
    EXPECT_EQ(encode(Command{1, one}).size(), 24u + 16u);
    one.failed.insert(255);
    EXPECT_EQ(encode(Command{1, one}).size(), 24u + 32u);
}

TEST(Codec, TruncationNamesTheField) {
    View view;
    view.failed.insert(200);
    const auto bytes = encode(Command{1, view});
    auto decoded = decode(std::span(bytes.data(), bytes.size() - 8));  // boot and joint.count, and 3 of the set
    EXPECT_EQ(decoded.error, CodecError::truncated);
    EXPECT_EQ(decoded.detail, "input ends inside view.failed");
    decoded = decode(std::span(bytes.data(), 7));
    EXPECT_EQ(decoded.detail, "input ends inside view.epoch");
}

TEST(Codec, IdsAndSetsBeyondTheCapacityAreRefusedByName) {
    // A node id at the capacity (from), and kNoNode where no node is allowed (acks.node).
    auto bytes = encode(ErrorNotification{2, 7, 3});
    bytes[2] = 0x01;  // from = 256 + 2
    auto decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_EQ(decoded.detail, "from 258 is not a node id (at most 256 nodes)");
    // A task id at the capacity.
    bytes = encode(CheckpointRequest{2, 7, 3, 1});
    bytes[2 + 2 + 4 + 4] = 0x04;  // task = 1024 + 1
    decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_EQ(decoded.detail, "task 1025 is not a task id (at most 1024 tasks)");
    // A failed set of more words than a node set has.
    View view;
    view.failed.insert(255);
    bytes = encode(Command{1, view});
    bytes[2 + 2 + 4 + 4 + 2 + 2 + 2] = 5;  // the word count
    bytes.insert(bytes.end() - 1, 8, 0);  // and a fifth word before the joint count
    decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_EQ(decoded.detail, "view.failed has 5 words, a node set at most 4");
    // A set whose last word is empty: another encoding of a shorter set, refused.
    bytes = encode(Command{1, View{}});
    bytes[2 + 2 + 4 + 4 + 2 + 2 + 2] = 1;
    bytes.insert(bytes.end() - 1, 8, 0);
    decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_EQ(decoded.detail, "view.failed ends with an empty word (not canonical)");
    // The same checks on a joint view name it as such.
    bytes = encode(Command{1, View{}, {View{}}});
    bytes[bytes.size() - 1] = 1;
    bytes.insert(bytes.end(), 8, 0);
    decoded = decode(bytes);
    EXPECT_EQ(decoded.detail, "joint.failed ends with an empty word (not canonical)");
}

// Fault model 3: one width per quantity (types.hpp), refused where it is decoded.
TEST(Codec, ValuesBeyondTheirWidthsAreRefusedByName) {
    View wide;
    wide.epoch = kMaxEpoch + 1;
    wide.seq = 1;
    wide.config = wide.base = 0;
    wide.master = 0;
    const auto refused = [](const Message& message, const char* field) {
        const DecodedMessage decoded = decode(encode(message));
        EXPECT_FALSE(decoded.ok()) << field;
        EXPECT_EQ(decoded.error, CodecError::bad_value) << field;
        EXPECT_NE(decoded.detail.find(field), std::string::npos) << decoded.detail;
    };
    refused(Command{0, wide}, "view.epoch");
    View joint = wide;
    wide.epoch = kMaxEpoch;
    EXPECT_TRUE(decode(encode(Command{0, wide})).ok());  // the largest epoch fits
    refused(Command{0, wide, {joint}}, "joint.epoch");
    wide.seq = kMaxSeq + 1;
    refused(Command{0, wide}, "view.seq");
    refused(Heartbeat{2, kMaxEpoch + 1, 3, false, 0, {}}, "epoch");
    refused(Heartbeat{2, 7, kMaxIncarnation + 1, false, 0, {}}, "incarnation");
    refused(Heartbeat{2, 7, 3, false, 1, {HeartbeatAck{1, kMaxIncarnation + 1, 1}}}, "acks.incarnation");
    refused(ActivateCommand{1, kMaxEpoch + 1, 3}, "epoch");
    refused(ActivateCommand{1, 7, kMaxSeq + 1}, "seq");
    refused(Ack{2, 7, 0xFFFF'FFFFu, AckKind::Prepared}, "seq");
    refused(ErrorNotification{2, 0x8000'0000u, 0}, "epoch");
    // A version of {2^64-1, 2^64-1} names no switch and no count the Storage node holds.
    refused(CheckpointWrite{2, 7, 1, {~std::uint64_t{0}, ~std::uint64_t{0}}, true, {}}, "lineage");
    refused(CheckpointWrite{2, 7, 1, {lineage_of(7, 2), kMaxVersionCount + 1}, true, {}}, "version");
    refused(CheckpointAck{3, 7, 1, {lineage_of(kMaxEpoch, kMaxSeq + 1), 1}}, "lineage");
    refused(CheckpointRequest{2, 7, kMaxSeq + 1, 1}, "seq");
    refused(CheckpointReply{3, 7, 3, 1, true, {lineage_of(kMaxEpoch + 1, 0), 42}, {9}}, "lineage");
    EXPECT_TRUE(decode(encode(CheckpointWrite{2, 7, 1, {lineage_of(kMaxEpoch, kMaxSeq), kMaxVersionCount}, true, {}}))
                    .ok());
}

TEST(Codec, AnotherCodecVersionIsRefusedNamingBoth) {
    auto bytes = encode(Heartbeat{2, 7, 3, false, 0, {}});
    bytes[0] = 4;  // a node whose hand-overs name no boot
    const auto decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_version);
    EXPECT_NE(decoded.detail.find("codec version 4, expected 5"), std::string::npos) << decoded.detail;
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
    bytes[2 + 2 + 4 + 2 + 8 + 8] = 2;  // the `final` flag, after the lineage and the count
    EXPECT_EQ(decode(bytes).error, CodecError::bad_value);
}

TEST(Codec, ForgedAcknowledgementsAreRejected) {
    // More acknowledgements than nodes: refused before anything is read or allocated.
    auto bytes = encode(Heartbeat{2, 7, 3, false, 1, {}});
    bytes[bytes.size() - 7] = 0x01;  // the count (two bytes), before the reply flag and vote: 257
    bytes[bytes.size() - 6] = 0x01;
    auto decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_NE(decoded.detail.find("acks count 257 exceeds the 256-node limit"), std::string::npos)
        << decoded.detail;
    // An acknowledgement of a node id beyond the limit, and of no node.
    bytes = encode(Heartbeat{2, 7, 3, false, 1, {HeartbeatAck{1, 1, 1}}});
    bytes[bytes.size() - 15] = 0x01;  // the entry's node id (two bytes): 256
    bytes[bytes.size() - 14] = 0x00;
    decoded = decode(bytes);
    EXPECT_EQ(decoded.error, CodecError::bad_value);
    EXPECT_NE(decoded.detail.find("acks.node 256"), std::string::npos) << decoded.detail;
    bytes[bytes.size() - 15] = 0xFF;  // kNoNode
    bytes[bytes.size() - 14] = 0xFF;
    EXPECT_EQ(decode(bytes).error, CodecError::bad_value);
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
