#include <zlib.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "keel/eo/codec.hpp"
#include "keel/eo/components.hpp"

namespace keel::eo::components {

namespace {

constexpr std::size_t kSequenceOffset = 24;  // in the KSCN header (scene.hpp)
constexpr std::uint16_t kClassifiedVersion = 1;
constexpr std::uint16_t kAccountingVersion = 1;
constexpr std::uint16_t kFlagTruth = 1;
constexpr std::uint16_t kFlagResent = 2;
constexpr std::size_t kWorkerNameMax = 256;

void put_u64_at(std::span<std::uint8_t> bytes, std::size_t offset, std::uint64_t value) {
    for (std::size_t i = 0; i < 8; ++i)
        bytes[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
}

void put_u32_at(std::span<std::uint8_t> bytes, std::size_t offset, std::uint32_t value) {
    for (std::size_t i = 0; i < 4; ++i)
        bytes[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
}

void put_blob(ByteWriter& writer, std::span<const std::uint8_t> blob) {
    writer.u32(static_cast<std::uint32_t>(blob.size()));
    writer.bytes(blob);
}

std::span<const std::uint8_t> get_blob(ByteReader& reader, const char* field) {
    const std::uint32_t size = reader.u32(field);
    return reader.bytes(size, field);
}

// Checks the trailing CRC-32 and returns the bytes it covers.
std::span<const std::uint8_t> checked_body(std::span<const std::uint8_t> bytes, const char* what) {
    if (bytes.size() < 8) throw DecodeError(std::string(what) + ": buffer too short");
    const auto body = bytes.first(bytes.size() - 4);
    ByteReader tail(bytes.last(4));
    if (tail.u32("crc") != crc32(body))
        throw DecodeError(std::string(what) + ": checksum mismatch");
    return body;
}

}  // namespace

std::optional<std::uint64_t> peek_scene_sequence(std::span<const std::uint8_t> bytes) {
    if (bytes.size() < kSceneHeaderBytes) return std::nullopt;
    ByteReader reader(bytes.first(kSceneHeaderBytes));
    if (reader.u32("magic") != kSceneMagic) return std::nullopt;
    if (reader.u16("version") != kSceneVersion) return std::nullopt;
    reader.bytes(kSequenceOffset - 6, "header");
    return reader.u64("sequence");
}

std::uint32_t scene_body_crc(std::span<const std::uint8_t> scene_bytes) {
    if (scene_bytes.size() < kSceneHeaderBytes + 4) throw DecodeError("scene buffer too short");
    const auto body =
        scene_bytes.subspan(kSceneHeaderBytes, scene_bytes.size() - kSceneHeaderBytes - 4);
    return crc32(body);
}

std::vector<std::uint8_t> restamp_scene(std::span<const std::uint8_t> scene_bytes,
                                        std::uint64_t sequence, std::uint32_t body_crc) {
    if (!peek_scene_sequence(scene_bytes) || scene_bytes.size() < kSceneHeaderBytes + 4) {
        throw DecodeError("restamp: not a KSCN scene");
    }
    std::vector<std::uint8_t> out(scene_bytes.begin(), scene_bytes.end());
    put_u64_at(out, kSequenceOffset, sequence);
    const std::uint32_t header_crc =
        crc32(std::span<const std::uint8_t>(out.data(), kSceneHeaderBytes));
    const auto body_length = static_cast<z_off_t>(out.size() - kSceneHeaderBytes - 4);
    const auto total = static_cast<std::uint32_t>(crc32_combine(header_crc, body_crc, body_length));
    put_u32_at(out, out.size() - 4, total);
    return out;
}

std::vector<std::uint8_t> serialise(const ClassifiedImage& image) {
    std::vector<std::uint8_t> out;
    const std::vector<std::uint8_t> result = acca::serialise(image.result);
    const std::vector<std::uint8_t> quicklook = keel::eo::serialise(image.quicklook);
    out.reserve(128 + image.worker.size() + result.size() + quicklook.size());
    ByteWriter writer(out);
    writer.u32(kClassifiedMagic);
    writer.u16(kClassifiedVersion);
    writer.u16(static_cast<std::uint16_t>((image.versus_truth ? kFlagTruth : 0) |
                                          (image.resent ? kFlagResent : 0)));
    writer.u64(image.sequence);
    writer.u64(image.seed);
    writer.u32(image.worker_pid);
    writer.u32(image.classified);
    put_blob(writer,
             std::span<const std::uint8_t>(
                 reinterpret_cast<const std::uint8_t*>(image.worker.data()), image.worker.size()));
    writer.f64(image.truth_cloud_fraction);
    const sink::Confusion confusion = image.versus_truth.value_or(sink::Confusion{});
    writer.u64(confusion.true_positive);
    writer.u64(confusion.false_positive);
    writer.u64(confusion.false_negative);
    writer.u64(confusion.true_negative);
    put_blob(writer, result);
    put_blob(writer, quicklook);
    writer.u32(crc32(out));
    return out;
}

ClassifiedImage deserialise_classified(std::span<const std::uint8_t> bytes) {
    ByteReader reader(checked_body(bytes, "classified image"));
    if (reader.u32("magic") != kClassifiedMagic) throw DecodeError("classified image: wrong magic");
    if (reader.u16("version") != kClassifiedVersion)
        throw DecodeError("classified image: unknown version");
    const std::uint16_t flags = reader.u16("flags");
    ClassifiedImage image;
    image.sequence = reader.u64("sequence");
    image.seed = reader.u64("seed");
    image.worker_pid = reader.u32("worker_pid");
    image.classified = reader.u32("classified");
    const auto worker = get_blob(reader, "worker");
    if (worker.size() > kWorkerNameMax) throw DecodeError("classified image: worker name too long");
    image.worker.assign(worker.begin(), worker.end());
    image.truth_cloud_fraction = reader.f64("truth_cloud_fraction");
    sink::Confusion confusion;
    confusion.true_positive = reader.u64("tp");
    confusion.false_positive = reader.u64("fp");
    confusion.false_negative = reader.u64("fn");
    confusion.true_negative = reader.u64("tn");
    if ((flags & kFlagTruth) != 0) image.versus_truth = confusion;
    image.resent = (flags & kFlagResent) != 0;
    image.result = acca::deserialise_result(get_blob(reader, "result"));
    image.quicklook = deserialise_scene(get_blob(reader, "quicklook"));
    if (reader.remaining() != 0) throw DecodeError("classified image: trailing bytes");
    if (image.result.sequence != image.sequence) {
        throw DecodeError("classified image: result belongs to another sequence");
    }
    return image;
}

bool Accounting::covers(std::uint64_t sequence) const {
    return sequence <= watermark ||
           std::binary_search(recorded_above.begin(), recorded_above.end(), sequence);
}

std::vector<std::uint8_t> serialise(const Accounting& accounting) {
    std::vector<std::uint8_t> out;
    ByteWriter writer(out);
    const std::size_t count = std::min(accounting.recorded_above.size(), accounting_list_max);
    writer.u32(kAccountingMagic);
    writer.u16(kAccountingVersion);
    writer.u16(static_cast<std::uint16_t>(count));
    writer.u64(accounting.watermark);
    writer.u64(accounting.recorded);
    writer.u64(accounting.duplicates);
    for (std::size_t i = 0; i < count; ++i) writer.u64(accounting.recorded_above[i]);
    writer.u32(crc32(out));
    return out;
}

Accounting deserialise_accounting(std::span<const std::uint8_t> bytes) {
    ByteReader reader(checked_body(bytes, "accounting"));
    if (reader.u32("magic") != kAccountingMagic) throw DecodeError("accounting: wrong magic");
    if (reader.u16("version") != kAccountingVersion)
        throw DecodeError("accounting: unknown version");
    const std::uint16_t count = reader.u16("count");
    if (count > accounting_list_max) throw DecodeError("accounting: list too long");
    Accounting accounting;
    accounting.watermark = reader.u64("watermark");
    accounting.recorded = reader.u64("recorded");
    accounting.duplicates = reader.u64("duplicates");
    accounting.recorded_above.reserve(count);
    for (std::uint16_t i = 0; i < count; ++i)
        accounting.recorded_above.push_back(reader.u64("sequence"));
    if (reader.remaining() != 0) throw DecodeError("accounting: trailing bytes");
    if (!std::is_sorted(accounting.recorded_above.begin(), accounting.recorded_above.end())) {
        throw DecodeError("accounting: sequence list not sorted");
    }
    return accounting;
}

std::string output_directory(const std::string& parameter) {
    if (!parameter.empty()) return parameter;
    if (const char* env = std::getenv("KEEL_EO_OUT_DIR"); env != nullptr && *env != '\0')
        return env;
    return "eo-out";
}

}  // namespace keel::eo::components
