#include "core/net/dds/typed_wire.hpp"

#include <algorithm>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>

#include "core/fsm/codec.hpp"
#include "core/fsm/messages.hpp"
#include "core/fsm/overloaded.hpp"

namespace keel::net::dds::typed {
namespace {

using fsm::Overloaded;

const char* topic_of(MessageKind kind) {
    switch (kind) {
        case MessageKind::heartbeat: return "KeelHeartbeat";
        case MessageKind::reconfiguration_command: return "KeelCommand";
        default: return "KeelAck";
    }
}

template <class Sample>
Envelope envelope_of(MessageKind kind, const Sample& sample) {
    Envelope envelope;
    envelope.kind = kind;
    envelope.source = sample.source;
    envelope.destination = sample.destination;
    envelope.port = sample.port;
    envelope.epoch = sample.epoch;
    envelope.sequence = sample.sequence_number;
    return envelope;
}

// A sequence borrowing `items` for the duration of dds_write.
template <class Sequence, class Item>
void borrow(Sequence& sequence, std::vector<Item>& items) {
    sequence._buffer = items.data();
    sequence._length = static_cast<std::uint32_t>(items.size());
    sequence._maximum = sequence._length;
    sequence._release = false;
}

keel_wire_HeartbeatBody body_of(const fsm::Heartbeat& heartbeat,
                                std::vector<keel_wire_HeartbeatAck>& acks) {
    acks.clear();
    for (const fsm::HeartbeatAck& ack : heartbeat.acks) {
        acks.push_back({ack.node, ack.incarnation, ack.seq});
    }
    keel_wire_HeartbeatBody body{};
    body.sender = heartbeat.from;
    body.seen_epoch = heartbeat.epoch;
    body.incarnation = heartbeat.incarnation;
    body.boot = heartbeat.boot;
    body.previous_boot = heartbeat.previous_boot;
    body.image = heartbeat.image;
    body.waiting = heartbeat.waiting;
    body.excluded = heartbeat.excluded;
    body.seq = heartbeat.seq;
    body.reply = heartbeat.reply;
    body.vote_left_ms = heartbeat.vote_left_ms;
    borrow(body.acks, acks);
    return body;
}

keel_wire_View view_of(const fsm::View& view, std::vector<std::uint16_t>& failed,
                       std::vector<std::uint16_t>& online) {
    failed.clear();
    online.clear();
    if (view.is_online() && view.online) {
        const fsm::OnlineConfig& config = *view.online;
        online.push_back(config.phase);
        online.push_back(config.master);
        online.push_back(static_cast<std::uint16_t>(config.observers.size()));
        online.insert(online.end(), config.observers.begin(), config.observers.end());
        online.push_back(static_cast<std::uint16_t>(config.host.size()));
        online.insert(online.end(), config.host.begin(), config.host.end());
    }
    for (int node = 0; node < fsm::kMaxNodes; ++node) {
        if (view.failed.contains(static_cast<fsm::NodeId>(node))) {
            failed.push_back(static_cast<std::uint16_t>(node));
        }
    }
    keel_wire_View out{};
    out.epoch = view.epoch;
    out.seq = view.seq;
    out.configuration = view.config;
    out.base = view.base;
    out.master = view.master;
    borrow(out.failed, failed);
    borrow(out.online, online);
    return out;
}

// Reading: a sample's fields as a protocol message. What the codec's decoder checks is
// left to it; here only what could not be represented at all (a set member beyond the
// capacity, an enum value outside its IDL enum, more entries than the codec counts).
struct Refused {
    std::string why;
};

fsm::Heartbeat heartbeat_of(const keel_wire_HeartbeatBody& body) {
    if (body.acks._length > static_cast<std::uint32_t>(fsm::kMaxNodes)) {
        throw Refused{"a heartbeat with " + std::to_string(body.acks._length) +
                      " acknowledgements (at most " + std::to_string(fsm::kMaxNodes) + ")"};
    }
    fsm::Heartbeat heartbeat;
    heartbeat.from = body.sender;
    heartbeat.epoch = body.seen_epoch;
    heartbeat.incarnation = body.incarnation;
    heartbeat.boot = body.boot;
    heartbeat.previous_boot = body.previous_boot;
    heartbeat.image = body.image;
    heartbeat.waiting = body.waiting;
    heartbeat.excluded = body.excluded;
    heartbeat.seq = body.seq;
    heartbeat.reply = body.reply;
    heartbeat.vote_left_ms = body.vote_left_ms;
    for (std::uint32_t i = 0; i < body.acks._length; ++i) {
        const keel_wire_HeartbeatAck& ack = body.acks._buffer[i];
        heartbeat.acks.push_back({ack.node, ack.incarnation, ack.seq});
    }
    return heartbeat;
}

fsm::View view_from(const keel_wire_View& raw, const char* which) {
    fsm::View view;
    view.epoch = raw.epoch;
    view.seq = raw.seq;
    view.config = raw.configuration;
    view.base = raw.base;
    view.master = raw.master;
    for (std::uint32_t i = 0; i < raw.failed._length; ++i) {
        const std::uint16_t node = raw.failed._buffer[i];
        if (node >= fsm::kMaxNodes) {
            throw Refused{std::string(which) + ".failed names node " + std::to_string(node) +
                          " (the capacity is " + std::to_string(fsm::kMaxNodes) + " nodes)"};
        }
        view.failed.insert(node);
    }
    // The flat online configuration; its ids are bounded by the codec's decoder and the
    // mission (admission.hpp) after this.
    const std::uint32_t length = raw.online._length;
    if (length == 0) return view;
    const std::uint16_t* flat = raw.online._buffer;
    const auto refuse = [&] {
        return Refused{std::string(which) + ".online does not hold a configuration (" + std::to_string(length) +
                       " entries)"};
    };
    if (length < 4) throw refuse();
    if (flat[0] > 0xFF) throw refuse();
    auto online = std::make_shared<fsm::OnlineConfig>();
    online->phase = static_cast<fsm::PhaseId>(flat[0]);
    online->master = flat[1];
    const std::uint32_t observers = flat[2];
    if (observers > static_cast<std::uint32_t>(fsm::kMaxNodes) || 3 + observers + 1 > length) throw refuse();
    online->observers.assign(flat + 3, flat + 3 + observers);
    const std::uint32_t hosts = flat[3 + observers];
    if (hosts > static_cast<std::uint32_t>(fsm::kMaxTasks) || 4 + observers + hosts != length) throw refuse();
    online->host.assign(flat + 4 + observers, flat + 4 + observers + hosts);
    view.online = fsm::OnlinePtr(std::move(online));
    return view;
}

fsm::Message message_of(MessageKind kind, const void* sample) {
    switch (kind) {
        case MessageKind::heartbeat:
            return heartbeat_of(static_cast<const keel_wire_Heartbeat*>(sample)->body);
        case MessageKind::reconfiguration_command: {
            const auto& raw = *static_cast<const keel_wire_Command*>(sample);
            if (raw.kind == keel_wire_COMMAND_ACTIVATE) {
                return fsm::ActivateCommand{raw.sender, raw.activate_epoch, raw.activate_seq};
            }
            if (raw.kind != keel_wire_COMMAND_SWITCH) {
                throw Refused{"command kind " + std::to_string(static_cast<int>(raw.kind)) +
                              " is none of CommandKind"};
            }
            if (raw.joint._length > fsm::kMaxJointViews) {
                throw Refused{"a command with " + std::to_string(raw.joint._length) +
                              " joint views (at most " + std::to_string(fsm::kMaxJointViews) + ")"};
            }
            std::vector<fsm::View> joint;
            for (std::uint32_t i = 0; i < raw.joint._length; ++i) {
                joint.push_back(view_from(raw.joint._buffer[i], "joint"));
            }
            fsm::Command command(raw.sender, view_from(raw.adopted, "adopted"), std::move(joint));
            command.boot = raw.handed_boot;
            return command;
        }
        default: {
            const auto& raw = *static_cast<const keel_wire_Ack*>(sample);
            switch (raw.kind) {
                case keel_wire_ACK_PREPARED:
                case keel_wire_ACK_ACTIVATED:
                    return fsm::Ack{raw.sender, raw.ack_epoch, raw.seq,
                                    raw.kind == keel_wire_ACK_PREPARED ? fsm::AckKind::Prepared
                                                                       : fsm::AckKind::Activated,
                                    raw.view, raw.prepared_reply};
                case keel_wire_ACK_CHECKPOINT:
                    return fsm::CheckpointAck{raw.sender, raw.ack_epoch, raw.task,
                                              fsm::Version(raw.lineage, raw.count)};
                case keel_wire_ACK_HEARTBEAT:
                    if (raw.heartbeat_reply._length != 1) {
                        throw Refused{"a heartbeat acknowledgement without its heartbeat"};
                    }
                    return heartbeat_of(raw.heartbeat_reply._buffer[0]);
            }
            throw Refused{"acknowledgement kind " + std::to_string(static_cast<int>(raw.kind)) +
                          " is none of AckKind"};
        }
    }
}

}  // namespace

const dds_topic_descriptor_t* descriptor(MessageKind kind) {
    switch (kind) {
        case MessageKind::heartbeat: return &keel_wire_Heartbeat_desc;
        case MessageKind::reconfiguration_command: return &keel_wire_Command_desc;
        case MessageKind::acknowledgement: return &keel_wire_Ack_desc;
        default: return nullptr;
    }
}

bool is_typed(MessageKind kind) { return descriptor(kind) != nullptr; }

std::optional<std::string> Outgoing::build(const Envelope& envelope,
                                           std::span<const NodeAddress> destinations) {
    kind_ = envelope.kind;
    const fsm::DecodedMessage decoded = fsm::decode(envelope.payload);
    if (!decoded.ok()) {
        return std::string("the payload is not a protocol message (") +
               fsm::to_string(decoded.error) + ": " + decoded.detail + ")";
    }
    const fsm::Message& message = *decoded.message;
    const auto wrong_topic = [&] {
        return std::string("a ") + std::string(fsm::kind_name(message)) + " does not travel on " +
               topic_of(kind_);
    };
    switch (kind_) {
        case MessageKind::heartbeat: {
            const auto* heartbeat = std::get_if<fsm::Heartbeat>(&message);
            if (heartbeat == nullptr) return wrong_topic();
            heartbeat_ = keel_wire_Heartbeat{};
            fill_header(heartbeat_, envelope);
            heartbeat_.body = body_of(*heartbeat, acks_);
            return std::nullopt;
        }
        case MessageKind::reconfiguration_command: {
            command_ = keel_wire_Command{};
            fill_header(command_, envelope);
            if (!destinations.empty()) {
                command_.destination = broadcast_address;
                destinations_.assign(destinations.begin(), destinations.end());
                borrow(command_.destinations, destinations_);
            }
            if (const auto* activate = std::get_if<fsm::ActivateCommand>(&message)) {
                command_.kind = keel_wire_COMMAND_ACTIVATE;
                command_.sender = activate->from;
                command_.activate_epoch = activate->epoch;
                command_.activate_seq = activate->seq;
                failed_.assign(1, {});
                online_.assign(1, {});
                command_.adopted = view_of(fsm::View{}, failed_[0], online_[0]);
                return std::nullopt;
            }
            const auto* switching = std::get_if<fsm::Command>(&message);
            if (switching == nullptr) return wrong_topic();
            command_.kind = keel_wire_COMMAND_SWITCH;
            command_.sender = switching->from;
            command_.handed_boot = switching->boot;
            // Every view's failed list and online configuration first (the vector of lists must not grow while the
            // views point into it), then the views.
            failed_.assign(1 + switching->joint.size(), {});
            online_.assign(1 + switching->joint.size(), {});
            command_.adopted = view_of(switching->view, failed_[0], online_[0]);
            joint_.clear();
            for (std::size_t i = 0; i < switching->joint.size(); ++i) {
                joint_.push_back(view_of(switching->joint[i], failed_[i + 1], online_[i + 1]));
            }
            borrow(command_.joint, joint_);
            return std::nullopt;
        }
        case MessageKind::acknowledgement: {
            ack_ = keel_wire_Ack{};
            fill_header(ack_, envelope);
            return std::visit(
                Overloaded{
                    [&](const fsm::Ack& a) -> std::optional<std::string> {
                        ack_.kind = a.kind == fsm::AckKind::Prepared ? keel_wire_ACK_PREPARED
                                                                     : keel_wire_ACK_ACTIVATED;
                        ack_.sender = a.from;
                        ack_.ack_epoch = a.epoch;
                        ack_.seq = a.seq;
                        ack_.view = a.view;
                        ack_.prepared_reply = a.reply;
                        return std::nullopt;
                    },
                    [&](const fsm::CheckpointAck& a) -> std::optional<std::string> {
                        ack_.kind = keel_wire_ACK_CHECKPOINT;
                        ack_.sender = a.from;
                        ack_.ack_epoch = a.epoch;
                        ack_.task = a.task;
                        ack_.lineage = a.version.lineage;
                        ack_.count = a.version.count;
                        return std::nullopt;
                    },
                    [&](const fsm::Heartbeat& h) -> std::optional<std::string> {
                        ack_.kind = keel_wire_ACK_HEARTBEAT;
                        ack_.sender = h.from;
                        reply_ = body_of(h, acks_);
                        ack_.heartbeat_reply._buffer = &reply_;
                        ack_.heartbeat_reply._length = 1;
                        ack_.heartbeat_reply._maximum = 1;
                        ack_.heartbeat_reply._release = false;
                        return std::nullopt;
                    },
                    [&](const auto&) -> std::optional<std::string> { return wrong_topic(); },
                },
                message);
        }
        default:
            return std::string("kind ") + std::string(to_string(kind_)) + " has no typed topic";
    }
}

const void* Outgoing::sample() const {
    switch (kind_) {
        case MessageKind::heartbeat: return &heartbeat_;
        case MessageKind::reconfiguration_command: return &command_;
        default: return &ack_;
    }
}

Header header(MessageKind kind, const void* sample) {
    switch (kind) {
        case MessageKind::heartbeat: {
            const auto& raw = *static_cast<const keel_wire_Heartbeat*>(sample);
            return {raw.source, raw.sequence_number};
        }
        case MessageKind::reconfiguration_command: {
            const auto& raw = *static_cast<const keel_wire_Command*>(sample);
            return {raw.source, raw.sequence_number};
        }
        default: {
            const auto& raw = *static_cast<const keel_wire_Ack*>(sample);
            return {raw.source, raw.sequence_number};
        }
    }
}

Incoming read(MessageKind kind, const void* sample, std::optional<NodeAddress> self) {
    Incoming out;
    Envelope envelope;
    switch (kind) {
        case MessageKind::heartbeat:
            envelope = envelope_of(kind, *static_cast<const keel_wire_Heartbeat*>(sample));
            break;
        case MessageKind::reconfiguration_command: {
            const auto& raw = *static_cast<const keel_wire_Command*>(sample);
            envelope = envelope_of(kind, raw);
            const std::uint32_t listed = raw.destinations._length;
            if (listed == 0) break;
            if (listed > static_cast<std::uint32_t>(fsm::kMaxNodes) || raw.destinations._buffer == nullptr) {
                out.error = "a command for " + std::to_string(listed) + " destinations (at most " +
                            std::to_string(fsm::kMaxNodes) + ")";
                return out;
            }
            if (raw.destination != broadcast_address) {
                out.error = "a command for a list of destinations names destination " +
                            std::to_string(raw.destination) + ", not broadcast";
                return out;
            }
            const std::span<const std::uint16_t> list(raw.destinations._buffer, listed);
            if (std::ranges::find(list, broadcast_address) != list.end()) {
                out.error = "a command's list of destinations names broadcast";
                return out;
            }
            if (!self) break;  // a tool: the sample is for several nodes
            envelope.destination =
                std::ranges::find(list, *self) != list.end() ? *self : list.front();
            break;
        }
        default:
            envelope = envelope_of(kind, *static_cast<const keel_wire_Ack*>(sample));
            break;
    }
    try {
        envelope.payload = fsm::encode(message_of(kind, sample));
    } catch (const Refused& refused) {
        out.error = refused.why;
        return out;
    }
    // The codec's decoder checks every field (ids within the capacity, canonical sets,
    // enum values): what it refuses, this topic refuses.
    const fsm::DecodedMessage checked = fsm::decode(envelope.payload);
    if (!checked.ok()) {
        out.error = std::string(fsm::to_string(checked.error)) + ": " + checked.detail;
        return out;
    }
    out.envelope = std::move(envelope);
    return out;
}

}  // namespace keel::net::dds::typed
