// Endpoint: a node's one door to the network, and the one place inbound messages are judged.
//
// An Endpoint owns a Transport (DDS, loopback, or either wrapped in a FaultTransport) and
// runs every inbound item through its ReceiveFilter, in this order:
//   0. a source that is not the node its authenticated writer speaks for, or a sequence
//      number its writer already used (DdsTransport judges both: it knows the writer)
//                                               -> dropped_forged_sender, dropped_replayed
//   1. undecodable bytes or invalid fields      -> dropped_malformed
//   2. payload above limits.max_payload_bytes   -> dropped_oversized
//   3. source not in the mission's node list    -> dropped_unknown_sender
//   4. epoch below the epoch floor (heartbeats excepted: they are never stale)
//                                               -> dropped_stale_epoch
//   5. destination neither this node nor broadcast, or sent by this node
//                                               -> ignored_not_addressed (not an error)
// Each drop is counted and logged (spdlog, rate-limited so a flood cannot fill the log);
// none throws. What passes is delivered to the caller's function, in arrival order.
//
// Usage from the node's event loop (one thread; counters() may be read from any thread):
//
//   Endpoint endpoint(std::move(transport), {.known_nodes = {1, 2, 3}});
//   endpoint.set_epoch_floor(epoch);            // whenever the node adopts a new epoch
//   endpoint.set_local_epoch(epoch);            // epoch stamped on outgoing envelopes
//   endpoint.send(endpoint.make_envelope(MessageKind::heartbeat, broadcast_address, 0, {}));
//   endpoint.wait(std::chrono::milliseconds(10));   // another thread may endpoint.wake()
//   endpoint.poll([&](Envelope&& message) { ... });
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>

#include "core/net/transport.hpp"

namespace spdlog {
class logger;
}

namespace keel::net {

struct FilterConfig {
    std::set<NodeAddress> known_nodes;  // the mission's node addresses (the local one included)
    EnvelopeLimits limits{};
    std::string log_name = "keel.net";  // spdlog logger name (created if it does not exist)
};

// Whether the count-th drop of one reason is logged: the first ten are, then one in a
// thousand, so that a flood is counted (the status line's `dropped`), not logged message
// by message.
constexpr bool log_this_drop(std::uint64_t count) { return count <= 10 || count % 1000 == 0; }

// Judges raw inbound items for one node. Not thread-safe except counters().
class ReceiveFilter {
public:
    ReceiveFilter(NodeAddress local_address, FilterConfig config);

    // Returns the envelope when it should reach the node; counts and logs it otherwise.
    std::optional<Envelope> admit(Inbound&& item);

    void set_epoch_floor(Epoch floor) { epoch_floor_.store(floor); }
    Epoch epoch_floor() const { return epoch_floor_.load(); }
    void set_known_nodes(std::set<NodeAddress> known_nodes);

    // received, dropped_* and ignored_not_addressed; the rest are zero.
    TransportCounters counters() const;

private:
    void log_drop(const char* reason, std::uint64_t count, const std::string& text);

    NodeAddress local_address_;
    FilterConfig config_;
    std::shared_ptr<spdlog::logger> logger_;
    std::atomic<Epoch> epoch_floor_{0};
    std::atomic<std::uint64_t> received_{0};
    std::atomic<std::uint64_t> dropped_malformed_{0};
    std::atomic<std::uint64_t> dropped_oversized_{0};
    std::atomic<std::uint64_t> dropped_unknown_sender_{0};
    std::atomic<std::uint64_t> dropped_stale_epoch_{0};
    std::atomic<std::uint64_t> dropped_forged_sender_{0};
    std::atomic<std::uint64_t> dropped_replayed_{0};
    std::atomic<std::uint64_t> ignored_not_addressed_{0};
};

class Endpoint {
public:
    Endpoint(std::unique_ptr<Transport> transport, FilterConfig config);

    NodeAddress local_address() const { return transport_->local_address(); }

    // An envelope from this node, stamped with the local epoch and the next sequence number.
    Envelope make_envelope(MessageKind kind, NodeAddress destination, Port port,
                           std::vector<std::uint8_t> payload);

    // Sends; refuses (counted in send_failed) envelopes that break validate() or whose
    // source is not this node.
    SendResult send(const Envelope& envelope);
    // send() of `envelope` to each of `destinations`, under one sequence number
    // (Transport::send_to_each); the envelope's own destination is not used.
    SendResult send_to_each(const Envelope& envelope, std::span<const NodeAddress> destinations);

    // Delivers up to max_items filtered envelopes to `deliver`; returns how many were
    // delivered. Never blocks.
    std::size_t poll(const std::function<void(Envelope&&)>& deliver, std::size_t max_items = 256);

    bool wait(std::chrono::nanoseconds timeout) { return transport_->wait(timeout); }
    // Ends the wait() under way (or the next one) at once; callable from any thread.
    void wake() { transport_->wake(); }

    void set_epoch_floor(Epoch floor) { filter_.set_epoch_floor(floor); }
    Epoch epoch_floor() const { return filter_.epoch_floor(); }
    void set_local_epoch(Epoch epoch) { local_epoch_ = epoch; }
    Epoch local_epoch() const { return local_epoch_; }
    void set_known_nodes(std::set<NodeAddress> known_nodes) {
        filter_.set_known_nodes(std::move(known_nodes));
    }

    void publish_node_state(const NodeState& state) { transport_->publish_node_state(state); }

    // Filter counts plus the transport's own (sent, send_failed, fault_*, deadline_missed).
    TransportCounters counters() const;

    Transport& transport() { return *transport_; }

private:
    std::unique_ptr<Transport> transport_;
    ReceiveFilter filter_;
    EnvelopeLimits limits_;
    Epoch local_epoch_ = 0;
    Sequence next_sequence_ = 1;
    std::atomic<std::uint64_t> send_refused_{0};
    // Why `envelope` may not leave (counted in send_refused_), or nothing.
    std::optional<SendResult> refusal(const Envelope& envelope);
    std::vector<Inbound> batch_;
};

}  // namespace keel::net
