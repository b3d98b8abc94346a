// Compact binary encoding of the protocol messages (messages.hpp).
//
// The network layer carries the bytes as an envelope payload. Layout: one byte of codec
// version (kCodecVersion), one byte of message kind (the index of the alternative in
// `Message`, plus one), then the fields in declaration order, integers big-endian and
// fixed width, node/task/phase ids one byte, configuration ids two bytes, sets eight
// bytes, byte strings as a four-byte length then the bytes; a list as a one-byte count
// then its entries. A Heartbeat is 18 bytes plus 9 per acknowledgement (a monitor's
// acknowledges every node it watches), a Command 26. A task state's version is its lineage
// then its count, eight bytes each (types.hpp, Version; codec version 3: version 2 carried
// the count alone).
//
// decode() never trusts its input: truncated input, trailing bytes, an unknown version or
// kind, an out-of-range enum or a length beyond the limit is a CodecError with a sentence,
// never undefined behaviour.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/fsm/messages.hpp"

namespace keel::fsm {

inline constexpr std::uint8_t kCodecVersion = 3;
// Bound on a checkpoint's state in a message; a corrupt length cannot allocate more.
inline constexpr std::size_t kMaxStateBytes = 16u * 1024u * 1024u;
// A Command's joint views (spec/Quorum.tla): one per switch started since the Master's
// last completed one, and each of those excludes or readmits a node or changes the phase,
// so a few; more than this is refused as a bad value.
inline constexpr std::size_t kMaxJointViews = 64;

enum class CodecError : std::uint8_t {
    truncated = 1,      // input ended inside a field
    trailing_bytes = 2,  // bytes left after the message
    bad_version = 3,
    bad_kind = 4,
    bad_value = 5,  // a field outside its range (an enum, a flag, a length)
};
const char* to_string(CodecError error);

struct DecodedMessage {
    std::optional<Message> message;
    CodecError error = CodecError::truncated;
    std::string detail;

    bool ok() const { return message.has_value(); }
};

void encode_into(const Message& message, std::vector<std::uint8_t>& out);
std::vector<std::uint8_t> encode(const Message& message);
DecodedMessage decode(std::span<const std::uint8_t> bytes);

}  // namespace keel::fsm
