// Byte-level helpers shared by the earth-observation components' message formats
// (scenes, cloud masks, AOCS checkpoints): little-endian writers and a bounds-checked
// reader, and CRC-32 so a corrupt buffer is rejected instead of misread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace keel::eo {

// Raised for malformed input buffers (an operating error, not a programmer error).
class DecodeError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// CRC-32 (IEEE 802.3, reflected 0xEDB88320), the checksum zlib and PNG use.
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

class ByteWriter {
  public:
    explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}
    void u8(std::uint8_t value) { out_.push_back(value); }
    void u16(std::uint16_t value) { put_le(value, 2); }
    void u32(std::uint32_t value) { put_le(value, 4); }
    void u64(std::uint64_t value) { put_le(value, 8); }
    void f64(double value);
    void bytes(std::span<const std::uint8_t> data) {
        out_.insert(out_.end(), data.begin(), data.end());
    }
    std::size_t size() const { return out_.size(); }

  private:
    void put_le(std::uint64_t value, int count) {
        for (int i = 0; i < count; ++i) out_.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
    }
    std::vector<std::uint8_t>& out_;
};

// Reads little-endian fields; every read checks the remaining length so a truncated
// buffer raises DecodeError naming the field instead of reading past the end.
class ByteReader {
  public:
    explicit ByteReader(std::span<const std::uint8_t> data) : data_(data) {}
    std::uint8_t u8(const char* field) { return static_cast<std::uint8_t>(get_le(1, field)); }
    std::uint16_t u16(const char* field) { return static_cast<std::uint16_t>(get_le(2, field)); }
    std::uint32_t u32(const char* field) { return static_cast<std::uint32_t>(get_le(4, field)); }
    std::uint64_t u64(const char* field) { return get_le(8, field); }
    double f64(const char* field);
    std::span<const std::uint8_t> bytes(std::size_t count, const char* field);
    std::size_t offset() const { return offset_; }
    std::size_t remaining() const { return data_.size() - offset_; }

  private:
    void need(std::size_t count, const char* field) const {
        if (remaining() < count) {
            throw DecodeError(std::string("truncated buffer: ") + field + " needs " +
                              std::to_string(count) + " bytes at offset " +
                              std::to_string(offset_) + ", " + std::to_string(remaining()) +
                              " left");
        }
    }
    std::uint64_t get_le(int count, const char* field) {
        need(static_cast<std::size_t>(count), field);
        std::uint64_t value = 0;
        for (int i = 0; i < count; ++i)
            value |= std::uint64_t{data_[offset_ + static_cast<std::size_t>(i)]} << (8 * i);
        offset_ += static_cast<std::size_t>(count);
        return value;
    }
    std::span<const std::uint8_t> data_;
    std::size_t offset_ = 0;
};

}  // namespace keel::eo
