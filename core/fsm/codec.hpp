// Compact binary encoding of the protocol messages (messages.hpp).
//
// The network layer carries the bytes as an envelope payload. Layout: one byte of codec
// version (kCodecVersion), one byte of message kind (the index of the alternative in
// `Message`, plus one), then the fields in declaration order, integers big-endian and
// fixed width (core/net/bytes.hpp writes and reads them): node and task ids two bytes,
// phase ids one, configuration ids two; a node set as a one-byte count of words, then that
// many eight-byte words (word i holds ids 64 i to 64 i + 63), up to its last non-empty
// word only (the empty set is the single byte 0); byte strings as a four-byte length then
// the bytes; a list as a count (two bytes for a heartbeat's acknowledgements, one for a
// Command's joint views) then its entries. A view is 15 bytes plus 8 per word of its
// failed set (at most 47 at kMaxNodes). A Heartbeat is 20 bytes plus 10 per
// acknowledgement (a monitor acknowledges every node it watches), a Command 24 with no
// node failed. A task state's version is its lineage then its count, eight bytes each.
//
// Versions: 3 had one-byte ids and a set as one 64-bit word (64 nodes, 64 tasks); 4 has
// two-byte ids and sets of words, for the capacity of types.hpp; 5 (this one) adds a
// Command's `boot` (a hand-over names its receiver's boot) after its view. decode()
// refuses every version but kCodecVersion, naming both.
//
// decode() never trusts its input: truncated input, trailing bytes, an unknown version or
// kind, an out-of-range enum, id, flag or count, a set not in its canonical form (a last
// word that is empty: one encoding per value) or a length beyond the limit is a CodecError
// with a sentence naming the field, never undefined behaviour.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/fsm/messages.hpp"
#include "core/net/bytes.hpp"

namespace keel::fsm {

inline constexpr std::uint8_t kCodecVersion = 5;
// Bound on a checkpoint's state in a message; a corrupt length cannot allocate more.
inline constexpr std::size_t kMaxStateBytes = 16u * 1024u * 1024u;
// A checkpoint's state is a snapshot: its format version (u32) and sequence (u64), then the
// component's payload (core/node/wire.cpp, encode_snapshot), which a mission bounds with a
// task's max_state_bytes.
inline constexpr std::size_t kSnapshotHeaderBytes = 4 + 8;
// A Command's joint views (spec/Quorum.tla): one per switch started since the Master's
// last completed one, and each of those excludes or readmits a node or changes the phase,
// so a few; more than this is refused as a bad value.
inline constexpr std::size_t kMaxJointViews = 64;

// The largest encoding of each message, derived from the capacity (types.hpp): the network
// layer's limits must admit kMaxMessageBytes (core/node checks it at compile time).
inline constexpr std::size_t kMaxNodeSetBytes = 1 + 8 * NodeSet::kWords;
// An online configuration (a view whose base is kOnlineConfig): phase, master, observers
// and one host per task.
inline constexpr std::size_t kMaxOnlineBytes = 1 + 2 + 2 + 2 * kMaxNodes + 2 + 2 * kMaxTasks;
inline constexpr std::size_t kMaxViewBytes = 4 + 4 + 2 + 2 + 2 + kMaxNodeSetBytes + kMaxOnlineBytes;
inline constexpr std::size_t kHeartbeatAckBytes = 2 + 4 + 4;
inline constexpr std::size_t kMaxHeartbeatBytes =
    2 + (2 + 4 + 4 + 4 + 4 + 8 + 1 + 1 + 4) + 2 + kMaxNodes * kHeartbeatAckBytes + 1 + 4;
inline constexpr std::size_t kMaxCommandBytes = 2 + 2 + kMaxViewBytes + 4 + 1 + kMaxJointViews * kMaxViewBytes;
// A checkpoint message's bytes besides its state (CheckpointReply, the larger).
inline constexpr std::size_t kCheckpointOverheadBytes = 2 + (2 + 4 + 4 + 2 + 1 + 8 + 8) + 4;
inline constexpr std::size_t kMaxCheckpointBytes = kCheckpointOverheadBytes + kMaxStateBytes;
inline constexpr std::size_t kMaxMessageBytes =
    std::max({kMaxHeartbeatBytes, kMaxCommandBytes, kMaxCheckpointBytes});

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

// A View in the codec's layout (epoch, seq, config, base, master, failed set, and an
// online configuration where the base is one), for the
// node's persisted state (core/node/wire.cpp). read_view checks what decode() checks of a
// view and records a failure in the reader, naming the field (view.epoch, ...).
void write_view(net::ByteWriter& writer, const View& view);
View read_view(net::ByteReader& reader);

}  // namespace keel::fsm
