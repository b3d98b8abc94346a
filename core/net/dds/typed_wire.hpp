// The protocol's typed topics (internal to keel_net_dds): KeelHeartbeat, KeelCommand and
// KeelAck carry the protocol messages as IDL fields (keel.idl), so that a DDS tool shows
// what a node said. Everything above the transport still speaks envelopes whose payload is
// the protocol codec's encoding (core/fsm/codec.hpp): a sample is built from the decoded
// payload when sent, and a received sample becomes the codec's encoding of its message,
// checked by the codec's own decoder, so a sample carries exactly what the codec can say
// and no more.
//
// | kind                    | topic        | messages                                   |
// |-------------------------|--------------|--------------------------------------------|
// | heartbeat               | KeelHeartbeat| Heartbeat                                  |
// | reconfiguration_command | KeelCommand  | Command, ActivateCommand                   |
// | acknowledgement         | KeelAck      | Ack, CheckpointAck, Heartbeat (a reply)    |
//
// Every other kind travels as an envelope of bytes (keel_wire_Message).
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/net/envelope.hpp"
#include "keel.h"  // generated from keel.idl

namespace keel::net::dds::typed {

// The envelope's fields every Keel sample opens with (typed or bytes).
template <class Sample>
void fill_header(Sample& sample, const Envelope& envelope) {
    sample.source = envelope.source;
    sample.destination = envelope.destination;
    sample.port = envelope.port;
    sample.epoch = envelope.epoch;
    sample.sequence_number = envelope.sequence;
}

// The IDL type of `kind`'s topic, or nullptr for a kind that travels as bytes.
const dds_topic_descriptor_t* descriptor(MessageKind kind);
bool is_typed(MessageKind kind);

// A typed sample built from an envelope, with the storage its sequences point into: valid
// until the next build() or the object's end.
class Outgoing {
public:
    // Maps `envelope` (its payload a protocol message its kind's topic carries) to the
    // sample. Returns why not: a payload the codec does not decode, or a message of another
    // topic.
    // `destinations` (a Command's only): every node the one sample is for (the envelope's
    // own destination is then not written).
    std::optional<std::string> build(const Envelope& envelope,
                                     std::span<const NodeAddress> destinations = {});
    const void* sample() const;

private:
    MessageKind kind_ = MessageKind::heartbeat;
    keel_wire_Heartbeat heartbeat_{};
    keel_wire_Command command_{};
    keel_wire_Ack ack_{};
    keel_wire_HeartbeatBody reply_{};
    std::vector<keel_wire_HeartbeatAck> acks_;
    std::vector<keel_wire_View> joint_;
    std::vector<std::vector<std::uint16_t>> failed_;  // each view's failed set
    std::vector<std::vector<std::uint16_t>> online_;  // each view's online configuration, flat
    std::vector<std::uint16_t> destinations_;
};

// The envelope a received typed sample stands for, its payload the codec's encoding of the
// sample's message; or why the sample is refused (EnvelopeError::bad_message).
struct Incoming {
    std::optional<Envelope> envelope;
    std::string error;
};
// `self`: the reading node. A Command written for several nodes (its `destinations`) is
// addressed to `self` when `self` is one of them, else to the first of them (another node);
// without `self` (a tool that reads every node's traffic), to broadcast_address.
Incoming read(MessageKind kind, const void* sample, std::optional<NodeAddress> self = {});

// The envelope fields of a typed sample, for the sender check before the message is read.
struct Header {
    NodeAddress source = 0;
    Sequence sequence = 0;
};
Header header(MessageKind kind, const void* sample);

}  // namespace keel::net::dds::typed
