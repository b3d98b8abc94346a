#include "core/node/data_plane.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "core/fsm/codec.hpp"
#include "core/node/wire.hpp"

namespace keel::node {

namespace {

constexpr std::size_t kMaxQueued = 64;
// Samples above this size travel as large messages (reliable) rather than sampled data.
constexpr std::size_t kLargeSampleBytes = 60'000;
// The thread waits on its endpoint: samples arriving, or publish()/stop() waking it.
constexpr auto kPollInterval = std::chrono::milliseconds(20);

}  // namespace

DataPlane::DataPlane(std::unique_ptr<net::Endpoint> endpoint, fsm::NodeId self,
                     std::map<std::string, fsm::TaskId, std::less<>> producers,
                     std::map<std::int64_t, fsm::TaskId> ports, tasking::Executor& executor)
    : endpoint_(std::move(endpoint)),
      self_(self),
      producers_(std::move(producers)),
      ports_(std::move(ports)),
      executor_(executor) {}

DataPlane::~DataPlane() { stop(); }

void DataPlane::start() {
    if (thread_.joinable()) return;
    stopping_.store(false);
    thread_ = std::thread([this] { run(); });
}

void DataPlane::stop() {
    stopping_.store(true);
    endpoint_->wake();
    if (thread_.joinable()) thread_.join();
}

void DataPlane::set_routes(std::vector<std::vector<fsm::NodeId>> routes) {
    std::lock_guard lock(mutex_);
    routes_ = std::move(routes);
}

void DataPlane::publish(const tasking::TaskSpec& producer, const tasking::Sample& sample) {
    const auto found = producers_.find(producer.name);
    if (found == producers_.end()) return;
    std::lock_guard lock(mutex_);
    if (found->second >= routes_.size()) return;
    if (too_large(found->second, sample.size_bytes())) {
        // The component broke its task's stated bound: other nodes do not get it.
        if (++counters_.sample_too_large <= 10) {
            spdlog::warn("task {}: a sample of {} bytes is above its max_sample_bytes ({}): not sent",
                         producer.name, sample.size_bytes(), sample_limits_[found->second]);
        }
        return;
    }
    const auto& route = routes_[found->second];
    if (std::none_of(route.begin(), route.end(), [&](fsm::NodeId node) { return node != self_; })) {
        return;  // only local consumers (or none): the executor delivers those itself
    }
    if (queue_.size() >= kMaxQueued) {
        queue_.pop_front();
        ++counters_.queue_dropped;
    }
    queue_.push_back({found->second, sample});
    endpoint_->wake();  // the thread sends it now, not at its next poll
}

DataPlaneCounters DataPlane::counters() const {
    std::lock_guard lock(mutex_);
    return counters_;
}

bool DataPlane::too_large(fsm::TaskId producer, std::size_t payload_bytes) const {
    return producer < sample_limits_.size() && sample_limits_[producer] != 0 &&
           payload_bytes > sample_limits_[producer];
}

bool DataPlane::wanted_here(fsm::TaskId producer) const {
    std::lock_guard lock(mutex_);
    if (producer >= routes_.size()) return false;
    const auto& route = routes_[producer];
    return std::find(route.begin(), route.end(), self_) != route.end();
}

void DataPlane::run() {
    std::vector<Outbound> batch;
    while (!stopping_.load()) {
        endpoint_->wait(kPollInterval);
        endpoint_->poll([&](net::Envelope&& envelope) { receive(std::move(envelope)); });
        {
            std::unique_lock lock(mutex_);
            batch.assign(std::make_move_iterator(queue_.begin()), std::make_move_iterator(queue_.end()));
            queue_.clear();
        }
        for (const Outbound& item : batch) {
            if (stopping_.load()) break;
            send(item);
        }
        batch.clear();
    }
}

void DataPlane::send(const Outbound& item) {
    std::vector<fsm::NodeId> remote;
    {
        std::lock_guard lock(mutex_);
        if (item.producer >= routes_.size()) return;
        for (const fsm::NodeId node : routes_[item.producer]) {
            if (node != self_) remote.push_back(node);
        }
    }
    if (remote.empty()) return;
    // The sample topics are addressed (DDS partitions per destination node, see
    // data_plane_dds_config()): each consumer's node gets its own write and DDS ships it to
    // that node only, so a scene two nodes need crosses the network twice and reaches no
    // third node.
    std::vector<std::uint8_t> payload = encode_sample(item.sample);
    const net::MessageKind kind = payload.size() > kLargeSampleBytes ? net::MessageKind::large
                                                                     : net::MessageKind::unreliable_data;
    endpoint_->set_local_epoch(epoch_.load());
    net::Envelope envelope = endpoint_->make_envelope(
        kind, static_cast<net::NodeAddress>(remote[0]),
        static_cast<net::Port>(item.sample.source_port), std::move(payload));
    for (const fsm::NodeId node : remote) {
        if (stopping_.load()) return;
        envelope.destination = static_cast<net::NodeAddress>(node);
        const bool sent = endpoint_->send(envelope) == net::SendResult::sent;
        std::lock_guard lock(mutex_);
        if (sent) ++counters_.samples_sent;
        else ++counters_.send_failed;
    }
}

std::optional<std::size_t> largest_stated_sample(const mission::Mission& mission) {
    std::size_t largest = 0;
    for (const mission::Task& task : mission.tasks) {
        if (!task.max_sample_bytes) return std::nullopt;
        largest = std::max(largest, static_cast<std::size_t>(*task.max_sample_bytes));
    }
    if (mission.tasks.empty()) return std::nullopt;
    return largest;
}

net::dds::DdsConfig data_plane_dds_config(net::dds::DdsConfig config,
                                          const std::vector<net::NodeAddress>& nodes,
                                          std::uint32_t data_domain,
                                          std::optional<std::size_t> largest_sample) {
    config.domain_id = data_domain;
    if (largest_sample) {
        config.limits.max_payload_bytes = *largest_sample + kSampleHeaderBytes;
        config.max_sample_bytes = net::dds::max_sample_bytes_for(config.limits.max_payload_bytes);
    }
    config.kinds = {net::MessageKind::unreliable_data, net::MessageKind::large};
    config.addressed_kinds = config.kinds;
    config.addressed_destinations = nodes;
    return config;
}

std::optional<std::size_t> largest_stated_state(const mission::Mission& mission) {
    std::size_t largest = 0;
    for (const mission::Task& task : mission.tasks) {
        if (!task.checkpoint) continue;
        if (!task.max_state_bytes) return std::nullopt;
        largest = std::max(largest, static_cast<std::size_t>(*task.max_state_bytes));
    }
    return largest;
}

net::dds::DdsConfig protocol_dds_config(net::dds::DdsConfig config,
                                        const std::vector<net::NodeAddress>& nodes,
                                        std::optional<std::size_t> largest_state) {
    std::size_t largest = fsm::kMaxMessageBytes;
    if (largest_state) {
        largest = std::max({fsm::kMaxHeartbeatBytes, fsm::kMaxCommandBytes,
                            fsm::kCheckpointOverheadBytes + fsm::kSnapshotHeaderBytes + *largest_state});
    }
    config.limits.max_payload_bytes = largest;
    config.max_sample_bytes =
        std::max(net::dds::max_sample_bytes_for(largest), net::dds::max_typed_sample_bytes);
    config.kinds.clear();
    for (const net::MessageKind kind : net::all_message_kinds) {
        if (carries_protocol(kind)) config.kinds.push_back(kind);
    }
    // Checkpoint writes, checkpoint and phase requests, and replies: each has one destination.
    config.addressed_kinds = {net::MessageKind::reliable_data, net::MessageKind::request,
                              net::MessageKind::response, net::MessageKind::acknowledgement};
    config.addressed_destinations = nodes;
    // Heartbeats and Commands: a reader per sender, so no node's samples displace another's.
    config.keyed_senders = nodes;
    // A switch's Commands and Activates to every member, in a burst: none displaced.
    config.command_history_depth = net::dds::command_history_for(static_cast<int>(nodes.size()));
    return config;
}

void DataPlane::receive(net::Envelope&& envelope) {
    if (envelope.kind != net::MessageKind::unreliable_data && envelope.kind != net::MessageKind::large) {
        return;  // protocol traffic: the node's loop reads it on its own participant
    }
    const auto producer = ports_.find(envelope.port);
    if (producer == ports_.end() || !wanted_here(producer->second)) return;
    auto sample = decode_sample(envelope.payload, static_cast<tasking::PortNumber>(envelope.port));
    if (!sample) {
        std::lock_guard lock(mutex_);
        ++counters_.bad_sample;
        return;
    }
    if (too_large(producer->second, sample->size_bytes())) {
        std::lock_guard lock(mutex_);
        if (++counters_.sample_too_large <= 10) {
            spdlog::warn("node {}: a sample of {} bytes for task {} is above its max_sample_bytes: "
                         "dropped", envelope.source, sample->size_bytes(), producer->second);
        }
        return;
    }
    executor_.deliver(*sample);
    std::lock_guard lock(mutex_);
    ++counters_.samples_received;
}

}  // namespace keel::node
