#include "keel/eo/codec.hpp"

#include <array>
#include <bit>
#include <cstring>

namespace keel::eo {
namespace {

// Slicing-by-4 tables: a 16 MB scene is checksummed at several hundred MB/s, which keeps
// the checksum small next to the classification it protects.
using CrcTables = std::array<std::array<std::uint32_t, 256>, 4>;

constexpr CrcTables make_tables() {
    CrcTables tables{};
    for (std::uint32_t i = 0; i < 256; ++i) {
        std::uint32_t crc = i;
        for (int bit = 0; bit < 8; ++bit) crc = (crc & 1U) ? (crc >> 1) ^ 0xEDB88320U : crc >> 1;
        tables[0][i] = crc;
    }
    for (std::uint32_t i = 0; i < 256; ++i) {
        for (std::size_t t = 1; t < 4; ++t)
            tables[t][i] = (tables[t - 1][i] >> 8) ^ tables[0][tables[t - 1][i] & 0xFFU];
    }
    return tables;
}

constexpr CrcTables kTables = make_tables();

}  // namespace

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
    crc = ~crc;
    std::size_t i = 0;
    const std::size_t n = bytes.size();
    for (; i + 4 <= n; i += 4) {
        crc ^= std::uint32_t{bytes[i]} | (std::uint32_t{bytes[i + 1]} << 8) |
               (std::uint32_t{bytes[i + 2]} << 16) | (std::uint32_t{bytes[i + 3]} << 24);
        crc = kTables[3][crc & 0xFFU] ^ kTables[2][(crc >> 8) & 0xFFU] ^
              kTables[1][(crc >> 16) & 0xFFU] ^ kTables[0][crc >> 24];
    }
    for (; i < n; ++i) crc = kTables[0][(crc ^ bytes[i]) & 0xFFU] ^ (crc >> 8);
    return ~crc;
}

void ByteWriter::f64(double value) {
    u64(std::bit_cast<std::uint64_t>(value));
}

double ByteReader::f64(const char* field) {
    return std::bit_cast<double>(u64(field));
}

std::span<const std::uint8_t> ByteReader::bytes(std::size_t count, const char* field) {
    need(count, field);
    auto out = data_.subspan(offset_, count);
    offset_ += count;
    return out;
}

}  // namespace keel::eo
