#include "core/net/endpoint.hpp"

#include <spdlog/spdlog.h>

#include <stdexcept>
#include <utility>

namespace keel::net {

namespace {

std::shared_ptr<spdlog::logger> logger_named(const std::string& name) {
    if (auto existing = spdlog::get(name)) return existing;
    auto created = spdlog::default_logger()->clone(name);
    try {
        spdlog::register_logger(created);
    } catch (const spdlog::spdlog_ex&) {
        // Another thread registered the same name first; use that one.
        if (auto existing = spdlog::get(name)) return existing;
    }
    return created;
}

std::string describe(const Envelope& envelope) {
    return std::string(to_string(envelope.kind)) + " from node " +
           std::to_string(envelope.source) + " to " + std::to_string(envelope.destination) +
           " port " + std::to_string(envelope.port) + " epoch " +
           std::to_string(envelope.epoch) + " seq " + std::to_string(envelope.sequence);
}

}  // namespace

ReceiveFilter::ReceiveFilter(NodeAddress local_address, FilterConfig config)
    : local_address_(local_address),
      config_(std::move(config)),
      logger_(logger_named(config_.log_name)) {}

void ReceiveFilter::set_known_nodes(std::set<NodeAddress> known_nodes) {
    config_.known_nodes = std::move(known_nodes);
}

void ReceiveFilter::log_drop(const char* reason, std::uint64_t count, const std::string& text) {
    if (log_this_drop(count)) {
        logger_->warn("node {}: dropped {} message (#{}): {}", local_address_, reason, count,
                      text);
    }
}

std::optional<Envelope> ReceiveFilter::admit(Inbound&& item) {
    if (!item.ok) {
        if (item.error == EnvelopeError::forged_sender) {
            log_drop("forged-sender", ++dropped_forged_sender_, item.detail + " [" + item.origin + "]");
        } else if (item.error == EnvelopeError::replayed) {
            log_drop("replayed", ++dropped_replayed_, item.detail + " [" + item.origin + "]");
        } else if (item.error == EnvelopeError::oversized) {
            log_drop("oversized", ++dropped_oversized_, item.detail + " [" + item.origin + "]");
        } else {
            log_drop("malformed", ++dropped_malformed_,
                     std::string(to_string(item.error)) + ": " + item.detail + " [" +
                         item.origin + "]");
        }
        return std::nullopt;
    }
    Envelope& envelope = item.envelope;
    // Transports that do not decode bytes (DDS samples) hand up fields that still need checks.
    if (auto problem = validate(envelope, config_.limits)) {
        if (problem->error == EnvelopeError::oversized) {
            log_drop("oversized", ++dropped_oversized_, problem->detail + " [" + item.origin + "]");
        } else {
            log_drop("malformed", ++dropped_malformed_,
                     std::string(to_string(problem->error)) + ": " + problem->detail + " [" +
                         item.origin + "]");
        }
        return std::nullopt;
    }
    if (!config_.known_nodes.contains(envelope.source)) {
        log_drop("unknown-sender", ++dropped_unknown_sender_, describe(envelope));
        return std::nullopt;
    }
    // Heartbeats are never stale (core/fsm/heartbeat_monitor.hpp): a node still at an older
    // epoch must be heard, or a Master could never fence a node it excluded after a partition.
    if (envelope.kind != MessageKind::heartbeat && envelope.epoch < epoch_floor_.load()) {
        log_drop("stale-epoch", ++dropped_stale_epoch_,
                 describe(envelope) + " below floor " + std::to_string(epoch_floor_.load()));
        return std::nullopt;
    }
    if (envelope.source == local_address_ ||
        (envelope.destination != local_address_ && envelope.destination != broadcast_address)) {
        ++ignored_not_addressed_;
        return std::nullopt;
    }
    ++received_;
    return std::move(envelope);
}

TransportCounters ReceiveFilter::counters() const {
    TransportCounters counters;
    counters.received = received_.load();
    counters.dropped_malformed = dropped_malformed_.load();
    counters.dropped_oversized = dropped_oversized_.load();
    counters.dropped_unknown_sender = dropped_unknown_sender_.load();
    counters.dropped_stale_epoch = dropped_stale_epoch_.load();
    counters.dropped_forged_sender = dropped_forged_sender_.load();
    counters.dropped_replayed = dropped_replayed_.load();
    counters.ignored_not_addressed = ignored_not_addressed_.load();
    return counters;
}

Endpoint::Endpoint(std::unique_ptr<Transport> transport, FilterConfig config)
    : transport_(std::move(transport)),
      filter_(transport_ ? transport_->local_address() : NodeAddress{0}, config),
      limits_(config.limits) {
    if (!transport_) throw std::invalid_argument("Endpoint needs a transport");
    batch_.reserve(256);
}

Envelope Endpoint::make_envelope(MessageKind kind, NodeAddress destination, Port port,
                                 std::vector<std::uint8_t> payload) {
    Envelope envelope;
    envelope.kind = kind;
    envelope.source = local_address();
    envelope.destination = destination;
    envelope.port = port;
    envelope.epoch = local_epoch_;
    envelope.sequence = next_sequence_++;
    envelope.payload = std::move(payload);
    return envelope;
}

std::optional<SendResult> Endpoint::refusal(const Envelope& envelope) {
    if (envelope.source != local_address()) {
        ++send_refused_;
        return SendResult::rejected_invalid;
    }
    if (auto problem = validate(envelope, limits_)) {
        ++send_refused_;
        return problem->error == EnvelopeError::oversized ? SendResult::rejected_oversized
                                                          : SendResult::rejected_invalid;
    }
    return std::nullopt;
}

SendResult Endpoint::send(const Envelope& envelope) {
    if (auto refused = refusal(envelope)) return *refused;
    return transport_->send(envelope);
}

SendResult Endpoint::send_to_each(const Envelope& envelope,
                                  std::span<const NodeAddress> destinations) {
    // validate() has no rule on a destination: the envelope's fields stand for every one.
    if (auto refused = refusal(envelope)) return *refused;
    return transport_->send_to_each(envelope, destinations);
}

std::size_t Endpoint::poll(const std::function<void(Envelope&&)>& deliver,
                           std::size_t max_items) {
    std::size_t delivered = 0;
    // Bounded work per call: at most max_items raw items are taken from the transport.
    batch_.clear();
    transport_->receive(batch_, max_items);
    for (Inbound& item : batch_) {
        if (auto envelope = filter_.admit(std::move(item))) {
            deliver(std::move(*envelope));
            ++delivered;
        }
    }
    batch_.clear();
    return delivered;
}

TransportCounters Endpoint::counters() const {
    TransportCounters counters = filter_.counters();
    TransportCounters carrier = transport_->counters();
    carrier.received = 0;  // the filter's count of delivered envelopes is the one that matters
    carrier.send_failed += send_refused_.load();
    counters += carrier;
    return counters;
}

}  // namespace keel::net
