// Little-endian encoding of the integers that snapshots and built-in payloads hold.
// ByteReader never reads past its end: a short input makes it fail(), not misbehave.
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace keel::tasking {

inline void put_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
    for (int shift = 0; shift < 32; shift += 8) {
        out.push_back(static_cast<std::uint8_t>(value >> shift));
    }
}

inline void put_u64(std::vector<std::uint8_t>& out, std::uint64_t value) {
    for (int shift = 0; shift < 64; shift += 8) {
        out.push_back(static_cast<std::uint8_t>(value >> shift));
    }
}

inline void put_i64(std::vector<std::uint8_t>& out, std::int64_t value) {
    put_u64(out, static_cast<std::uint64_t>(value));
}

inline void put_bytes(std::vector<std::uint8_t>& out, std::span<const std::uint8_t> bytes) {
    put_u32(out, static_cast<std::uint32_t>(bytes.size()));
    out.insert(out.end(), bytes.begin(), bytes.end());
}

inline void put_string(std::vector<std::uint8_t>& out, std::string_view text) {
    put_u32(out, static_cast<std::uint32_t>(text.size()));
    out.insert(out.end(), text.begin(), text.end());
}

class ByteReader {
  public:
    explicit ByteReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

    bool fail() const { return failed_; }
    bool at_end() const { return offset_ == bytes_.size(); }

    std::uint32_t u32() { return static_cast<std::uint32_t>(integer(4)); }
    std::uint64_t u64() { return integer(8); }
    std::int64_t i64() { return static_cast<std::int64_t>(integer(8)); }

    std::vector<std::uint8_t> bytes() {
        const std::uint32_t size = u32();
        if (failed_ || bytes_.size() - offset_ < size) {
            failed_ = true;
            return {};
        }
        std::vector<std::uint8_t> out(bytes_.begin() + static_cast<std::ptrdiff_t>(offset_),
                                      bytes_.begin() + static_cast<std::ptrdiff_t>(offset_ + size));
        offset_ += size;
        return out;
    }

    std::string string() {
        const std::vector<std::uint8_t> raw = bytes();
        return std::string(raw.begin(), raw.end());
    }

  private:
    std::uint64_t integer(std::size_t width) {
        if (failed_ || bytes_.size() - offset_ < width) {
            failed_ = true;
            return 0;
        }
        std::uint64_t value = 0;
        for (std::size_t index = 0; index < width; ++index) {
            value |= static_cast<std::uint64_t>(bytes_[offset_ + index]) << (8 * index);
        }
        offset_ += width;
        return value;
    }

    std::span<const std::uint8_t> bytes_;
    std::size_t offset_ = 0;
    bool failed_ = false;
};

}  // namespace keel::tasking
