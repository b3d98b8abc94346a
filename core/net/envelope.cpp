#include "core/net/envelope.hpp"

#include <limits>
#include <stdexcept>
#include <utility>

namespace keel::net {

namespace {

constexpr std::uint8_t min_kind = static_cast<std::uint8_t>(MessageKind::unreliable_data);
constexpr std::uint8_t max_kind = static_cast<std::uint8_t>(MessageKind::large);

void put_u16(std::uint8_t* out, std::uint16_t value) {
    out[0] = static_cast<std::uint8_t>(value >> 8);
    out[1] = static_cast<std::uint8_t>(value);
}
void put_u24(std::uint8_t* out, std::uint32_t value) {
    out[0] = static_cast<std::uint8_t>(value >> 16);
    out[1] = static_cast<std::uint8_t>(value >> 8);
    out[2] = static_cast<std::uint8_t>(value);
}
void put_u32(std::uint8_t* out, std::uint32_t value) {
    out[0] = static_cast<std::uint8_t>(value >> 24);
    out[1] = static_cast<std::uint8_t>(value >> 16);
    out[2] = static_cast<std::uint8_t>(value >> 8);
    out[3] = static_cast<std::uint8_t>(value);
}
std::uint16_t get_u16(const std::uint8_t* in) {
    return static_cast<std::uint16_t>((in[0] << 8) | in[1]);
}
std::uint32_t get_u24(const std::uint8_t* in) {
    return (std::uint32_t{in[0]} << 16) | (std::uint32_t{in[1]} << 8) | std::uint32_t{in[2]};
}
std::uint32_t get_u32(const std::uint8_t* in) {
    return (std::uint32_t{in[0]} << 24) | (std::uint32_t{in[1]} << 16) |
           (std::uint32_t{in[2]} << 8) | std::uint32_t{in[3]};
}

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
    const std::size_t start = out.size();
    out.resize(start + header_size_bytes + envelope.payload.size());
    std::uint8_t* header = out.data() + start;
    header[0] = static_cast<std::uint8_t>((envelope_version << 4) |
                                          static_cast<std::uint8_t>(envelope.kind));
    header[1] = envelope.source;
    header[2] = envelope.destination;
    put_u16(header + 3, envelope.port);
    put_u24(header + 5, envelope.epoch);
    put_u32(header + 8, envelope.sequence);
    put_u32(header + 12, static_cast<std::uint32_t>(envelope.payload.size()));
    if (!envelope.payload.empty()) {
        std::copy(envelope.payload.begin(), envelope.payload.end(), header + header_size_bytes);
    }
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
                                     "frame of " + std::to_string(bytes.size()) +
                                         " bytes is shorter than the 16-byte header");
    }
    const std::uint8_t* header = bytes.data();
    const auto version = static_cast<std::uint8_t>(header[0] >> 4);
    if (version != envelope_version) {
        return DecodeResult::failure(EnvelopeError::bad_version,
                                     "envelope version " + std::to_string(version) +
                                         ", expected " + std::to_string(envelope_version));
    }
    const auto raw_kind = static_cast<std::uint8_t>(header[0] & 0x0F);
    if (!is_valid_kind(raw_kind)) {
        return DecodeResult::failure(EnvelopeError::bad_kind,
                                     "message kind " + std::to_string(raw_kind) +
                                         " is not one of the known kinds");
    }
    if (header[1] == broadcast_address) {
        return DecodeResult::failure(EnvelopeError::bad_source,
                                     "source is the broadcast address, which no node has");
    }
    const std::uint32_t payload_bytes = get_u32(header + 12);
    if (payload_bytes > limits.max_payload_bytes) {
        return DecodeResult::failure(EnvelopeError::oversized,
                                     "declared payload of " + std::to_string(payload_bytes) +
                                         " bytes exceeds the maximum of " +
                                         std::to_string(limits.max_payload_bytes));
    }
    const std::size_t available = bytes.size() - header_size_bytes;
    if (available < payload_bytes) {
        return DecodeResult::failure(EnvelopeError::truncated,
                                     "declared payload of " + std::to_string(payload_bytes) +
                                         " bytes but only " + std::to_string(available) +
                                         " follow the header");
    }
    if (available > payload_bytes) {
        return DecodeResult::failure(EnvelopeError::length_mismatch,
                                     std::to_string(available - payload_bytes) +
                                         " bytes follow the declared payload of " +
                                         std::to_string(payload_bytes));
    }
    Envelope envelope;
    envelope.kind = static_cast<MessageKind>(raw_kind);
    envelope.source = header[1];
    envelope.destination = header[2];
    envelope.port = get_u16(header + 3);
    envelope.epoch = get_u24(header + 5);
    envelope.sequence = get_u32(header + 8);
    envelope.payload.assign(bytes.begin() + header_size_bytes, bytes.end());
    return DecodeResult::success(std::move(envelope));
}

}  // namespace keel::net
