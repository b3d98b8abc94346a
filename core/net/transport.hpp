// Transport: how envelopes leave and reach a node, whatever carries them.
//
// Three implementations exist: DdsTransport (core/net/dds/, Cyclone DDS), LoopbackTransport
// (an in-process hub: the simulator's and the unit tests' network) and FaultTransport (a
// decorator injecting loss, delay, duplication and partitions around any Transport).
//
// A Transport hands up *raw* inbound items: decoded envelopes and reports of bytes that
// could not be decoded. It does not judge senders or epochs. A node never reads a
// Transport directly: it owns an Endpoint (endpoint.hpp), which is the one place where
// malformed, oversized, unknown-sender and stale-epoch messages are counted, logged and
// dropped.
//
// Threading contract (every implementation):
//   - send(), receive() and publish_node_state() are called from one thread, the node's
//     event loop. They never block for long: send() may wait for DDS flow control up to
//     the configured max blocking time, receive() never waits.
//   - wait() blocks the calling (loop) thread until receive() may return something, wake()
//     is called or the timeout passes; it may return early (spurious wake-ups are allowed).
//   - wake() and counters() may be called from any thread (not from a signal handler).
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/net/envelope.hpp"

namespace keel::net {

// One item handed up by Transport::receive(): an envelope, or the reason bytes were refused.
struct Inbound {
    bool ok = true;
    Envelope envelope;                                // meaningful when ok
    EnvelopeError error = EnvelopeError::truncated;  // meaningful when !ok
    std::string detail;                               // meaningful when !ok
    std::string origin;                               // where it came from, for logs

    static Inbound accepted(Envelope envelope_in, std::string origin_in = {}) {
        Inbound item;
        item.envelope = std::move(envelope_in);
        item.origin = std::move(origin_in);
        return item;
    }
    static Inbound rejected(EnvelopeError error_in, std::string detail_in,
                            std::string origin_in = {}) {
        Inbound item;
        item.ok = false;
        item.error = error_in;
        item.detail = std::move(detail_in);
        item.origin = std::move(origin_in);
        return item;
    }
};

enum class SendResult : std::uint8_t {
    sent = 0,
    rejected_invalid = 1,    // the envelope breaks validate() (a programmer error upstream)
    rejected_oversized = 2,  // payload above the transport's maximum
    failed = 3,              // the carrier refused (DDS error, flow-control timeout, full queue)
};
std::string_view to_string(SendResult result);

// The roles of the paper's management layer, as published in NodeState.
enum class Role : std::uint8_t { unknown = 0, master, observer, worker, storage, interface, resigned };
std::string_view to_string(Role role);

// What a node tells the world about itself; DDS tools see it on the KeelNodeState topic.
struct NodeState {
    NodeAddress node = 0;
    std::string name{};         // mission node name, e.g. "PN1"
    Role role = Role::unknown;
    Epoch epoch = 0;
    std::uint32_t configuration_id = 0;
    std::string configuration{};  // mission configuration name, e.g. "C1" ("SAFE" in safe mode)
    std::string phase{};          // mission phase name

    friend bool operator==(const NodeState&, const NodeState&) = default;
};

struct TransportCounters {
    std::uint64_t sent = 0;                    // envelopes handed to the carrier
    std::uint64_t send_failed = 0;             // send() results other than sent
    std::uint64_t received = 0;                // envelopes delivered to the node
    std::uint64_t received_bytes = 0;          // payload bytes of the items taken from the carrier
    std::uint64_t dropped_malformed = 0;       // undecodable bytes or invalid fields
    std::uint64_t dropped_oversized = 0;       // payload above the maximum
    std::uint64_t dropped_unknown_sender = 0;  // source not in the mission's node list
    std::uint64_t dropped_stale_epoch = 0;     // epoch below the node's epoch floor
    std::uint64_t dropped_forged_sender = 0;   // source is not the node its writer speaks for
    std::uint64_t dropped_replayed = 0;        // a sequence number its writer already used
    std::uint64_t ignored_not_addressed = 0;   // for another node (shared DDS topics)
    // Filled by FaultTransport only.
    std::uint64_t fault_lost = 0;
    std::uint64_t fault_partitioned = 0;
    std::uint64_t fault_duplicated = 0;
    std::uint64_t fault_delayed = 0;
    // Filled by DdsTransport only.
    std::uint64_t deadline_missed = 0;  // heartbeat deadline misses seen by the reader

    TransportCounters& operator+=(const TransportCounters& other);
    friend bool operator==(const TransportCounters&, const TransportCounters&) = default;
};

class Transport {
public:
    virtual ~Transport() = default;

    virtual NodeAddress local_address() const = 0;

    // Sends one envelope. The source must be local_address().
    virtual SendResult send(const Envelope& envelope) = 0;

    // Sends `envelope` to each of `destinations` (its own destination is not used): what
    // each receives is what send() of the envelope addressed to it would deliver. A
    // transport may carry them as one message (DdsTransport: a Command as one sample for
    // all); this default sends one each. Returns `sent`, or the first other result.
    virtual SendResult send_to_each(const Envelope& envelope,
                                    std::span<const NodeAddress> destinations);

    // Moves up to max_items raw inbound items into `out` (appended); returns how many.
    // Never blocks.
    virtual std::size_t receive(std::vector<Inbound>& out, std::size_t max_items) = 0;

    // Blocks until receive() may have something or `timeout` passes. Returns true when
    // something may be available.
    virtual bool wait(std::chrono::nanoseconds timeout) = 0;

    // Makes the wait() under way, or else the next one, return at once: how another thread
    // hands the loop work that did not come from the network (control commands, a stop
    // request, samples to send). One wake-up is consumed by the wait() it ends.
    virtual void wake() = 0;

    // Publishes this node's state for observers (DDS: KeelNodeState, transient-local).
    virtual void publish_node_state(const NodeState& state) = 0;

    // Carrier-level counts (sent, send_failed, fault_*, deadline_missed).
    virtual TransportCounters counters() const = 0;
};

}  // namespace keel::net
