#include "core/fsm/messages.hpp"
#include "core/fsm/overloaded.hpp"

namespace keel::fsm {

const char* to_string(AckKind kind) {
    return kind == AckKind::Prepared ? "Prepared" : "Activated";
}

std::string_view kind_name(std::size_t index) {
    static constexpr std::string_view names[] = {
        "Heartbeat",       "Command",       "Activate",          "Ack",
        "ErrorNotification", "CheckpointWrite", "CheckpointAck", "CheckpointRequest",
        "CheckpointReply", "PhaseRequest"};
    static_assert(std::size(names) == std::variant_size_v<Message>);
    return index < std::size(names) ? names[index] : "unknown";
}

std::string_view kind_name(const Message& message) { return kind_name(message.index()); }

NodeId sender_of(const Message& message) {
    return std::visit([](const auto& value) { return value.from; }, message);
}

bool has_epoch(const Message& message) {
    return !std::holds_alternative<Heartbeat>(message) &&
           !std::holds_alternative<PhaseRequest>(message);
}

Epoch epoch_of(const Message& message) {
    return std::visit(Overloaded{[](const Command& m) { return m.view.epoch; },
                                 [](const PhaseRequest&) { return Epoch{0}; },
                                 [](const auto& m) { return m.epoch; }},
                      message);
}

}  // namespace keel::fsm
