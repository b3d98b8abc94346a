// LoopbackTransport: an in-process network. Nodes attached to one LoopbackHub exchange
// envelopes as encoded frames (the same codec the wire uses), so the simulator and unit
// tests exercise decoding and every drop path without DDS.
//
// Delivery is FIFO per receiving node and deterministic for a given order of send() calls:
// a unicast frame goes to its destination, a broadcast frame to every other attached node.
// Each inbox holds at most max_queued_frames; a frame for a full inbox is dropped and
// send() reports SendResult::failed. The hub is thread-safe, so nodes may live on
// different threads (wait() wakes on a frame for that node, or on wake()).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "core/net/transport.hpp"

namespace keel::net {

class LoopbackTransport;

class LoopbackHub : public std::enable_shared_from_this<LoopbackHub> {
public:
    static std::shared_ptr<LoopbackHub> create(std::size_t max_queued_frames = 4096,
                                               EnvelopeLimits limits = {});

    // Attaches a node; throws std::invalid_argument for the broadcast address or an
    // address already attached.
    std::unique_ptr<LoopbackTransport> attach(NodeAddress address);

    // Puts raw bytes in a node's inbox as if they had arrived from the network (tests).
    void inject_frame(NodeAddress destination, std::vector<std::uint8_t> frame);

    // The last NodeState each node published (what a DDS tool would see).
    std::map<NodeAddress, NodeState> node_states() const;

private:
    friend class LoopbackTransport;
    struct Inbox {
        std::deque<std::vector<std::uint8_t>> frames;
    };

    LoopbackHub(std::size_t max_queued_frames, EnvelopeLimits limits);
    bool deliver(NodeAddress from, NodeAddress to, const std::vector<std::uint8_t>& frame);
    void detach(NodeAddress address);

    const std::size_t max_queued_frames_;
    const EnvelopeLimits limits_;
    mutable std::mutex mutex_;
    std::condition_variable arrived_;
    std::map<NodeAddress, Inbox> inboxes_;
    std::map<NodeAddress, NodeState> node_states_;
};

class LoopbackTransport final : public Transport {
public:
    ~LoopbackTransport() override;
    LoopbackTransport(const LoopbackTransport&) = delete;
    LoopbackTransport& operator=(const LoopbackTransport&) = delete;

    NodeAddress local_address() const override { return address_; }
    SendResult send(const Envelope& envelope) override;
    std::size_t receive(std::vector<Inbound>& out, std::size_t max_items) override;
    bool wait(std::chrono::nanoseconds timeout) override;
    void wake() override;
    void publish_node_state(const NodeState& state) override;
    TransportCounters counters() const override;

private:
    friend class LoopbackHub;
    LoopbackTransport(std::shared_ptr<LoopbackHub> hub, NodeAddress address);

    std::shared_ptr<LoopbackHub> hub_;
    NodeAddress address_;
    std::atomic<std::uint64_t> sent_{0};
    std::atomic<std::uint64_t> send_failed_{0};
    std::atomic<std::uint64_t> received_{0};
    std::atomic<std::uint64_t> received_bytes_{0};
    bool woken_ = false;  // guarded by the hub's mutex
};

}  // namespace keel::net
