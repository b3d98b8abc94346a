#include "core/fsm/codec.hpp"

#include <memory>
#include <type_traits>

namespace keel::fsm {

namespace {

using net::ByteError;
using net::ByteReader;
using net::ByteWriter;

// The names a view's fields go by in a failure's sentence.
struct ViewFields {
    const char* epoch;
    const char* seq;
    const char* config;
    const char* base;
    const char* master;
    const char* failed;
    const char* online;
};
constexpr ViewFields kViewFields{"view.epoch", "view.seq",    "view.config",
                                 "view.base",  "view.master", "view.failed", "view.online"};
constexpr ViewFields kJointFields{"joint.epoch", "joint.seq",    "joint.config",
                                  "joint.base",  "joint.master", "joint.failed", "joint.online"};

void write_node(ByteWriter& w, NodeId node) { w.u16(node); }
void write_task(ByteWriter& w, TaskId task) { w.u16(task); }

// A node id: below the capacity, or kNoNode where `none_allowed`.
NodeId read_node(ByteReader& r, const char* field, bool none_allowed = true) {
    const NodeId node = r.u16(field);
    if (!r.failed() && node >= kMaxNodes && !(none_allowed && node == kNoNode)) {
        r.fail(ByteError::bad_value, std::string(field) + " " + std::to_string(node) +
                                         " is not a node id (at most " +
                                         std::to_string(kMaxNodes) + " nodes)");
    }
    return node;
}
TaskId read_task(ByteReader& r, const char* field) {
    const TaskId task = r.u16(field);
    if (!r.failed() && task >= kMaxTasks) {
        r.fail(ByteError::bad_value, std::string(field) + " " + std::to_string(task) +
                                         " is not a task id (at most " +
                                         std::to_string(kMaxTasks) + " tasks)");
    }
    return task;
}

// The widths of types.hpp: a larger epoch, switch counter, incarnation or version is
// refused where it is decoded (fault model 3), so none reaches an index or an overflow.
std::uint32_t read_bounded_u32(ByteReader& r, const char* field, std::uint32_t max, const char* what) {
    const std::uint32_t value = r.u32(field);
    if (!r.failed() && value > max) {
        r.fail(ByteError::bad_value, std::string(field) + " " + std::to_string(value) + " exceeds " +
                                         what + " (at most " + std::to_string(max) + ")");
    }
    return value;
}
Epoch read_epoch(ByteReader& r, const char* field) {
    return read_bounded_u32(r, field, kMaxEpoch, "the epoch's 24-bit width");
}
Seq read_seq(ByteReader& r, const char* field) {
    return read_bounded_u32(r, field, kMaxSeq, "the switch counter's width");
}
std::uint32_t read_incarnation(ByteReader& r, const char* field) {
    return read_bounded_u32(r, field, kMaxIncarnation, "the incarnation's width");
}

// A set: the count of words up to its last non-empty one, then those words.
void write_set(ByteWriter& w, const NodeSet& set) {
    const int words = set.used_words();
    w.u8(static_cast<std::uint8_t>(words));
    for (int i = 0; i < words; ++i) w.u64(set.word(i));
}
static_assert(NodeSet::kWords <= 0xFF, "a set's word count fits in its byte");

NodeSet read_set(ByteReader& r, const char* field) {
    NodeSet set;
    const std::uint8_t words = r.u8(field);
    if (r.failed()) return set;
    if (words > NodeSet::kWords) {
        r.fail(ByteError::bad_value, std::string(field) + " has " + std::to_string(words) +
                                         " words, a node set at most " +
                                         std::to_string(NodeSet::kWords));
        return set;
    }
    for (int i = 0; i < words; ++i) set.set_word(i, r.u64(field));
    if (!r.failed() && words > 0 && set.word(words - 1) == 0) {
        r.fail(ByteError::bad_value, std::string(field) + " ends with an empty word (not canonical)");
    }
    return set;
}

// An online configuration (a view whose base is kOnlineConfig, and only then): its phase,
// master, observers (a count, then the ids) and hosts (a count: the mission's tasks, then
// one node per task, kNoNode for a task not placed). Views of the graph keep their bytes.
void write_online(ByteWriter& w, const OnlineConfig& online) {
    w.u8(online.phase);
    write_node(w, online.master);
    w.u16(static_cast<std::uint16_t>(online.observers.size()));
    for (NodeId observer : online.observers) write_node(w, observer);
    w.u16(static_cast<std::uint16_t>(online.host.size()));
    for (NodeId host : online.host) write_node(w, host);
}
OnlinePtr read_online(ByteReader& r, const char* field) {
    auto online = std::make_shared<OnlineConfig>();
    online->phase = r.u8(field);
    online->master = read_node(r, field, false);
    const std::uint16_t observers = r.u16(field);
    if (!r.failed() && observers > kMaxNodes) {
        r.fail(ByteError::bad_value, std::string(field) + " lists " + std::to_string(observers) +
                                         " observers (at most " + std::to_string(kMaxNodes) + " nodes)");
    }
    for (std::uint16_t i = 0; i < observers && !r.failed(); ++i) online->observers.push_back(read_node(r, field, false));
    const std::uint16_t hosts = r.u16(field);
    if (!r.failed() && hosts > kMaxTasks) {
        r.fail(ByteError::bad_value, std::string(field) + " places " + std::to_string(hosts) +
                                         " tasks (at most " + std::to_string(kMaxTasks) + ")");
    }
    for (std::uint16_t i = 0; i < hosts && !r.failed(); ++i) online->host.push_back(read_node(r, field));
    if (r.failed()) return nullptr;
    return OnlinePtr(std::move(online));
}

void write_fields_of(ByteWriter& w, const View& value) {
    w.u32(value.epoch);
    w.u32(value.seq);
    w.u16(value.config);
    w.u16(value.base);
    write_node(w, value.master);
    write_set(w, value.failed);
    if (value.is_online() && value.online) write_online(w, *value.online);
}
View read_view_fields(ByteReader& r, const ViewFields& names) {
    View value;
    value.epoch = read_epoch(r, names.epoch);
    value.seq = read_seq(r, names.seq);
    value.config = r.u16(names.config);
    value.base = r.u16(names.base);
    value.master = read_node(r, names.master);
    value.failed = read_set(r, names.failed);
    if (!r.failed() && value.is_online()) value.online = read_online(r, names.online);
    return value;
}

void write_version(ByteWriter& w, const Version& version) {
    w.u64(version.lineage);
    w.u64(version.count);
}
Version read_version(ByteReader& r) {
    Version version;
    version.lineage = r.u64("lineage");
    version.count = r.u64("version");
    if (r.failed()) return version;
    if (lineage_epoch(version.lineage) > kMaxEpoch || lineage_seq(version.lineage) > kMaxSeq) {
        r.fail(ByteError::bad_value, "lineage " + std::to_string(version.lineage) +
                                         " names no switch (its epoch or switch counter exceeds its width)");
    } else if (version.count > kMaxVersionCount) {
        r.fail(ByteError::bad_value, "version " + std::to_string(version.count) +
                                         " exceeds a signed 64-bit step count (the Storage node's width)");
    }
    return version;
}
std::vector<std::uint8_t> read_state(ByteReader& r) {
    const auto state = r.bytes("state", kMaxStateBytes);
    return {state.begin(), state.end()};
}

void write_fields(ByteWriter& w, const Heartbeat& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    w.u32(m.incarnation);
    w.u32(m.boot);
    w.u32(m.previous_boot);
    w.u64(m.image);
    w.flag(m.waiting);
    w.flag(m.excluded);
    w.u32(m.seq);
    w.u16(static_cast<std::uint16_t>(m.acks.size()));
    for (const HeartbeatAck& ack : m.acks) {
        write_node(w, ack.node);
        w.u32(ack.incarnation);
        w.u32(ack.seq);
    }
    w.flag(m.reply);
    w.u32(m.vote_left_ms);
}
void write_fields(ByteWriter& w, const Command& m) {
    write_node(w, m.from);
    write_fields_of(w, m.view);
    w.u32(m.boot);
    w.u8(static_cast<std::uint8_t>(m.joint.size()));
    for (const View& joint : m.joint) write_fields_of(w, joint);
}
void write_fields(ByteWriter& w, const ActivateCommand& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
}
void write_fields(ByteWriter& w, const Ack& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
    w.u8(static_cast<std::uint8_t>(m.kind));
    w.u64(m.view);
    w.flag(m.reply);
}
void write_fields(ByteWriter& w, const ErrorNotification& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    write_node(w, m.failed_node);
}
void write_fields(ByteWriter& w, const CheckpointWrite& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    write_task(w, m.task);
    write_version(w, m.version);
    w.flag(m.final);
    w.bytes(m.state);
}
void write_fields(ByteWriter& w, const CheckpointAck& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    write_task(w, m.task);
    write_version(w, m.version);
}
void write_fields(ByteWriter& w, const CheckpointRequest& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
    write_task(w, m.task);
}
void write_fields(ByteWriter& w, const CheckpointReply& m) {
    write_node(w, m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
    write_task(w, m.task);
    w.flag(m.found);
    write_version(w, m.version);
    w.bytes(m.state);
}
void write_fields(ByteWriter& w, const PhaseRequest& m) {
    write_node(w, m.from);
    w.u8(m.phase);
}

void read_fields(ByteReader& r, Heartbeat& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.incarnation = read_incarnation(r, "incarnation");
    m.boot = r.u32("boot");
    m.previous_boot = r.u32("previous_boot");
    m.image = r.u64("image");
    m.waiting = r.flag("waiting");
    m.excluded = r.flag("excluded");
    m.seq = r.u32("seq");
    const std::uint16_t count = r.u16("acks");
    if (r.failed()) return;
    if (count > kMaxNodes) {
        r.fail(ByteError::bad_value, "acks count " + std::to_string(count) + " exceeds the " +
                                         std::to_string(kMaxNodes) + "-node limit");
        return;
    }
    m.acks.resize(count);
    for (HeartbeatAck& ack : m.acks) {
        ack.node = read_node(r, "acks.node", false);
        ack.incarnation = read_incarnation(r, "acks.incarnation");
        ack.seq = r.u32("acks.seq");
        if (r.failed()) return;
    }
    m.reply = r.flag("reply");
    m.vote_left_ms = r.u32("vote_left_ms");
}
void read_fields(ByteReader& r, Command& m) {
    m.from = read_node(r, "from");
    m.view = read_view_fields(r, kViewFields);
    m.boot = r.u32("boot");
    const auto count = r.u8("joint.count");
    if (!r.failed() && count > kMaxJointViews) {
        r.fail(ByteError::bad_value, "joint.count " + std::to_string(count) + " exceeds the limit of " +
                                         std::to_string(kMaxJointViews));
        return;
    }
    for (std::size_t i = 0; i < count && !r.failed(); ++i) m.joint.push_back(read_view_fields(r, kJointFields));
}
void read_fields(ByteReader& r, ActivateCommand& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.seq = read_seq(r, "seq");
}
void read_fields(ByteReader& r, Ack& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.seq = read_seq(r, "seq");
    const auto kind = r.u8("kind");
    if (!r.failed() && kind != 1 && kind != 2) {
        r.fail(ByteError::bad_value, "ack kind " + std::to_string(kind) + " is not Prepared or Activated");
    }
    m.kind = static_cast<AckKind>(kind);
    m.view = r.u64("view");
    m.reply = r.flag("reply");
}
void read_fields(ByteReader& r, ErrorNotification& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.failed_node = read_node(r, "failed_node");
}
void read_fields(ByteReader& r, CheckpointWrite& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.task = read_task(r, "task");
    m.version = read_version(r);
    m.final = r.flag("final");
    m.state = read_state(r);
}
void read_fields(ByteReader& r, CheckpointAck& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.task = read_task(r, "task");
    m.version = read_version(r);
}
void read_fields(ByteReader& r, CheckpointRequest& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.seq = read_seq(r, "seq");
    m.task = read_task(r, "task");
}
void read_fields(ByteReader& r, CheckpointReply& m) {
    m.from = read_node(r, "from");
    m.epoch = read_epoch(r, "epoch");
    m.seq = read_seq(r, "seq");
    m.task = read_task(r, "task");
    m.found = r.flag("found");
    m.version = read_version(r);
    m.state = read_state(r);
}
void read_fields(ByteReader& r, PhaseRequest& m) {
    m.from = read_node(r, "from");
    m.phase = r.u8("phase");
}

template <std::size_t I>
bool decode_alternative(std::size_t index, ByteReader& reader, std::optional<Message>& out) {
    if constexpr (I < std::variant_size_v<Message>) {
        if (index == I) {
            std::variant_alternative_t<I, Message> value;
            read_fields(reader, value);
            if (!reader.failed()) out.emplace(std::in_place_index<I>, std::move(value));
            return true;
        }
        return decode_alternative<I + 1>(index, reader, out);
    } else {
        return false;
    }
}

CodecError codec_error(ByteError error) {
    return error == ByteError::bad_value ? CodecError::bad_value : CodecError::truncated;
}

}  // namespace

const char* to_string(CodecError error) {
    switch (error) {
        case CodecError::truncated: return "truncated";
        case CodecError::trailing_bytes: return "trailing-bytes";
        case CodecError::bad_version: return "bad-version";
        case CodecError::bad_kind: return "bad-kind";
        case CodecError::bad_value: return "bad-value";
    }
    return "unknown";
}

void write_view(ByteWriter& writer, const View& view) { write_fields_of(writer, view); }

View read_view(ByteReader& reader) { return read_view_fields(reader, kViewFields); }

void encode_into(const Message& message, std::vector<std::uint8_t>& out) {
    ByteWriter writer(out);
    writer.u8(kCodecVersion);
    writer.u8(static_cast<std::uint8_t>(message.index() + 1));
    std::visit([&](const auto& value) { write_fields(writer, value); }, message);
}

std::vector<std::uint8_t> encode(const Message& message) {
    std::vector<std::uint8_t> out;
    encode_into(message, out);
    return out;
}

DecodedMessage decode(std::span<const std::uint8_t> bytes) {
    DecodedMessage result;
    ByteReader reader(bytes);
    const auto version = reader.u8("version");
    const auto kind = reader.u8("kind");
    if (reader.failed()) {
        result.error = codec_error(reader.error());
        result.detail = reader.detail();
        return result;
    }
    if (version != kCodecVersion) {
        result.error = CodecError::bad_version;
        result.detail = "codec version " + std::to_string(version) + ", expected " +
                        std::to_string(kCodecVersion) +
                        " (a node of another Keel version: every node of a cluster must run one)";
        return result;
    }
    std::optional<Message> message;
    if (kind == 0 || !decode_alternative<0>(kind - 1u, reader, message)) {
        result.error = CodecError::bad_kind;
        result.detail = "message kind " + std::to_string(kind) + " is unknown";
        return result;
    }
    if (reader.failed()) {
        result.error = codec_error(reader.error());
        result.detail = reader.detail();
        return result;
    }
    if (reader.remaining() != 0) {
        result.error = CodecError::trailing_bytes;
        result.detail = std::to_string(reader.remaining()) + " bytes after the message";
        return result;
    }
    result.message = std::move(message);
    return result;
}

}  // namespace keel::fsm
