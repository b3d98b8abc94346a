#include "core/net/envelope.hpp"

#include <limits>
#include <stdexcept>
#include <utility>

#include "core/net/bytes.hpp"

namespace keel::net {

namespace {

constexpr std::uint8_t min_kind = static_cast<std::uint8_t>(MessageKind::unreliable_data);
constexpr std::uint8_t max_kind = static_cast<std::uint8_t>(MessageKind::large);

}  // namespace

bool is_valid_kind(std::uint8_t raw_kind) { return raw_kind >= min_kind && raw_kind <= max_kind; }

std::string_view to_string(MessageKind kind) {
    switch (kind) {
        case MessageKind::unreliable_data: return "unreliable_data";
        case MessageKind::reliable_data: return "reliable_data";
        case MessageKind::request: return "request";
        case MessageKind::response: return "response";
        case MessageKind::reconfiguration_command: return "reconfiguration_command";
        case MessageKind::acknowledgement: return "acknowledgement";
        case MessageKind::heartbeat: return "heartbeat";
        case MessageKind::error_notification: return "error_notification";
        case MessageKind::large: return "large";
    }
    return "invalid_kind";
}

std::string_view to_string(EnvelopeError error) {
    switch (error) {
        case EnvelopeError::truncated: return "truncated";
        case EnvelopeError::length_mismatch: return "length_mismatch";
        case EnvelopeError::oversized: return "oversized";
        case EnvelopeError::bad_version: return "bad_version";
        case EnvelopeError::bad_kind: return "bad_kind";
        case EnvelopeError::bad_source: return "bad_source";
        case EnvelopeError::bad_epoch: return "bad_epoch";
        case EnvelopeError::forged_sender: return "forged_sender";
        case EnvelopeError::replayed: return "replayed";
        case EnvelopeError::bad_message: return "bad_message";
    }
    return "invalid_error";
}

DecodeResult DecodeResult::success(Envelope envelope) {
    DecodeResult result;
    result.envelope_ = std::move(envelope);
    return result;
}

DecodeResult DecodeResult::failure(EnvelopeError error, std::string detail) {
    DecodeResult result;
    result.error_ = error;
    result.detail_ = std::move(detail);
    return result;
}

const Envelope& DecodeResult::envelope() const& {
    if (!envelope_) throw std::logic_error("DecodeResult::envelope() on a failed decode");
    return *envelope_;
}

Envelope&& DecodeResult::envelope() && {
    if (!envelope_) throw std::logic_error("DecodeResult::envelope() on a failed decode");
    return std::move(*envelope_);
}

EnvelopeError DecodeResult::error() const {
    if (envelope_) throw std::logic_error("DecodeResult::error() on a successful decode");
    return error_;
}

std::optional<EnvelopeProblem> validate(const Envelope& envelope, const EnvelopeLimits& limits) {
    if (!is_valid_kind(static_cast<std::uint8_t>(envelope.kind))) {
        return EnvelopeProblem{EnvelopeError::bad_kind,
                               "message kind " +
                                   std::to_string(static_cast<unsigned>(envelope.kind)) +
                                   " is not one of the known kinds"};
    }
    if (envelope.source == broadcast_address) {
        return EnvelopeProblem{EnvelopeError::bad_source,
                               "source is the broadcast address, which no node has"};
    }
    if (envelope.epoch > max_epoch) {
        return EnvelopeProblem{EnvelopeError::bad_epoch, "epoch " + std::to_string(envelope.epoch) +
                                                             " does not fit in 24 bits"};
    }
    if (envelope.payload.size() > limits.max_payload_bytes) {
        return EnvelopeProblem{EnvelopeError::oversized,
                               "payload of " + std::to_string(envelope.payload.size()) +
                                   " bytes exceeds the maximum of " +
                                   std::to_string(limits.max_payload_bytes)};
    }
    return std::nullopt;
}

void encode_into(const Envelope& envelope, std::vector<std::uint8_t>& out) {
    const EnvelopeLimits wire_limit{std::numeric_limits<std::uint32_t>::max()};
    if (auto problem = validate(envelope, wire_limit)) {
        throw std::invalid_argument("cannot encode envelope: " + problem->detail);
    }
    out.reserve(out.size() + header_size_bytes + envelope.payload.size());
    ByteWriter writer(out);
    writer.u8(static_cast<std::uint8_t>((envelope_version << 4) |
                                        static_cast<std::uint8_t>(envelope.kind)));
    writer.u16(envelope.source);
    writer.u16(envelope.destination);
    writer.u16(envelope.port);
    writer.u24(envelope.epoch);
    writer.u32(envelope.sequence);
    writer.u32(static_cast<std::uint32_t>(envelope.payload.size()));
    writer.raw(envelope.payload);
}

std::vector<std::uint8_t> encode(const Envelope& envelope) {
    std::vector<std::uint8_t> out;
    out.reserve(header_size_bytes + envelope.payload.size());
    encode_into(envelope, out);
    return out;
}

DecodeResult decode(std::span<const std::uint8_t> bytes, const EnvelopeLimits& limits) {
    if (bytes.size() < header_size_bytes) {
        return DecodeResult::failure(EnvelopeError::truncated,
                                     "frame of " + std::to_string(bytes.size()) + " bytes is shorter than the " +
                                         std::to_string(header_size_bytes) + "-byte header");
    }
    ByteReader reader(bytes);
    const std::uint8_t first = reader.u8("version");
    Envelope envelope;
    envelope.source = reader.u16("source");
    envelope.destination = reader.u16("destination");
    envelope.port = reader.u16("port");
    envelope.epoch = reader.u24("epoch");
    envelope.sequence = reader.u32("sequence");
    const std::uint32_t payload_bytes = reader.u32("payload length");
    // The header is all there (checked above): the reader cannot have failed.
    const auto version = static_cast<std::uint8_t>(first >> 4);
    if (version != envelope_version) {
        return DecodeResult::failure(EnvelopeError::bad_version,
                                     "envelope version " + std::to_string(version) +
                                         ", expected " + std::to_string(envelope_version));
    }
    const auto raw_kind = static_cast<std::uint8_t>(first & 0x0F);
    if (!is_valid_kind(raw_kind)) {
        return DecodeResult::failure(EnvelopeError::bad_kind,
                                     "message kind " + std::to_string(raw_kind) +
                                         " is not one of the known kinds");
    }
    envelope.kind = static_cast<MessageKind>(raw_kind);
    if (envelope.source == broadcast_address) {
        return DecodeResult::failure(EnvelopeError::bad_source,
                                     "source is the broadcast address, which no node has");
    }
    if (payload_bytes > limits.max_payload_bytes) {
        return DecodeResult::failure(EnvelopeError::oversized,
                                     "declared payload of " + std::to_string(payload_bytes) +
                                         " bytes exceeds the maximum of " +
                                         std::to_string(limits.max_payload_bytes));
    }
    if (reader.remaining() < payload_bytes) {
        return DecodeResult::failure(EnvelopeError::truncated,
                                     "declared payload of " + std::to_string(payload_bytes) +
                                         " bytes but only " + std::to_string(reader.remaining()) +
                                         " follow the header");
    }
    if (reader.remaining() > payload_bytes) {
        return DecodeResult::failure(EnvelopeError::length_mismatch,
                                     std::to_string(reader.remaining() - payload_bytes) +
                                         " bytes follow the declared payload of " +
                                         std::to_string(payload_bytes));
    }
    const auto payload = reader.raw(payload_bytes, "payload");
    envelope.payload.assign(payload.begin(), payload.end());
    return DecodeResult::success(std::move(envelope));
}

}  // namespace keel::net
