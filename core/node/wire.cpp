#include "core/node/wire.hpp"

#include <variant>

#include "core/fsm/codec.hpp"
#include "core/fsm/overloaded.hpp"
#include "core/net/bytes.hpp"

namespace keel::node {

// The network layer must carry what the protocol's capacity needs (core/fsm/types.hpp):
// every node id as an address other than the broadcast one, and the largest message.
static_assert(fsm::kMaxNodes - 1 < net::broadcast_address &&
                  sizeof(net::NodeAddress) >= sizeof(fsm::NodeId),
              "every node id is a node address");
static_assert(fsm::kMaxMessageBytes <= net::default_max_payload_bytes,
              "the largest protocol message fits in an envelope");

namespace {

using net::ByteReader;
using net::ByteWriter;
using fsm::Overloaded;

}  // namespace

net::MessageKind kind_of(const fsm::Message& message) {
    using K = net::MessageKind;
    return std::visit(
        Overloaded{
            [](const fsm::Heartbeat& heartbeat) { return heartbeat.reply ? K::acknowledgement : K::heartbeat; },
            [](const fsm::Command&) { return K::reconfiguration_command; },
            [](const fsm::ActivateCommand&) { return K::reconfiguration_command; },
            // A request, not a command: any node may forward one (an interface node relays
            // the ground's), while only processing nodes may write commands (DDS Security
            // permissions, nodes/cluster/README.md "Security").
            [](const fsm::PhaseRequest&) { return K::request; },
            [](const fsm::Ack&) { return K::acknowledgement; },
            [](const fsm::CheckpointAck&) { return K::acknowledgement; },
            [](const fsm::ErrorNotification&) { return K::error_notification; },
            [](const fsm::CheckpointWrite&) { return K::reliable_data; },
            [](const fsm::CheckpointRequest&) { return K::request; },
            [](const fsm::CheckpointReply&) { return K::response; },
        },
        message);
}

bool carries_protocol(net::MessageKind kind) {
    return kind != net::MessageKind::unreliable_data && kind != net::MessageKind::large;
}

std::vector<std::uint8_t> encode_sample(const tasking::Sample& sample) {
    std::vector<std::uint8_t> out;
    out.reserve(kSampleHeaderBytes + sample.size_bytes());
    ByteWriter writer(out);
    writer.u32(sample.type_id);
    writer.u64(sample.sequence);
    writer.i64(sample.timestamp_ns);
    if (sample.payload) writer.raw(*sample.payload);
    return out;
}

std::optional<tasking::Sample> decode_sample(std::span<const std::uint8_t> bytes,
                                             tasking::PortNumber source_port) {
    ByteReader reader(bytes);
    tasking::Sample sample;
    sample.type_id = reader.u32("type_id");
    sample.sequence = reader.u64("sequence");
    sample.timestamp_ns = reader.i64("timestamp_ns");
    const auto rest = reader.rest();
    if (reader.failed()) return std::nullopt;
    sample.payload = tasking::make_payload(std::vector<std::uint8_t>(rest.begin(), rest.end()));
    sample.source_port = source_port;
    return sample;
}

std::vector<std::uint8_t> encode_snapshot(const tasking::Snapshot& snapshot) {
    std::vector<std::uint8_t> out;
    out.reserve(fsm::kSnapshotHeaderBytes + snapshot.payload.size());
    ByteWriter writer(out);
    writer.u32(snapshot.format_version);
    writer.u64(snapshot.sequence);
    writer.raw(snapshot.payload);
    return out;
}

std::optional<tasking::Snapshot> decode_snapshot(std::span<const std::uint8_t> bytes,
                                                 const std::string& task) {
    ByteReader reader(bytes);
    tasking::Snapshot snapshot;
    snapshot.task = task;
    snapshot.format_version = reader.u32("format_version");
    snapshot.sequence = reader.u64("sequence");
    const auto rest = reader.rest();
    if (reader.failed()) return std::nullopt;
    snapshot.payload.assign(rest.begin(), rest.end());
    return snapshot;
}

std::vector<std::uint8_t> encode_view(const fsm::View& view) {
    std::vector<std::uint8_t> out;
    ByteWriter writer(out);
    fsm::write_view(writer, view);
    return out;
}

std::optional<fsm::View> decode_view(std::span<const std::uint8_t> bytes, std::string* why) {
    ByteReader reader(bytes);
    const fsm::View view = fsm::read_view(reader);
    if (!reader.failed() && !reader.at_end()) {
        reader.fail(net::ByteError::bad_value,
                    std::to_string(reader.remaining()) + " bytes after the view");
    }
    if (reader.failed()) {
        if (why != nullptr) *why = reader.detail();
        return std::nullopt;
    }
    return view;
}

std::optional<fsm::View> decode_view_format1(std::span<const std::uint8_t> bytes) {
    ByteReader reader(bytes);
    fsm::View view;
    view.epoch = reader.u32("view.epoch");
    view.seq = reader.u32("view.seq");
    view.config = reader.u16("view.config");
    view.base = reader.u16("view.base");
    const std::uint8_t master = reader.u8("view.master");
    const std::uint64_t failed = reader.u64("view.failed");
    if (reader.failed() || !reader.at_end()) return std::nullopt;
    // Format 1 held at most 64 nodes, with 0xFF for "no node".
    view.master = master == 0xFF ? fsm::kNoNode : fsm::NodeId{master};
    view.failed.set_word(0, failed);
    return view;
}

}  // namespace keel::node
