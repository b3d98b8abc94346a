// NodeRuntime: one Keel node — the paper's management layer around the verified state
// machines. It glues core/fsm (NodeProtocol), core/tasking (the executor running the
// node's components) and core/net (an Endpoint over DDS, wrapped in the fault-injecting
// decorator) in one event-loop thread:
//
//   wait on the Endpoint (until the next heartbeat boundary or task period)
//   -> control commands (stdin)  -> inbound envelopes: protocol messages to
//   NodeProtocol::step, samples to the executor -> NodeProtocol::tick when due
//   -> what the executor's worker pool produced (components never run on the loop, so a
//   long execution cannot delay heartbeats): checkpoints to NodeProtocol::task_stepped,
//   task health events. Samples between nodes never touch the loop: the data plane
//   (data_plane.hpp, its own thread and DDS participant) sends them where the
//   subscription lists say and delivers those addressed here to the executor.
//   -> after every protocol call, its actions in order (actions.hpp)
//
// The management services of the paper, as they appear here:
//   monitor                     heartbeats (NodeProtocol) and task health (the executor's
//                               TaskHealthMonitor; handle_health())
//   reconfiguration manager     NodeProtocol on the Master (decision graph)
//   reconfiguration service     Activate/Deactivate actions -> executor (activate(),
//                               deactivate())
//   checkpointing service       snapshots -> task_stepped -> CheckpointWrite; on the Storage
//                               node StoreCheckpoint -> SQLite (StateDb)
//
// Threading: run() is the loop thread. post_command() and request_stop() may be called
// from any thread (a stdin reader, a signal watcher; not from a signal handler): they wake
// the loop's wait on the Endpoint, so it acts on them at once rather than at the next
// message or tick.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <variant>
#include <string>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/net/dds/credentials.hpp"
#include "core/net/dds/dds_transport.hpp"
#include "core/node/scheduling.hpp"
#include "core/tasking/pi_mutex.hpp"
#include "core/tasking/registry.hpp"

namespace keel::node {

struct RuntimeOptions {
    std::string mission_path;
    // The verified SHA-256 of the mission image (hex); its first 64 bits go in every
    // heartbeat, and a node flying another image takes no part (NodeProtocol). Empty:
    // not compared.
    std::string image_sha256;
    std::string node;
    std::string trace_path;       // empty: no trace
    std::string storage_db_path;  // empty: nothing persisted (every boot is a first boot)
    std::uint32_t domain_id = 0;
    // The DDS domain of the data plane (samples); none: net::dds::data_domain_for(domain_id).
    std::optional<std::uint32_t> data_domain_id;
    std::string network_interface = "lo";
    std::vector<std::string> peers = {"127.0.0.1"};
    // Discard the persisted protocol state (epoch, view, incarnation) and boot the initial
    // configuration; the Storage node's checkpoints are kept and resumed. For a cluster
    // restarted as a whole, where nodes booting as the spec's Restart would elect no Master.
    bool cold_start = false;
    // DDS Security files of this node (keel-node --security DIR); none: --insecure.
    net::dds::SecurityFiles security{};
    // The ground's operator (ground.hpp, credentials.hpp): when set, ground commands (`phase`,
    // `recover`, `exclude`) are admitted only signed by it; none (--insecure): the control
    // input is trusted as the ground's.
    std::optional<net::dds::OperatorIdentity> operator_identity;
    // Why a secured node has no operator identity (its files failed the check): it flies,
    // and refuses every ground command saying so.
    std::string operator_problem;
    // When the node's dated credentials expire, soonest first (net::dds::credential_
    // expiries): the status line names the first, and the node warns (at start, then
    // hourly) once it is within its warning window. Empty: --insecure.
    std::vector<net::dds::CredentialExpiry> credential_expiries;
    // --realtime: the loop above its tasks under SCHED_FIFO, memory locked, the loop's CPU
    // budget (scheduling.hpp).
    SchedulingOptions scheduling;
    // Where JSON status lines go (one per line); empty: nowhere.
    std::function<void(const std::string&)> status_sink;
};

// The outcome of setting a node up: an exit code and what to tell the operator.
struct SetupError {
    int exit_code = 2;
    std::string message;
};

// Counters of what the node dropped above the envelope layer.
struct RuntimeCounters {
    std::uint64_t bad_payload = 0;       // protocol payload that did not decode
    std::uint64_t forged_sender = 0;     // message naming another sender than its envelope
    std::uint64_t bad_sample = 0;        // sample bytes that did not decode
    std::uint64_t sample_too_large = 0;  // above its task's max_sample_bytes (sent or received)
    std::uint64_t samples_sent = 0;
    std::uint64_t samples_received = 0;
    std::uint64_t health_events = 0;
    std::uint64_t task_restarts = 0;
    std::uint64_t state_too_large = 0;  // checkpoint states above their task's max_state_bytes
};

class NodeRuntime {
public:
    // Takes the mission (loaded from options.mission_path's image) and checks everything the
    // node needs before it joins the network: the topology, the node exists, every task's
    // component is registered. Errors name the mission file.
    static std::variant<std::unique_ptr<NodeRuntime>, SetupError> create(
        RuntimeOptions options, mission::Mission mission,
        const tasking::ComponentRegistry& registry);
    ~NodeRuntime();

    // Joins the network and runs until request_stop() or a `quit` command. Returns the
    // process exit code (0 on a clean stop).
    int run();

    void request_stop();
    // A control line (`phase NAME`, `partition NODE...`, `heal`, `status`, `quit`).
    void post_command(std::string line);

    RuntimeCounters counters() const;

    struct Impl;

private:
    explicit NodeRuntime(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
    std::atomic<bool> stop_{false};
    tasking::PiMutex commands_mutex_;  // the loop takes it too (core/tasking/pi_mutex.hpp)
    std::deque<std::string> commands_;
    // Wakes the loop's wait (the Endpoint's wake()) while the loop runs; guarded by
    // commands_mutex_, so it is never called on an Endpoint being destroyed.
    std::function<void()> wake_loop_;
};

}  // namespace keel::node
