#include "core/node/wire.hpp"

#include <type_traits>
#include <variant>

namespace keel::node {

namespace {

template <typename T>
void put(std::vector<std::uint8_t>& out, T value) {
    using U = std::make_unsigned_t<T>;
    const auto bits = static_cast<U>(value);
    for (int shift = static_cast<int>(sizeof(T) * 8) - 8; shift >= 0; shift -= 8) {
        out.push_back(static_cast<std::uint8_t>((bits >> shift) & 0xFFu));
    }
}

// Reads big-endian integers from a span; any read past the end sets failed().
class Reader {
public:
    explicit Reader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

    template <typename T>
    T get() {
        using U = std::make_unsigned_t<T>;
        if (bytes_.size() - offset_ < sizeof(T) || failed_) {
            failed_ = true;
            return T{};
        }
        U value = 0;
        for (std::size_t i = 0; i < sizeof(T); ++i) {
            value = static_cast<U>((value << 8) | bytes_[offset_ + i]);
        }
        offset_ += sizeof(T);
        return static_cast<T>(value);
    }
    std::span<const std::uint8_t> rest() const { return bytes_.subspan(offset_); }
    bool failed() const { return failed_; }
    bool done() const { return offset_ == bytes_.size(); }

private:
    std::span<const std::uint8_t> bytes_;
    std::size_t offset_ = 0;
    bool failed_ = false;
};

template <class... F>
struct Overloaded : F... {
    using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

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
    out.reserve(20 + sample.size_bytes());
    put(out, sample.type_id);
    put(out, sample.sequence);
    put(out, sample.timestamp_ns);
    if (sample.payload) out.insert(out.end(), sample.payload->begin(), sample.payload->end());
    return out;
}

std::optional<tasking::Sample> decode_sample(std::span<const std::uint8_t> bytes,
                                             tasking::PortNumber source_port) {
    Reader reader(bytes);
    tasking::Sample sample;
    sample.type_id = reader.get<std::uint32_t>();
    sample.sequence = reader.get<std::uint64_t>();
    sample.timestamp_ns = reader.get<std::int64_t>();
    if (reader.failed()) return std::nullopt;
    const auto rest = reader.rest();
    sample.payload = tasking::make_payload(std::vector<std::uint8_t>(rest.begin(), rest.end()));
    sample.source_port = source_port;
    return sample;
}

std::vector<std::uint8_t> encode_snapshot(const tasking::Snapshot& snapshot) {
    std::vector<std::uint8_t> out;
    out.reserve(12 + snapshot.payload.size());
    put(out, snapshot.format_version);
    put(out, snapshot.sequence);
    out.insert(out.end(), snapshot.payload.begin(), snapshot.payload.end());
    return out;
}

std::optional<tasking::Snapshot> decode_snapshot(std::span<const std::uint8_t> bytes,
                                                 const std::string& task) {
    Reader reader(bytes);
    tasking::Snapshot snapshot;
    snapshot.task = task;
    snapshot.format_version = reader.get<std::uint32_t>();
    snapshot.sequence = reader.get<std::uint64_t>();
    if (reader.failed()) return std::nullopt;
    const auto rest = reader.rest();
    snapshot.payload.assign(rest.begin(), rest.end());
    return snapshot;
}

std::vector<std::uint8_t> encode_view(const fsm::View& view) {
    std::vector<std::uint8_t> out;
    put(out, view.epoch);
    put(out, view.seq);
    put(out, view.config);
    put(out, view.base);
    put(out, view.master);
    put(out, view.failed.bits());
    return out;
}

std::optional<fsm::View> decode_view(std::span<const std::uint8_t> bytes) {
    Reader reader(bytes);
    fsm::View view;
    view.epoch = reader.get<std::uint32_t>();
    view.seq = reader.get<std::uint32_t>();
    view.config = reader.get<std::uint16_t>();
    view.base = reader.get<std::uint16_t>();
    view.master = reader.get<std::uint8_t>();
    view.failed = fsm::NodeSet::from_bits(reader.get<std::uint64_t>());
    if (reader.failed() || !reader.done()) return std::nullopt;
    return view;
}

}  // namespace keel::node
