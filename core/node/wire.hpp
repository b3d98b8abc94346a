// How a node puts its traffic on the network layer: which transmission type (net
// MessageKind) carries each protocol message, and the byte layouts of what the protocol
// codec does not cover — application samples, task snapshots inside checkpoints, and the
// persisted view.
//
// Every decode_* function never trusts its input: a short or inconsistent byte string is
// std::nullopt, never undefined behaviour.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/fsm/messages.hpp"
#include "core/net/envelope.hpp"
#include "core/tasking/component.hpp"
#include "core/tasking/sample.hpp"

namespace keel::node {

// The paper's transmission type of each protocol message (messages.hpp has the table).
net::MessageKind kind_of(const fsm::Message& message);
// Whether envelopes of this kind carry protocol messages (codec.hpp) rather than samples.
bool carries_protocol(net::MessageKind kind);

// Application sample: type id (4 bytes), sequence (8), timestamp (8), then the payload;
// integers big-endian. The source port travels in the envelope.
inline constexpr std::size_t kSampleHeaderBytes = 4 + 8 + 8;
std::vector<std::uint8_t> encode_sample(const tasking::Sample& sample);
std::optional<tasking::Sample> decode_sample(std::span<const std::uint8_t> bytes,
                                             tasking::PortNumber source_port);

// A task snapshot as the state bytes of a checkpoint: format version (4 bytes), sequence
// (8), then the component's payload. The task name is not stored: the checkpoint's task id
// names it.
std::vector<std::uint8_t> encode_snapshot(const tasking::Snapshot& snapshot);
std::optional<tasking::Snapshot> decode_snapshot(std::span<const std::uint8_t> bytes,
                                                 const std::string& task);

// A View for the node's persistent state (StateDb), in the protocol codec's layout
// (core/fsm/codec.hpp: epoch 4, seq 4, config 2, base 2, master 2, then the failed set as a
// count of words and the words; 15 bytes when no node failed). decode_view says why it
// refused in `why`, naming the field. StateDb records this as view format 2.
std::vector<std::uint8_t> encode_view(const fsm::View& view);
std::optional<fsm::View> decode_view(std::span<const std::uint8_t> bytes, std::string* why = nullptr);
// View format 1, what Keel wrote before its capacity grew past 64 nodes: epoch 4, seq 4,
// config 2, base 2, master 1 (0xFF: none), failed set as one 64-bit word (21 bytes).
// StateDb reads it from databases written then.
std::optional<fsm::View> decode_view_format1(std::span<const std::uint8_t> bytes);

}  // namespace keel::node
