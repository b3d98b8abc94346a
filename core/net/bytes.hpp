// Keel's one byte writer and reader: fixed-width integers, flags and length-prefixed byte
// strings, big-endian unless told otherwise.
//
// Everything Keel lays out byte by byte goes through these two classes: the envelope
// (envelope.cpp), the serialized DDS samples (dds/dds_transport.cpp, CDR in either byte
// order), the protocol codec (core/fsm/codec.cpp) and the node's own layouts (application
// samples, task snapshots, the persisted view: core/node/wire.cpp). Header-only, with no
// dependency beyond the standard library, so that the sans-IO state machines can use it
// without linking the network layer.
//
// ByteReader never trusts its input and never reads past its end. Every read names its
// field; the first failure is kept (later reads return zero and change nothing), with a
// sentence that names the field: "input ends inside view.epoch". A decoder reads all of its
// fields, then checks failed() once. fail() lets a decoder add its own checks (a value out
// of range) under the same rule.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace keel::net {

enum class ByteOrder : std::uint8_t { big, little };

// Why a ByteReader stopped.
enum class ByteError : std::uint8_t {
    none = 0,
    truncated = 1,  // the input ended inside a field, or a length declares more than is left
    bad_value = 2,  // a field outside its range (a flag, a length above its limit, ...)
};

class ByteWriter {
public:
    explicit ByteWriter(std::vector<std::uint8_t>& out, ByteOrder order = ByteOrder::big)
        : out_(out), order_(order) {}

    void u8(std::uint8_t value) { out_.push_back(value); }
    void u16(std::uint16_t value) { put(value, 2); }
    void u24(std::uint32_t value) { put(value, 3); }
    void u32(std::uint32_t value) { put(value, 4); }
    void u64(std::uint64_t value) { put(value, 8); }
    void i64(std::int64_t value) { put(static_cast<std::uint64_t>(value), 8); }
    void flag(bool value) { u8(value ? 1 : 0); }
    // The bytes as they are (the reader knows how many).
    void raw(std::span<const std::uint8_t> value) { out_.insert(out_.end(), value.begin(), value.end()); }
    // A four-byte length, then the bytes.
    void bytes(std::span<const std::uint8_t> value) {
        u32(static_cast<std::uint32_t>(value.size()));
        raw(value);
    }

private:
    void put(std::uint64_t value, int width) {
        if (order_ == ByteOrder::big) {
            for (int shift = (width - 1) * 8; shift >= 0; shift -= 8) {
                out_.push_back(static_cast<std::uint8_t>(value >> shift));
            }
        } else {
            for (int shift = 0; shift < width * 8; shift += 8) {
                out_.push_back(static_cast<std::uint8_t>(value >> shift));
            }
        }
    }

    std::vector<std::uint8_t>& out_;
    ByteOrder order_;
};

class ByteReader {
public:
    explicit ByteReader(std::span<const std::uint8_t> bytes, ByteOrder order = ByteOrder::big)
        : bytes_(bytes), order_(order) {}

    bool failed() const { return error_ != ByteError::none; }
    ByteError error() const { return error_; }
    // The first failure, as a sentence naming its field; empty while none.
    const std::string& detail() const { return detail_; }
    std::size_t position() const { return position_; }
    std::size_t remaining() const { return bytes_.size() - position_; }
    bool at_end() const { return position_ == bytes_.size(); }

    std::uint8_t u8(const char* field) { return static_cast<std::uint8_t>(get(1, field)); }
    std::uint16_t u16(const char* field) { return static_cast<std::uint16_t>(get(2, field)); }
    std::uint32_t u24(const char* field) { return static_cast<std::uint32_t>(get(3, field)); }
    std::uint32_t u32(const char* field) { return static_cast<std::uint32_t>(get(4, field)); }
    std::uint64_t u64(const char* field) { return get(8, field); }
    std::int64_t i64(const char* field) { return static_cast<std::int64_t>(get(8, field)); }
    // One byte that must be 0 or 1.
    bool flag(const char* field) {
        const std::uint8_t value = u8(field);
        if (!failed() && value > 1) fail(ByteError::bad_value, std::string(field) + " is not 0 or 1");
        return value == 1;
    }
    // The next `count` bytes, as a view into the input (empty on failure).
    std::span<const std::uint8_t> raw(std::size_t count, const char* field) {
        if (failed()) return {};
        if (count > remaining()) {
            fail(ByteError::truncated, std::string(field) + " needs " + std::to_string(count) +
                                           " bytes, " + std::to_string(remaining()) + " remain");
            return {};
        }
        const auto value = bytes_.subspan(position_, count);
        position_ += count;
        return value;
    }
    // A four-byte length, then that many bytes; a length above `max_bytes` is a bad value,
    // refused before anything is read or allocated.
    std::span<const std::uint8_t> bytes(const char* field, std::size_t max_bytes) {
        const std::uint32_t length = u32(field);
        if (failed()) return {};
        if (length > max_bytes) {
            fail(ByteError::bad_value, std::string(field) + " length " + std::to_string(length) +
                                           " exceeds the limit of " + std::to_string(max_bytes));
            return {};
        }
        if (length > remaining()) {
            fail(ByteError::truncated, std::string(field) + " declares " + std::to_string(length) +
                                           " bytes, " + std::to_string(remaining()) + " remain");
            return {};
        }
        return raw(length, field);
    }
    // Everything not read yet (empty on failure).
    std::span<const std::uint8_t> rest() {
        if (failed()) return {};
        const auto value = bytes_.subspan(position_);
        position_ = bytes_.size();
        return value;
    }
    // Records a failure; the first one is kept.
    void fail(ByteError error, std::string detail) {
        if (failed()) return;
        error_ = error;
        detail_ = std::move(detail);
    }

private:
    std::uint64_t get(std::size_t width, const char* field) {
        if (failed()) return 0;
        if (remaining() < width) {
            fail(ByteError::truncated, std::string("input ends inside ") + field);
            return 0;
        }
        std::uint64_t value = 0;
        if (order_ == ByteOrder::big) {
            for (std::size_t i = 0; i < width; ++i) value = (value << 8) | bytes_[position_ + i];
        } else {
            for (std::size_t i = width; i > 0; --i) value = (value << 8) | bytes_[position_ + i - 1];
        }
        position_ += width;
        return value;
    }

    std::span<const std::uint8_t> bytes_;
    ByteOrder order_;
    std::size_t position_ = 0;
    ByteError error_ = ByteError::none;
    std::string detail_;
};

}  // namespace keel::net
