// The application envelope: what every Keel message carries between nodes, and its codec.
//
// The paper's network layer addresses a message by the destination node's logical address
// and a port, and tags it with a transmission type; it spends 17 bytes on that. Keel's
// envelope adds the sender, the configuration epoch (so stale messages can be rejected in
// one place) and a per-sender sequence number, in an 18-byte header (integers big-endian,
// written and read by bytes.hpp):
//
//   offset  size  field
//   0       1     version (high nibble, = envelope_version) | message kind (low nibble)
//   1       2     source node logical address (never broadcast_address)
//   3       2     destination node logical address (broadcast_address = every node)
//   5       2     port
//   7       3     epoch (24 bits: at most max_epoch)
//   10      4     sequence
//   14      4     payload length in bytes
//   18      n     payload
//
// Version 2: addresses of two bytes, for missions of up to 256 nodes (core/fsm/types.hpp,
// kMaxNodes) with a broadcast address outside them; version 1 had one-byte addresses.
//
// decode() never trusts its input: every failure is a DecodeError with a sentence saying
// what was wrong, and no input (truncated, corrupt, huge length) causes undefined behaviour.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace keel::net {

using NodeAddress = std::uint16_t;
using Port = std::uint16_t;
using Epoch = std::uint32_t;
using Sequence = std::uint32_t;

// A destination of broadcast_address reaches every node; no node has this address.
inline constexpr NodeAddress broadcast_address = 0xFFFF;
// Epochs travel in 24 bits; a mission reconfigures far fewer times than this.
inline constexpr Epoch max_epoch = 0xFF'FFFF;
inline constexpr std::uint8_t envelope_version = 2;
inline constexpr std::size_t header_size_bytes = 18;
// Default bound on a payload; large messages (tens of MB) fit, a corrupt length does not.
inline constexpr std::size_t default_max_payload_bytes = 64u * 1024u * 1024u;

// The paper's transmission types. Values are stable: they are on the wire.
enum class MessageKind : std::uint8_t {
    unreliable_data = 1,
    reliable_data = 2,
    request = 3,
    response = 4,
    reconfiguration_command = 5,
    acknowledgement = 6,
    heartbeat = 7,
    error_notification = 8,
    large = 9,
};
inline constexpr MessageKind all_message_kinds[] = {
    MessageKind::unreliable_data,         MessageKind::reliable_data,
    MessageKind::request,                 MessageKind::response,
    MessageKind::reconfiguration_command, MessageKind::acknowledgement,
    MessageKind::heartbeat,               MessageKind::error_notification,
    MessageKind::large,
};

bool is_valid_kind(std::uint8_t raw_kind);
std::string_view to_string(MessageKind kind);

struct Envelope {
    MessageKind kind = MessageKind::unreliable_data;
    NodeAddress source = 0;
    NodeAddress destination = broadcast_address;
    Port port = 0;
    Epoch epoch = 0;
    Sequence sequence = 0;
    std::vector<std::uint8_t> payload{};

    friend bool operator==(const Envelope&, const Envelope&) = default;
};

// Why bytes or an envelope were rejected. Values are stable (used in logs and counters).
enum class EnvelopeError : std::uint8_t {
    truncated = 1,        // fewer bytes than the header or than the declared payload length
    length_mismatch = 2,  // bytes left over after the declared payload
    oversized = 3,        // declared payload longer than the configured maximum
    bad_version = 4,      // version nibble is not envelope_version
    bad_kind = 5,         // kind nibble is not a MessageKind
    bad_source = 6,       // source is the broadcast address
    bad_epoch = 7,        // epoch above max_epoch
    // Raised by transports that know who wrote a message (DdsTransport), never by decode():
    forged_sender = 8,  // the source field is not the node the authenticated writer speaks for
    replayed = 9,       // a sequence number its writer already used (a captured message again)
    // Raised by transports with typed protocol topics (DdsTransport): a sample whose fields
    // are not a message its topic carries, or hold a value the protocol codec refuses.
    bad_message = 10,
};
std::string_view to_string(EnvelopeError error);

struct EnvelopeLimits {
    std::size_t max_payload_bytes = default_max_payload_bytes;
};

// The outcome of decode() or validate(): either an envelope or an error with a sentence.
class DecodeResult {
public:
    static DecodeResult success(Envelope envelope);
    static DecodeResult failure(EnvelopeError error, std::string detail);

    bool ok() const { return envelope_.has_value(); }
    const Envelope& envelope() const&;
    Envelope&& envelope() &&;
    EnvelopeError error() const;
    const std::string& detail() const { return detail_; }

private:
    std::optional<Envelope> envelope_;
    EnvelopeError error_ = EnvelopeError::truncated;
    std::string detail_;
};

// Checks the fields of an envelope that did not come from decode() (a DDS sample, a caller):
// returns the first problem, or nothing when the envelope may travel.
struct EnvelopeProblem {
    EnvelopeError error;
    std::string detail;
};
std::optional<EnvelopeProblem> validate(const Envelope& envelope, const EnvelopeLimits& limits);

// Appends the encoded envelope to `out`. Precondition: validate() found no problem
// (violations are programmer errors and throw std::invalid_argument).
void encode_into(const Envelope& envelope, std::vector<std::uint8_t>& out);
std::vector<std::uint8_t> encode(const Envelope& envelope);

DecodeResult decode(std::span<const std::uint8_t> bytes, const EnvelopeLimits& limits = {});

}  // namespace keel::net
