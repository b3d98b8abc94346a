#include "core/net/envelope.hpp"

#include <gtest/gtest.h>

#include <random>

namespace keel::net {
namespace {

Envelope sample(MessageKind kind, std::size_t payload_bytes) {
    Envelope envelope;
    envelope.kind = kind;
    envelope.source = 3;
    envelope.destination = broadcast_address;
    envelope.port = 0xBEEF;
    envelope.epoch = 0xABCDEF;
    envelope.sequence = 0xDEADBEEF;
    envelope.payload.resize(payload_bytes);
    for (std::size_t i = 0; i < payload_bytes; ++i) {
        envelope.payload[i] = static_cast<std::uint8_t>(i * 7 + 1);
    }
    return envelope;
}

TEST(Envelope, HeaderIsEighteenBytesAndLayoutIsAsDocumented) {
    const std::vector<std::uint8_t> bytes = encode(sample(MessageKind::request, 2));
    ASSERT_EQ(bytes.size(), header_size_bytes + 2);
    EXPECT_EQ(header_size_bytes, 18u);
    const std::vector<std::uint8_t> expected_header = {
        0x23, 0x00, 0x03, 0xFF, 0xFF, 0xBE, 0xEF, 0xAB, 0xCD,
        0xEF, 0xDE, 0xAD, 0xBE, 0xEF, 0x00, 0x00, 0x00, 0x02};
    EXPECT_EQ(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + 18), expected_header);
}

// Missions of up to 256 nodes: node 255 is an address like any other (it was the broadcast
// address when addresses were one byte), and so is every two-byte address below broadcast.
TEST(Envelope, TwoByteAddressesRoundTrip) {
    for (NodeAddress address : {NodeAddress{0}, NodeAddress{255}, NodeAddress{256}, NodeAddress{0xFFFE}}) {
        Envelope envelope = sample(MessageKind::heartbeat, 3);
        envelope.source = address;
        envelope.destination = address;
        DecodeResult decoded = decode(encode(envelope));
        ASSERT_TRUE(decoded.ok()) << address << ": " << decoded.detail();
        EXPECT_EQ(decoded.envelope(), envelope);
    }
    EXPECT_EQ(broadcast_address, 0xFFFF);
}

// Frames of another envelope version (version 1: one-byte addresses) are refused, naming
// both versions.
TEST(Envelope, AFrameOfVersionOneIsRefused) {
    std::vector<std::uint8_t> bytes = encode(sample(MessageKind::request, 0));
    bytes[0] = static_cast<std::uint8_t>((1 << 4) | (bytes[0] & 0x0F));
    DecodeResult decoded = decode(bytes);
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error(), EnvelopeError::bad_version);
    EXPECT_EQ(decoded.detail(), "envelope version 1, expected 2");
}

TEST(Envelope, EveryKindRoundTrips) {
    for (MessageKind kind : all_message_kinds) {
        for (std::size_t size : {0u, 1u, 64u, 65536u}) {
            const Envelope original = sample(kind, size);
            DecodeResult decoded = decode(encode(original));
            ASSERT_TRUE(decoded.ok()) << to_string(kind) << ": " << decoded.detail();
            EXPECT_EQ(decoded.envelope(), original);
        }
    }
}

TEST(Envelope, SixteenMegabytePayloadRoundTrips) {
    const Envelope original = sample(MessageKind::large, 16u * 1024u * 1024u);
    DecodeResult decoded = decode(encode(original));
    ASSERT_TRUE(decoded.ok()) << decoded.detail();
    EXPECT_EQ(decoded.envelope(), original);
}

TEST(Envelope, TruncatedHeaderIsRejected) {
    const std::vector<std::uint8_t> bytes = encode(sample(MessageKind::heartbeat, 8));
    for (std::size_t cut = 0; cut < header_size_bytes; ++cut) {
        DecodeResult decoded = decode(std::span(bytes.data(), cut));
        ASSERT_FALSE(decoded.ok());
        EXPECT_EQ(decoded.error(), EnvelopeError::truncated);
        EXPECT_NE(decoded.detail().find("shorter than the 18-byte header"), std::string::npos);
    }
}

TEST(Envelope, TruncatedPayloadIsRejected) {
    const std::vector<std::uint8_t> bytes = encode(sample(MessageKind::reliable_data, 100));
    DecodeResult decoded = decode(std::span(bytes.data(), bytes.size() - 1));
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error(), EnvelopeError::truncated);
}

TEST(Envelope, TrailingBytesAreRejected) {
    std::vector<std::uint8_t> bytes = encode(sample(MessageKind::reliable_data, 10));
    bytes.push_back(0);
    DecodeResult decoded = decode(bytes);
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error(), EnvelopeError::length_mismatch);
}

TEST(Envelope, OversizedDeclaredLengthIsRejectedBeforeReadingPayload) {
    std::vector<std::uint8_t> bytes = encode(sample(MessageKind::large, 0));
    bytes[14] = 0xFF;  // declares ~4 GB but carries nothing
    DecodeResult decoded = decode(bytes);
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.error(), EnvelopeError::oversized);

    const std::vector<std::uint8_t> small = encode(sample(MessageKind::large, 1025));
    DecodeResult limited = decode(small, EnvelopeLimits{1024});
    ASSERT_FALSE(limited.ok());
    EXPECT_EQ(limited.error(), EnvelopeError::oversized);
    EXPECT_TRUE(decode(small, EnvelopeLimits{1025}).ok());
}

TEST(Envelope, BadVersionKindAndSourceAreRejected) {
    const std::vector<std::uint8_t> good = encode(sample(MessageKind::acknowledgement, 4));

    std::vector<std::uint8_t> bad_version = good;
    bad_version[0] = static_cast<std::uint8_t>((3 << 4) | (bad_version[0] & 0x0F));
    EXPECT_EQ(decode(bad_version).error(), EnvelopeError::bad_version);

    for (int raw_kind : {0, 10, 15}) {
        std::vector<std::uint8_t> bad_kind = good;
        bad_kind[0] = static_cast<std::uint8_t>((envelope_version << 4) | raw_kind);
        EXPECT_EQ(decode(bad_kind).error(), EnvelopeError::bad_kind);
    }

    std::vector<std::uint8_t> bad_source = good;
    bad_source[1] = 0xFF;  // the source, two bytes: the broadcast address
    bad_source[2] = 0xFF;
    EXPECT_EQ(decode(bad_source).error(), EnvelopeError::bad_source);
}

TEST(Envelope, EncodeRefusesWhatCannotTravel) {
    Envelope envelope = sample(MessageKind::heartbeat, 0);
    envelope.epoch = max_epoch + 1;
    EXPECT_THROW(encode(envelope), std::invalid_argument);
    envelope.epoch = max_epoch;
    EXPECT_NO_THROW(encode(envelope));
    envelope.source = broadcast_address;
    EXPECT_THROW(encode(envelope), std::invalid_argument);
    envelope.source = 1;
    envelope.kind = static_cast<MessageKind>(0);
    EXPECT_THROW(encode(envelope), std::invalid_argument);
}

TEST(Envelope, ValidateReportsEachProblem) {
    const EnvelopeLimits limits{16};
    Envelope envelope = sample(MessageKind::response, 16);
    EXPECT_FALSE(validate(envelope, limits).has_value());
    envelope.payload.push_back(0);
    EXPECT_EQ(validate(envelope, limits)->error, EnvelopeError::oversized);
    envelope.payload.pop_back();
    envelope.epoch = max_epoch + 1;
    EXPECT_EQ(validate(envelope, limits)->error, EnvelopeError::bad_epoch);
}

// Random and corrupted frames: decode must return (never crash, never read out of bounds
// under ASan) and anything it accepts must re-encode to the very same bytes.
TEST(Envelope, RandomAndCorruptFramesNeverCrashAndAcceptedOnesAreExact) {
    std::mt19937_64 random(20261121);
    const EnvelopeLimits limits{4096};
    std::size_t accepted = 0;
    for (int round = 0; round < 20000; ++round) {
        std::vector<std::uint8_t> bytes;
        if (round % 2 == 0) {
            bytes.resize(random() % 64);
            for (auto& byte : bytes) byte = static_cast<std::uint8_t>(random());
        } else {
            const auto kind = all_message_kinds[random() % std::size(all_message_kinds)];
            bytes = encode(sample(kind, random() % 48));
            const int flips = 1 + static_cast<int>(random() % 3);
            for (int flip = 0; flip < flips; ++flip) {
                bytes[random() % bytes.size()] ^= static_cast<std::uint8_t>(1u << (random() % 8));
            }
            if (random() % 4 == 0) bytes.resize(random() % (bytes.size() + 1));
        }
        DecodeResult decoded = decode(bytes, limits);
        if (decoded.ok()) {
            ++accepted;
            EXPECT_EQ(encode(decoded.envelope()), bytes);
        } else {
            EXPECT_FALSE(decoded.detail().empty());
            EXPECT_FALSE(to_string(decoded.error()).empty());
        }
    }
    // Bit flips in the addresses, port, epoch, sequence or payload still decode.
    EXPECT_GT(accepted, 1000u);
}

}  // namespace
}  // namespace keel::net
