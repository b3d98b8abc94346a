// Little-endian encoding of the integers that snapshots and built-in payloads hold: the
// application's own layouts, in the SDK's words. Both halves are Keel's one byte writer
// and reader (core/net/bytes.hpp) in little-endian order.
// ByteReader never reads past its end: a short input makes it fail(), not misbehave.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/net/bytes.hpp"

namespace keel::tasking {

inline void put_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
    net::ByteWriter(out, net::ByteOrder::little).u32(value);
}

inline void put_u64(std::vector<std::uint8_t>& out, std::uint64_t value) {
    net::ByteWriter(out, net::ByteOrder::little).u64(value);
}

inline void put_i64(std::vector<std::uint8_t>& out, std::int64_t value) {
    net::ByteWriter(out, net::ByteOrder::little).i64(value);
}

inline void put_bytes(std::vector<std::uint8_t>& out, std::span<const std::uint8_t> bytes) {
    net::ByteWriter(out, net::ByteOrder::little).bytes(bytes);
}

inline void put_string(std::vector<std::uint8_t>& out, std::string_view text) {
    put_bytes(out, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

class ByteReader {
  public:
    explicit ByteReader(std::span<const std::uint8_t> bytes)
        : reader_(bytes, net::ByteOrder::little) {}

    bool fail() const { return reader_.failed(); }
    bool at_end() const { return reader_.at_end(); }

    std::uint32_t u32() { return reader_.u32("u32"); }
    std::uint64_t u64() { return reader_.u64("u64"); }
    std::int64_t i64() { return reader_.i64("i64"); }

    std::vector<std::uint8_t> bytes() {
        const auto value = reader_.bytes("bytes", std::numeric_limits<std::uint32_t>::max());
        return {value.begin(), value.end()};
    }

    std::string string() {
        const auto value = reader_.bytes("string", std::numeric_limits<std::uint32_t>::max());
        return {value.begin(), value.end()};
    }

  private:
    net::ByteReader reader_;
};

}  // namespace keel::tasking
