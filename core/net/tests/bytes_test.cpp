#include "core/net/bytes.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace keel::net {
namespace {

TEST(Bytes, BigEndianIsTheDefaultAndEveryWidthRoundTrips) {
    std::vector<std::uint8_t> out;
    ByteWriter writer(out);
    writer.u8(0x01);
    writer.u16(0x0203);
    writer.u24(0x040506);
    writer.u32(0x0708090A);
    writer.u64(0x0B0C0D0E0F101112);
    writer.i64(-2);
    writer.flag(true);
    EXPECT_EQ(out, (std::vector<std::uint8_t>{0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09,
                                              0x0A, 0x0B, 0x0C, 0x0D, 0x0E, 0x0F, 0x10, 0x11, 0x12,
                                              0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFE, 0x01}));
    ByteReader reader(out);
    EXPECT_EQ(reader.u8("a"), 0x01);
    EXPECT_EQ(reader.u16("b"), 0x0203);
    EXPECT_EQ(reader.u24("c"), 0x040506u);
    EXPECT_EQ(reader.u32("d"), 0x0708090Au);
    EXPECT_EQ(reader.u64("e"), 0x0B0C0D0E0F101112u);
    EXPECT_EQ(reader.i64("f"), -2);
    EXPECT_TRUE(reader.flag("g"));
    EXPECT_FALSE(reader.failed());
    EXPECT_TRUE(reader.at_end());
}

TEST(Bytes, LittleEndianForCdr) {
    std::vector<std::uint8_t> out;
    ByteWriter writer(out, ByteOrder::little);
    writer.u16(0x0102);
    writer.u32(0x03040506);
    writer.u64(std::numeric_limits<std::uint64_t>::max() - 1);
    EXPECT_EQ(out, (std::vector<std::uint8_t>{0x02, 0x01, 0x06, 0x05, 0x04, 0x03, 0xFE, 0xFF, 0xFF,
                                              0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
    ByteReader reader(out, ByteOrder::little);
    EXPECT_EQ(reader.u16("a"), 0x0102);
    EXPECT_EQ(reader.u32("b"), 0x03040506u);
    EXPECT_EQ(reader.u64("c"), std::numeric_limits<std::uint64_t>::max() - 1);
    EXPECT_TRUE(reader.at_end());
}

TEST(Bytes, AShortInputNamesTheFieldAndTheFirstFailureIsKept) {
    const std::vector<std::uint8_t> bytes = {0, 0, 0, 7, 1};
    ByteReader reader(bytes);
    EXPECT_EQ(reader.u32("view.epoch"), 7u);
    EXPECT_EQ(reader.u32("view.seq"), 0u);  // one byte left: fails
    EXPECT_TRUE(reader.failed());
    EXPECT_EQ(reader.error(), ByteError::truncated);
    EXPECT_EQ(reader.detail(), "input ends inside view.seq");
    // Later reads return zero and keep the first failure.
    EXPECT_EQ(reader.u8("view.master"), 0);
    EXPECT_EQ(reader.detail(), "input ends inside view.seq");
    EXPECT_TRUE(reader.rest().empty());
}

TEST(Bytes, AFlagIsZeroOrOne) {
    const std::vector<std::uint8_t> bytes = {2};
    ByteReader reader(bytes);
    reader.flag("final");
    EXPECT_EQ(reader.error(), ByteError::bad_value);
    EXPECT_EQ(reader.detail(), "final is not 0 or 1");
}

TEST(Bytes, LengthPrefixedBytesAreBoundedBeforeAnythingIsRead) {
    std::vector<std::uint8_t> out;
    ByteWriter writer(out);
    const std::vector<std::uint8_t> state = {9, 8, 7};
    writer.bytes(state);
    {
        ByteReader reader(out);
        const auto read = reader.bytes("state", 3);
        EXPECT_EQ(std::vector<std::uint8_t>(read.begin(), read.end()), state);
        EXPECT_TRUE(reader.at_end());
    }
    {
        ByteReader reader(out);
        EXPECT_TRUE(reader.bytes("state", 2).empty());
        EXPECT_EQ(reader.error(), ByteError::bad_value);
        EXPECT_EQ(reader.detail(), "state length 3 exceeds the limit of 2");
    }
    {
        ByteReader reader(std::span(out.data(), out.size() - 1));
        EXPECT_TRUE(reader.bytes("state", 100).empty());
        EXPECT_EQ(reader.error(), ByteError::truncated);
        EXPECT_EQ(reader.detail(), "state declares 3 bytes, 2 remain");
    }
}

TEST(Bytes, RawAndRestAreViewsIntoTheInput) {
    const std::vector<std::uint8_t> bytes = {1, 2, 3, 4, 5};
    ByteReader reader(bytes);
    const auto head = reader.raw(2, "head");
    EXPECT_EQ(head.data(), bytes.data());
    EXPECT_EQ(reader.position(), 2u);
    EXPECT_EQ(reader.remaining(), 3u);
    EXPECT_TRUE(reader.raw(4, "body").empty());
    EXPECT_EQ(reader.detail(), "body needs 4 bytes, 3 remain");
    ByteReader again(bytes);
    again.u16("head");
    const auto rest = again.rest();
    EXPECT_EQ(std::vector<std::uint8_t>(rest.begin(), rest.end()), (std::vector<std::uint8_t>{3, 4, 5}));
    EXPECT_TRUE(again.at_end());
}

TEST(Bytes, ADecoderAddsItsOwnChecksUnderTheSameRule) {
    const std::vector<std::uint8_t> bytes = {0x01, 0x00};
    ByteReader reader(bytes);
    const std::uint16_t node = reader.u16("from");
    if (node >= 256) reader.fail(ByteError::bad_value, "from " + std::to_string(node) + " is not a node id");
    reader.fail(ByteError::truncated, "a second failure");
    EXPECT_EQ(reader.error(), ByteError::bad_value);
    EXPECT_EQ(reader.detail(), "from 256 is not a node id");
}

}  // namespace
}  // namespace keel::net
