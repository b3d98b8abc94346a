#include "core/fsm/codec.hpp"

#include <type_traits>

namespace keel::fsm {

namespace {

class Writer {
public:
    explicit Writer(std::vector<std::uint8_t>& out) : out_(out) {}
    void u8(std::uint8_t value) { out_.push_back(value); }
    void u16(std::uint16_t value) { put(value, 2); }
    void u32(std::uint32_t value) { put(value, 4); }
    void u64(std::uint64_t value) { put(value, 8); }
    void flag(bool value) { u8(value ? 1 : 0); }
    void bytes(const std::vector<std::uint8_t>& value) {
        u32(static_cast<std::uint32_t>(value.size()));
        out_.insert(out_.end(), value.begin(), value.end());
    }
    void view(const View& value) {
        u32(value.epoch);
        u32(value.seq);
        u16(value.config);
        u16(value.base);
        u8(value.master);
        u64(value.failed.bits());
    }

private:
    void put(std::uint64_t value, int width) {
        for (int shift = (width - 1) * 8; shift >= 0; shift -= 8) {
            out_.push_back(static_cast<std::uint8_t>(value >> shift));
        }
    }
    std::vector<std::uint8_t>& out_;
};

class Reader {
public:
    explicit Reader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

    bool failed() const { return error_.has_value(); }
    CodecError error() const { return *error_; }
    const std::string& detail() const { return detail_; }
    std::size_t remaining() const { return bytes_.size() - position_; }

    std::uint8_t u8(const char* field) { return static_cast<std::uint8_t>(get(1, field)); }
    std::uint16_t u16(const char* field) { return static_cast<std::uint16_t>(get(2, field)); }
    std::uint32_t u32(const char* field) { return static_cast<std::uint32_t>(get(4, field)); }
    std::uint64_t u64(const char* field) { return get(8, field); }
    bool flag(const char* field) {
        const auto raw = u8(field);
        if (!failed() && raw > 1) fail(CodecError::bad_value, std::string(field) + " is not 0 or 1");
        return raw == 1;
    }
    std::vector<std::uint8_t> bytes(const char* field) {
        const auto length = u32(field);
        if (failed()) return {};
        if (length > kMaxStateBytes) {
            fail(CodecError::bad_value, std::string(field) + " length " + std::to_string(length) +
                                            " exceeds the limit");
            return {};
        }
        if (length > remaining()) {
            fail(CodecError::truncated, std::string(field) + " declares " + std::to_string(length) +
                                            " bytes, " + std::to_string(remaining()) + " remain");
            return {};
        }
        std::vector<std::uint8_t> value(bytes_.begin() + static_cast<std::ptrdiff_t>(position_),
                                        bytes_.begin() + static_cast<std::ptrdiff_t>(position_ + length));
        position_ += length;
        return value;
    }
    View view() {
        View value;
        value.epoch = u32("view.epoch");
        value.seq = u32("view.seq");
        value.config = u16("view.config");
        value.base = u16("view.base");
        value.master = u8("view.master");
        value.failed = NodeSet::from_bits(u64("view.failed"));
        return value;
    }
    void fail(CodecError error, std::string detail) {
        if (error_) return;
        error_ = error;
        detail_ = std::move(detail);
    }

private:
    std::uint64_t get(int width, const char* field) {
        if (failed()) return 0;
        if (remaining() < static_cast<std::size_t>(width)) {
            fail(CodecError::truncated, std::string("input ends inside ") + field);
            return 0;
        }
        std::uint64_t value = 0;
        for (int i = 0; i < width; ++i) value = (value << 8) | bytes_[position_++];
        return value;
    }

    std::span<const std::uint8_t> bytes_;
    std::size_t position_ = 0;
    std::optional<CodecError> error_;
    std::string detail_;
};

void write_fields(Writer& w, const Heartbeat& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u32(m.incarnation);
    w.flag(m.excluded);
    w.u32(m.seq);
    w.u8(static_cast<std::uint8_t>(m.acks.size()));
    for (const HeartbeatAck& ack : m.acks) {
        w.u8(ack.node);
        w.u32(ack.incarnation);
        w.u32(ack.seq);
    }
    w.flag(m.reply);
}
void write_fields(Writer& w, const Command& m) {
    w.u8(m.from);
    w.view(m.view);
    w.u8(static_cast<std::uint8_t>(m.joint.size()));
    for (const View& joint : m.joint) w.view(joint);
}
void write_fields(Writer& w, const ActivateCommand& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
}
void write_fields(Writer& w, const Ack& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
    w.u8(static_cast<std::uint8_t>(m.kind));
}
void write_fields(Writer& w, const ErrorNotification& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u8(m.failed_node);
}
void write_fields(Writer& w, const CheckpointWrite& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u8(m.task);
    w.u64(m.version.lineage);
    w.u64(m.version.count);
    w.flag(m.final);
    w.bytes(m.state);
}
void write_fields(Writer& w, const CheckpointAck& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u8(m.task);
    w.u64(m.version.lineage);
    w.u64(m.version.count);
}
void write_fields(Writer& w, const CheckpointRequest& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
    w.u8(m.task);
}
void write_fields(Writer& w, const CheckpointReply& m) {
    w.u8(m.from);
    w.u32(m.epoch);
    w.u32(m.seq);
    w.u8(m.task);
    w.flag(m.found);
    w.u64(m.version.lineage);
    w.u64(m.version.count);
    w.bytes(m.state);
}
void write_fields(Writer& w, const PhaseRequest& m) {
    w.u8(m.from);
    w.u8(m.phase);
}

void read_fields(Reader& r, Heartbeat& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.incarnation = r.u32("incarnation");
    m.excluded = r.flag("excluded");
    m.seq = r.u32("seq");
    const std::uint8_t count = r.u8("acks");
    if (r.failed()) return;
    if (count > kMaxNodes) {
        r.fail(CodecError::bad_value, "acks count " + std::to_string(count) + " exceeds the " +
                                          std::to_string(kMaxNodes) + "-node limit");
        return;
    }
    m.acks.resize(count);
    for (HeartbeatAck& ack : m.acks) {
        ack.node = r.u8("acks.node");
        ack.incarnation = r.u32("acks.incarnation");
        ack.seq = r.u32("acks.seq");
        if (!r.failed() && ack.node >= kMaxNodes) {
            r.fail(CodecError::bad_value, "acks.node " + std::to_string(ack.node) + " is not a node id");
            return;
        }
    }
    m.reply = r.flag("reply");
}
void read_fields(Reader& r, Command& m) {
    m.from = r.u8("from");
    m.view = r.view();
    const auto count = r.u8("joint.count");
    if (!r.failed() && count > kMaxJointViews) {
        r.fail(CodecError::bad_value, "joint.count " + std::to_string(count) + " exceeds the limit of " +
                                          std::to_string(kMaxJointViews));
        return;
    }
    for (std::size_t i = 0; i < count && !r.failed(); ++i) m.joint.push_back(r.view());
}
void read_fields(Reader& r, ActivateCommand& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.seq = r.u32("seq");
}
void read_fields(Reader& r, Ack& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.seq = r.u32("seq");
    const auto kind = r.u8("kind");
    if (!r.failed() && kind != 1 && kind != 2) {
        r.fail(CodecError::bad_value, "ack kind " + std::to_string(kind) + " is not Prepared or Activated");
    }
    m.kind = static_cast<AckKind>(kind);
}
void read_fields(Reader& r, ErrorNotification& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.failed_node = r.u8("failed_node");
}
void read_fields(Reader& r, CheckpointWrite& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.task = r.u8("task");
    m.version.lineage = r.u64("lineage");
    m.version.count = r.u64("version");
    m.final = r.flag("final");
    m.state = r.bytes("state");
}
void read_fields(Reader& r, CheckpointAck& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.task = r.u8("task");
    m.version.lineage = r.u64("lineage");
    m.version.count = r.u64("version");
}
void read_fields(Reader& r, CheckpointRequest& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.seq = r.u32("seq");
    m.task = r.u8("task");
}
void read_fields(Reader& r, CheckpointReply& m) {
    m.from = r.u8("from");
    m.epoch = r.u32("epoch");
    m.seq = r.u32("seq");
    m.task = r.u8("task");
    m.found = r.flag("found");
    m.version.lineage = r.u64("lineage");
    m.version.count = r.u64("version");
    m.state = r.bytes("state");
}
void read_fields(Reader& r, PhaseRequest& m) {
    m.from = r.u8("from");
    m.phase = r.u8("phase");
}

template <std::size_t I>
bool decode_alternative(std::size_t index, Reader& reader, std::optional<Message>& out) {
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

void encode_into(const Message& message, std::vector<std::uint8_t>& out) {
    Writer writer(out);
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
    Reader reader(bytes);
    const auto version = reader.u8("version");
    const auto kind = reader.u8("kind");
    if (reader.failed()) {
        result.error = reader.error();
        result.detail = reader.detail();
        return result;
    }
    if (version != kCodecVersion) {
        result.error = CodecError::bad_version;
        result.detail = "codec version " + std::to_string(version) + ", expected " +
                        std::to_string(kCodecVersion);
        return result;
    }
    std::optional<Message> message;
    if (kind == 0 || !decode_alternative<0>(kind - 1u, reader, message)) {
        result.error = CodecError::bad_kind;
        result.detail = "message kind " + std::to_string(kind) + " is unknown";
        return result;
    }
    if (reader.failed()) {
        result.error = reader.error();
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
