#include "core/net/loopback_transport.hpp"

#include <stdexcept>
#include <string>

namespace keel::net {

std::shared_ptr<LoopbackHub> LoopbackHub::create(std::size_t max_queued_frames,
                                                 EnvelopeLimits limits) {
    return std::shared_ptr<LoopbackHub>(new LoopbackHub(max_queued_frames, limits));
}

LoopbackHub::LoopbackHub(std::size_t max_queued_frames, EnvelopeLimits limits)
    : max_queued_frames_(max_queued_frames), limits_(limits) {
    if (max_queued_frames_ == 0) throw std::invalid_argument("LoopbackHub needs room for a frame");
}

std::unique_ptr<LoopbackTransport> LoopbackHub::attach(NodeAddress address) {
    if (address == broadcast_address) {
        throw std::invalid_argument("cannot attach the broadcast address");
    }
    std::lock_guard lock(mutex_);
    if (!inboxes_.try_emplace(address).second) {
        throw std::invalid_argument("node address " + std::to_string(address) +
                                    " is already attached");
    }
    return std::unique_ptr<LoopbackTransport>(new LoopbackTransport(shared_from_this(), address));
}

void LoopbackHub::detach(NodeAddress address) {
    std::lock_guard lock(mutex_);
    inboxes_.erase(address);
}

bool LoopbackHub::deliver(NodeAddress from, NodeAddress to,
                          const std::vector<std::uint8_t>& frame) {
    bool all_queued = true;
    {
        std::lock_guard lock(mutex_);
        for (auto& [address, inbox] : inboxes_) {
            const bool addressed = (to == broadcast_address) ? address != from : address == to;
            if (!addressed) continue;
            if (inbox.frames.size() >= max_queued_frames_) {
                all_queued = false;
                continue;
            }
            inbox.frames.push_back(frame);
        }
    }
    arrived_.notify_all();
    return all_queued;
}

void LoopbackHub::inject_frame(NodeAddress destination, std::vector<std::uint8_t> frame) {
    {
        std::lock_guard lock(mutex_);
        auto inbox = inboxes_.find(destination);
        if (inbox == inboxes_.end() || inbox->second.frames.size() >= max_queued_frames_) return;
        inbox->second.frames.push_back(std::move(frame));
    }
    arrived_.notify_all();
}

std::map<NodeAddress, NodeState> LoopbackHub::node_states() const {
    std::lock_guard lock(mutex_);
    return node_states_;
}

LoopbackTransport::LoopbackTransport(std::shared_ptr<LoopbackHub> hub, NodeAddress address)
    : hub_(std::move(hub)), address_(address) {}

LoopbackTransport::~LoopbackTransport() { hub_->detach(address_); }

SendResult LoopbackTransport::send(const Envelope& envelope) {
    if (auto problem = validate(envelope, hub_->limits_)) {
        ++send_failed_;
        return problem->error == EnvelopeError::oversized ? SendResult::rejected_oversized
                                                          : SendResult::rejected_invalid;
    }
    if (!hub_->deliver(address_, envelope.destination, encode(envelope))) {
        ++send_failed_;
        return SendResult::failed;
    }
    ++sent_;
    return SendResult::sent;
}

std::size_t LoopbackTransport::receive(std::vector<Inbound>& out, std::size_t max_items) {
    std::deque<std::vector<std::uint8_t>> frames;
    {
        std::lock_guard lock(hub_->mutex_);
        auto& inbox = hub_->inboxes_[address_].frames;
        while (!inbox.empty() && frames.size() < max_items) {
            frames.push_back(std::move(inbox.front()));
            inbox.pop_front();
        }
    }
    for (auto& frame : frames) {
        received_bytes_ += frame.size();
        DecodeResult decoded = decode(frame, hub_->limits_);
        if (decoded.ok()) {
            out.push_back(Inbound::accepted(std::move(decoded).envelope(), "loopback"));
        } else {
            out.push_back(Inbound::rejected(decoded.error(), decoded.detail(), "loopback"));
        }
    }
    received_ += frames.size();
    return frames.size();
}

bool LoopbackTransport::wait(std::chrono::nanoseconds timeout) {
    std::unique_lock lock(hub_->mutex_);
    const bool ready = hub_->arrived_.wait_for(
        lock, timeout, [&] { return woken_ || !hub_->inboxes_[address_].frames.empty(); });
    woken_ = false;
    return ready;
}

void LoopbackTransport::wake() {
    {
        std::lock_guard lock(hub_->mutex_);
        woken_ = true;
    }
    hub_->arrived_.notify_all();
}

void LoopbackTransport::publish_node_state(const NodeState& state) {
    std::lock_guard lock(hub_->mutex_);
    hub_->node_states_[state.node] = state;
}

TransportCounters LoopbackTransport::counters() const {
    TransportCounters counters;
    counters.sent = sent_.load();
    counters.send_failed = send_failed_.load();
    counters.received = received_.load();
    counters.received_bytes = received_bytes_.load();
    return counters;
}

}  // namespace keel::net
