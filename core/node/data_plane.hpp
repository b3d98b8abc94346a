// DataPlane: how a node's components exchange samples with other nodes, on a thread and a
// DDS participant of their own.
//
// Samples can be large (a 2048 x 2048 px, 4-band scene is 16 MB) and a reliable DDS write of
// one takes long; the protocol loop must never wait on one, or its heartbeats would stop.
// So the data plane has its own participant (a DdsTransport with the node's address, wrapped
// in the same fault decorator plan) and its own thread:
//   - outbound: the executor's OutputSink hands every sample here (any worker thread); the
//     thread writes it to the nodes hosting a consumer of its producer in the current view
//     (the subscription lists, set by the loop on every reconfiguration), once per such
//     node, addressed to it; small samples as sampled data (best effort), large ones on the
//     reliable large-message topic. Both topics are addressed (data_plane_dds_config): DDS
//     ships a sample to its destination node's data plane only, never to other nodes;
//   - inbound: samples addressed to this node reach the executor (deliver()) only if this
//     node hosts a consumer of their producer in the current view.
// The outbound queue is bounded (drop-oldest, counted). The data plane's participant
// carries the sample topics only, the node's protocol participant the protocol topics only
// (protocol_dds_config), so neither takes, copies and drops the other's traffic; and the
// two are in different DDS domains (net::dds::data_domain_for), so a flood of large samples
// is received by Cyclone threads that carry no protocol traffic.
#pragma once

#include <atomic>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/fsm/types.hpp"
#include "core/mission/mission.hpp"
#include "core/net/dds/dds_transport.hpp"
#include "core/net/endpoint.hpp"
#include "core/tasking/executor.hpp"
#include "core/tasking/pi_mutex.hpp"

namespace keel::node {

struct DataPlaneCounters {
    std::uint64_t samples_sent = 0;   // one per destination node written to
    std::uint64_t samples_received = 0;
    std::uint64_t send_failed = 0;
    std::uint64_t queue_dropped = 0;  // evicted from a full outbound queue
    std::uint64_t bad_sample = 0;     // bytes that did not decode as a sample
    // Larger than its producer's max_sample_bytes: not sent (ours) or not delivered (a peer's).
    std::uint64_t sample_too_large = 0;
};

// The DDS configuration of a node's data plane participant: the node's own `config` carrying
// only unreliable_data and large, both addressed (one DDS partition per destination node),
// with writers to every node of `nodes` (the mission's addresses) made at start, in DDS
// domain `data_domain` (not the protocol's: net::dds::data_domain_for), so samples have
// Cyclone threads, socket and sample size bound of their own.
//
// `largest_sample`: the largest sample payload any task outputs, when every task of the
// mission states its max_sample_bytes. The envelope limit and the domain's MaxSampleSize
// are then that plus the sample's and the envelope's headers, so no peer makes the node
// reassemble a larger sample; none: the network layer's default bound (64 MiB).
net::dds::DdsConfig data_plane_dds_config(net::dds::DdsConfig config,
                                          const std::vector<net::NodeAddress>& nodes,
                                          std::uint32_t data_domain,
                                          std::optional<std::size_t> largest_sample = {});
// The largest max_sample_bytes of the mission's tasks, when every task states one.
std::optional<std::size_t> largest_stated_sample(const mission::Mission& mission);
// The DDS configuration of a node's protocol participant: every kind but the sample ones,
// whose payloads are protocol messages only, so at most fsm::kMaxMessageBytes (derived from
// the capacity, core/fsm/codec.hpp): a larger one is dropped as oversized before any copy,
// and DDS drops a sample larger than that before reassembling it (MaxSampleSize of the
// protocol's domain). The kinds of checkpoint writes and replies (reliable_data, response),
// the only ones that can be large, are addressed: they reach their destination alone (the
// Storage node, the requesting node), not every node (`nodes`: the mission's addresses,
// whose writers are created with the participant).
// `largest_state`: the largest max_state_bytes of the mission's checkpointed tasks, when each
// states one (largest_stated_state): then the protocol's domain admits no checkpoint with
// a larger state (nor, whatever the states, less than the largest heartbeat or command, or
// net::dds::max_typed_sample_bytes); none: the capacity's 16 MiB state.
net::dds::DdsConfig protocol_dds_config(net::dds::DdsConfig config,
                                        const std::vector<net::NodeAddress>& nodes,
                                        std::optional<std::size_t> largest_state = {});
// The largest max_state_bytes of the mission's checkpointed tasks when every one states it
// (0 when none is checkpointed); none otherwise.
std::optional<std::size_t> largest_stated_state(const mission::Mission& mission);

class DataPlane final : public tasking::OutputSink {
public:
    // `producers`: mission task name -> task id; `ports`: mission port -> producing task id.
    DataPlane(std::unique_ptr<net::Endpoint> endpoint, fsm::NodeId self,
              std::map<std::string, fsm::TaskId, std::less<>> producers,
              std::map<std::int64_t, fsm::TaskId> ports, tasking::Executor& executor);
    ~DataPlane() override;
    DataPlane(const DataPlane&) = delete;
    DataPlane& operator=(const DataPlane&) = delete;

    void start();
    void stop();

    // The nodes hosting a consumer of each task (by task id) in the current view.
    void set_routes(std::vector<std::vector<fsm::NodeId>> routes);
    // The node's epoch, stamped on outgoing samples (receivers' filters judge it).
    void set_epoch(fsm::Epoch epoch) { epoch_.store(epoch); }
    // Each task's (by task id) largest sample payload, 0: no bound (the mission's
    // max_sample_bytes). Set before start().
    void set_sample_limits(std::vector<std::size_t> by_task) { sample_limits_ = std::move(by_task); }

    // OutputSink: called by the executor's workers after each execution.
    void publish(const tasking::TaskSpec& producer, const tasking::Sample& sample) override;

    DataPlaneCounters counters() const;
    net::TransportCounters transport_counters() const { return endpoint_->counters(); }

private:
    struct Outbound {
        fsm::TaskId producer;
        tasking::Sample sample;
    };
    void run();
    void send(const Outbound& item);
    void receive(net::Envelope&& envelope);
    bool wanted_here(fsm::TaskId producer) const;
    bool too_large(fsm::TaskId producer, std::size_t payload_bytes) const;

    std::unique_ptr<net::Endpoint> endpoint_;
    fsm::NodeId self_;
    std::map<std::string, fsm::TaskId, std::less<>> producers_;
    std::map<std::int64_t, fsm::TaskId> ports_;
    tasking::Executor& executor_;
    std::vector<std::size_t> sample_limits_;  // by task id; 0 or absent: no bound

    mutable tasking::PiMutex mutex_;  // the loop takes it too (core/tasking/pi_mutex.hpp)
    std::vector<std::vector<fsm::NodeId>> routes_;
    std::deque<Outbound> queue_;
    DataPlaneCounters counters_;
    std::atomic<bool> stopping_{false};
    std::atomic<fsm::Epoch> epoch_{0};
    std::thread thread_;
};

}  // namespace keel::node
