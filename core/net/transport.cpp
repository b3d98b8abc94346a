#include "core/net/transport.hpp"

namespace keel::net {

std::string_view to_string(SendResult result) {
    switch (result) {
        case SendResult::sent: return "sent";
        case SendResult::rejected_invalid: return "rejected_invalid";
        case SendResult::rejected_oversized: return "rejected_oversized";
        case SendResult::failed: return "failed";
    }
    return "invalid_send_result";
}

std::string_view to_string(Role role) {
    switch (role) {
        case Role::unknown: return "unknown";
        case Role::master: return "master";
        case Role::observer: return "observer";
        case Role::worker: return "worker";
        case Role::storage: return "storage";
        case Role::interface: return "interface";
        case Role::resigned: return "resigned";
    }
    return "invalid_role";
}

SendResult Transport::send_to_each(const Envelope& envelope,
                                   std::span<const NodeAddress> destinations) {
    SendResult result = SendResult::sent;
    Envelope each = envelope;
    for (const NodeAddress destination : destinations) {
        each.destination = destination;
        const SendResult sent = send(each);
        if (result == SendResult::sent) result = sent;
    }
    return result;
}

TransportCounters& TransportCounters::operator+=(const TransportCounters& other) {
    sent += other.sent;
    send_failed += other.send_failed;
    received += other.received;
    received_bytes += other.received_bytes;
    dropped_malformed += other.dropped_malformed;
    dropped_oversized += other.dropped_oversized;
    dropped_unknown_sender += other.dropped_unknown_sender;
    dropped_stale_epoch += other.dropped_stale_epoch;
    dropped_forged_sender += other.dropped_forged_sender;
    dropped_replayed += other.dropped_replayed;
    ignored_not_addressed += other.ignored_not_addressed;
    fault_lost += other.fault_lost;
    fault_partitioned += other.fault_partitioned;
    fault_duplicated += other.fault_duplicated;
    fault_delayed += other.fault_delayed;
    deadline_missed += other.deadline_missed;
    return *this;
}

}  // namespace keel::net
