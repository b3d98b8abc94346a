#include "core/node/runtime.hpp"

#ifndef KEEL_FAULT_INJECTION
#define KEEL_FAULT_INJECTION 0  // a flight build unless the build says otherwise
#endif

#include <pthread.h>
#include <sched.h>
#include <sys/random.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <atomic>
#include <cstring>
#include <ctime>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "core/fsm/codec.hpp"
#include "core/fsm/json.hpp"
#include "core/fsm/node_protocol.hpp"
#include "core/fsm/overloaded.hpp"
#include "core/net/dds/dds_transport.hpp"
#include "core/net/endpoint.hpp"
#if KEEL_FAULT_INJECTION
#include "core/net/fault_transport.hpp"
#endif
#include "core/node/checkpoint_persister.hpp"
#include "core/node/data_plane.hpp"
#include "core/node/driver.hpp"
#include "core/node/ground.hpp"
#include "core/node/state_db.hpp"
#include "core/node/subscriptions.hpp"
#include "core/node/wire.hpp"
#include "core/tasking/clock.hpp"
#include "core/tasking/executor.hpp"

// One width per quantity, end to end (fault model 3): the epoch the protocol adopts and
// opens is the epoch the envelope carries.
static_assert(keel::fsm::kMaxEpoch == keel::net::max_epoch, "an epoch is 24 bits everywhere");
static_assert(keel::node::NodeDriver::kBroadcast == keel::net::broadcast_address,
              "the driver's broadcast is the envelope's");

namespace keel::node {

// An image the node must not fly (an older mission revision than the one it flew): exit 2,
// bad input.
struct ImageRefused {
    std::string why;
};

namespace {

std::int64_t steady_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

// A test build's keel-node takes `partition`, `deaf` and `heal` on stdin; a flight build has
// neither the control lines nor the transport wrapper that carries them out.
constexpr bool kFaultInjection = KEEL_FAULT_INJECTION != 0;

using fsm::TimeNs;

// keel-node's exit code after a disk failure (docs/clusters.md, exit codes).
constexpr int kDiskFailureExit = 5;
constexpr TimeNs kMaxWaitNs = 20'000'000;      // longest wait (commands and stop wake it)
constexpr TimeNs kMinPeriodicWaitNs = 1'000'000;
constexpr TimeNs kActiveWaitNs = 5'000'000;
// Local restarts of a task whose health fails before the node asks to be relocated.
constexpr int kMaxLocalRestarts = 1;
// A restarted node warns once when no Master has commanded it for this many miss limits.
constexpr TimeNs kNoMasterWarningPeriods = 10;

using fsm::Overloaded;

std::int64_t wall_clock_ns() {
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

std::vector<std::string> split_words(const std::string& line) {
    std::istringstream stream(line);
    std::vector<std::string> words;
    for (std::string word; stream >> word;) words.push_back(word);
    return words;
}

struct TaskSlot {
    std::string name;
    tasking::TaskId executor_id = 0;
    std::string configured_phase;
    bool active = false;
    bool checkpoint = false;
    std::optional<std::int64_t> period_ms;
    int restarts = 0;  // local restarts since the last healthy activation
    std::vector<std::uint8_t> last_state;  // latest snapshot bytes (for a local restart)
};

}  // namespace

// The node's host of its driver (driver.hpp): the driver decides the order of the
// protocol's effects; these members carry them out over DDS, the executor and SQLite.
struct NodeRuntime::Impl final : DriverHost {
    RuntimeOptions options;
    mission::Mission mission;
    fsm::Topology topology;
    fsm::NodeId self = 0;
    const tasking::ComponentRegistry* registry = nullptr;
    std::vector<tasking::TaskInstance> instances;  // handed to the executor at run()
    std::int64_t configure_ns = 0;  // instantiating and configuring the components

    tasking::SteadyClock clock;
    // What --realtime got (scheduling.hpp), and the loop's CPU budget under it.
    SchedulingReport scheduling;
    std::optional<LoopBudget> budget;
    std::unique_ptr<tasking::Executor> executor;
    std::vector<TaskSlot> tasks;  // by fsm task id
    std::unique_ptr<StateDb> db;
#if KEEL_FAULT_INJECTION
    // Partitions and receive omissions set by the control lines (a test build's).
    std::shared_ptr<net::FaultPlan> plan = std::make_shared<net::FaultPlan>();
#endif
    std::unique_ptr<net::Endpoint> endpoint;
    std::unique_ptr<DataPlane> data_plane;  // after the executor: stopped and destroyed first
    std::unique_ptr<fsm::NodeProtocol> protocol;
    // The Storage node: checkpoints go to disk off the loop, and what it says of a task
    // (a final checkpoint's acknowledgement, a restore's reply, its StoreCheckpoint trace
    // line) waits until the checkpoint it stands for is written (checkpoint_persister.hpp).
    std::unique_ptr<CheckpointPersister> persister;
    // Where the protocol's actions become effects, in the order the durable-state rules
    // need (driver.hpp): created with the protocol.
    std::unique_ptr<NodeDriver> driver;
    std::optional<Subscriptions> subscriptions;
    std::FILE* trace = nullptr;
    std::vector<fsm::Action> actions;
    std::vector<std::uint8_t> scratch;

    RuntimeCounters counters;
    mutable tasking::PiMutex counters_mutex;  // the loop takes it too (pi_mutex.hpp)
    std::optional<StoredState> persisted;
    // The node's own state saves (save_state's writes, each synced before the messages
    // that depend on it leave): how many, and their time in total and at most.
    std::uint64_t state_writes = 0;
    std::int64_t state_write_ns = 0;
    std::int64_t state_write_max_ns = 0;
    // Durable state (docs/fault-model.md, "Durable state"): a node whose own state cannot be
    // saved, or a Storage node whose checkpoint write failed, says nothing that stands
    // for it, asks to be excluded and stops (the driver's rule 3; exit code
    // kDiskFailureExit).
    bool stopping_for_disk = false;  // the loop ends at its next pass
    std::string last_status_key;
    std::optional<fsm::View> routed_view;
    fsm::Epoch floor_epoch = 0;
    bool safe_mode_logged = false;
    // A restarted node waits to be commanded; if no Master commands it for
    // kNoMasterWarningPeriods x miss_limit heartbeat periods, it says so once.
    TimeNs boot_ns = 0;
    bool no_master_warned = false;
    std::uint64_t warm_boots_logged = 0;
    std::uint32_t previous_boot = 0;  // the boot that saved the state this one found
    std::array<std::uint64_t, fsm::kMaxNodes> foreign_image_warned{};
    // Ground commands (ground.hpp): admitted only signed by the operator on a secured node;
    // the seq admitted last is saved with the node's state before the command acts.
    std::optional<GroundGate> ground;
    void act_on_ground(const std::string& verb, const std::vector<std::string>& arguments);
    void warn_if_no_master();
    // Credentials: a warning, at start and then hourly, while one is within its warning
    // window (CredentialExpiry::due); the status line's "credentials" object.
    void warn_of_expiry();
    std::string credentials_json() const;
    std::time_t expiry_warned_at = 0;
    // Fault model 3: the status line's "refused" object, and a warning naming the last
    // refusal when there were new ones (at most one a second).
    std::string refused_json() const;
    void warn_of_refusals();
    std::uint64_t refusals_warned = 0;
    std::uint64_t lost_checkpoints = 0;
    TimeNs refusals_warned_at = 0;

    TimeNs now() const { return clock.now_ns(); }
    bool self_is_interface() const {
        const mission::Node& node = mission.nodes.at(self);
        return !node.is_processing() && !node.is_storage();
    }
    const std::string& name() const { return options.node; }

    // --- setup ---
    void boot();
    // The persisted state, or nothing (with a warning) when it cannot be read.
    std::optional<StoredState> load_state_or_warn();
    void shutdown();

    // --- loop steps ---
    void on_envelope(net::Envelope&& envelope);
    void read_envelopes();
    std::vector<net::Envelope> batch;  // what one poll read (read_envelopes)
    void run_tasks();
    void handle_health(const tasking::HealthEvent& event);
    void handle_command(const std::string& line, bool& quit);
    void drive();  // the driver carries out the protocol's ready actions, in order
    void follow_phase();
    // Reports the persister's finished writes to the driver (the Storage node).
    void settle_checkpoints();
    void after_step();  // epoch floor, persistence, routes, status
    // What a restart needs besides checkpoints: everything StoredState holds, as it is now.
    StoredState current_state() const;

    // --- DriverHost ---
    void send(fsm::NodeId to, const fsm::Message& message) override;
    void send_to_each(const std::vector<fsm::NodeId>& to, const fsm::Message& message) override;
    std::vector<net::NodeAddress> destinations;  // send_to_each's, kept between calls
    // The envelope of `message` for `to`, once the step's trace lines are on the file.
    net::Envelope envelope_for(net::NodeAddress to, const fsm::Message& message);
    void activate(const fsm::act::Activate& action) override;
    // Starts a task from `snapshot` (fresh when its component refuses the state, said in
    // the log); one that does not start at all is queued in `unstarted` as its error.
    tasking::LifecycleResult start_task(TaskSlot& slot, const std::optional<tasking::Snapshot>& snapshot,
                                        const std::string& version);
    // Tasks that did not start: handled as unhealthy once the step that started them ends.
    std::vector<tasking::HealthEvent> unstarted;
    void deactivate(fsm::TaskId task) override;
    void write_trace(const fsm::act::Trace& trace_action) override;
    // Saves the node's state when it changed; false when saving failed.
    bool save_state() override;
    std::optional<std::uint64_t> store_checkpoint(fsm::act::StoreCheckpoint& store) override;
    void disk_failed(std::string_view what) override;
    void declared_failed(const fsm::act::DeclareFailed& declared) override;
    void entered_safe_mode() override;
    void print_status(bool force);
    std::string role_name() const;
    TimeNs next_wait_ns() const;
};

std::variant<std::unique_ptr<NodeRuntime>, SetupError> NodeRuntime::create(
    RuntimeOptions options, mission::Mission mission,
    const tasking::ComponentRegistry& registry) {
    auto impl = std::make_unique<Impl>();
    impl->mission = std::move(mission);
    std::string error;
    auto topology = fsm::Topology::build(impl->mission, &error);
    if (!topology) return SetupError{2, options.mission_path + ": " + error + "\n"};
    impl->topology = std::move(*topology);
    const auto self = impl->topology.node_id(options.node);
    if (!self) {
        std::string names;
        for (const auto& node : impl->mission.nodes) names += (names.empty() ? "" : ", ") + node.name;
        return SetupError{2, options.mission_path + ": no node '" + options.node +
                                 "' in mission '" + impl->mission.name + "' (nodes: " + names +
                                 ")\n"};
    }
    impl->self = *self;
    // Every processing node keeps every component it may ever run (the paper stores tasks on
    // each node), so an unknown component is an error wherever the task is placed.
    std::string errors;
    const auto instantiate_start = std::chrono::steady_clock::now();
    for (const auto& task : impl->mission.tasks) {
        tasking::InstantiateResult result = registry.instantiate(impl->mission, task.name);
        if (!result.ok()) {
            errors += result.error + "\n";
            continue;
        }
        impl->instances.push_back(std::move(*result.instance));
    }
    if (!errors.empty()) return SetupError{2, errors};
    impl->configure_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::steady_clock::now() - instantiate_start)
                             .count();
    impl->registry = &registry;
    impl->options = std::move(options);
    return std::unique_ptr<NodeRuntime>(new NodeRuntime(std::move(impl)));
}

NodeRuntime::NodeRuntime(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
NodeRuntime::~NodeRuntime() = default;

void NodeRuntime::post_command(std::string line) {
    std::lock_guard lock(commands_mutex_);
    if (commands_.size() < 1024) commands_.push_back(std::move(line));
    if (wake_loop_) wake_loop_();
}

void NodeRuntime::request_stop() {
    stop_.store(true);
    std::lock_guard lock(commands_mutex_);
    if (wake_loop_) wake_loop_();
}

RuntimeCounters NodeRuntime::counters() const {
    RuntimeCounters counters;
    {
        std::lock_guard lock(impl_->counters_mutex);
        counters = impl_->counters;
    }
    if (impl_->data_plane) {
        const DataPlaneCounters data = impl_->data_plane->counters();
        counters.samples_sent = data.samples_sent;
        counters.samples_received = data.samples_received;
        counters.bad_sample = data.bad_sample;
        counters.sample_too_large = data.sample_too_large;
    }
    return counters;
}

int NodeRuntime::run() {
    Impl& node = *impl_;
    // Before boot() starts the node's threads: the DDS participant's threads and the
    // persister inherit the loop's priority, the executor and the data plane the tasks'.
    node.scheduling = enter_loop_scheduling(node.options.scheduling);
    if (node.options.scheduling.realtime && !node.scheduling.realtime) {
        spdlog::warn("{}: scheduling: {}", node.name(), node.scheduling.describe(node.options.scheduling));
    } else {
        spdlog::info("{}: scheduling: {}", node.name(), node.scheduling.describe(node.options.scheduling));
    }
    if (node.scheduling.realtime && !node.scheduling.memory_locked) {
        spdlog::warn("{}: memory not locked: {}; pages may be swapped out", node.name(),
                     node.scheduling.lock_error);
    }
    if (node.scheduling.realtime) {
        node.budget.emplace(node.options.scheduling.budget_window_ns,
                            node.options.scheduling.budget_percent);
    }
    try {
        node.boot();
    } catch (const ImageRefused& refused) {
        spdlog::error("{}: {}", node.name(), refused.why);
        node.shutdown();
        return 2;
    } catch (const std::exception& error) {
        spdlog::error("{}: cannot start: {}", node.name(), error.what());
        node.shutdown();
        return 3;
    }
    {
        std::lock_guard lock(commands_mutex_);
        net::Endpoint* endpoint = node.endpoint.get();
        wake_loop_ = [endpoint] { endpoint->wake(); };
        // A command or stop posted before the loop could be woken is seen on the first pass.
    }
    bool quit = false;
    std::vector<std::string> lines;
    while (!quit && !stop_.load() && !node.stopping_for_disk) {
        const TimeNs wait_ns = node.next_wait_ns();
        if (wait_ns > 0) node.endpoint->wait(std::chrono::nanoseconds(wait_ns));
        if (node.budget) node.budget->begin_pass(steady_ns(), thread_cpu_ns());
        {
            std::lock_guard lock(commands_mutex_);
            lines.assign(commands_.begin(), commands_.end());
            commands_.clear();
        }
        for (const std::string& line : lines) node.handle_command(line, quit);
        node.settle_checkpoints();
        if (node.stopping_for_disk) break;
        node.read_envelopes();
        const TimeNs now = node.now();
        if (now >= node.protocol->next_tick_ns()) {
            node.protocol->tick(now);
            node.drive();
        }
        node.run_tasks();
        node.after_step();
        node.warn_if_no_master();
        node.warn_of_expiry();
        // The pool starts no execution past the lease: a process resumed after a stop
        // long enough to lose it runs nothing before this loop has held its tasks.
        node.executor->set_run_until(node.protocol->lease_expiry_ns());
        if (node.budget) {
            // A real-time loop that never blocks (a flood of messages) would starve the
            // machine: past its budget in this window it sleeps until it has kept its
            // share, one window at most.
            const std::int64_t sleep_ns = node.budget->end_pass(steady_ns(), thread_cpu_ns());
            if (sleep_ns > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(sleep_ns));
        }
    }
    spdlog::info("{}: stopping", node.name());
    {
        std::lock_guard lock(commands_mutex_);
        wake_loop_ = nullptr;
    }
    node.shutdown();
    return node.stopping_for_disk ? kDiskFailureExit : 0;
}

std::optional<StoredState> NodeRuntime::Impl::load_state_or_warn() {
    try {
        std::string note;
        std::optional<StoredState> stored = db->load_state(&note);
        if (!note.empty()) spdlog::warn("{}: {}", name(), note);
        return stored;
    } catch (const StateDbError& error) {
        spdlog::warn("{}: cold start: {}", name(), error.what());
        return std::nullopt;
    }
}

namespace {

// The first 64 bits of the image's SHA-256 (hex), as heartbeats carry it; 0 when none.
std::uint64_t image_tag(const std::string& sha256) {
    if (sha256.size() < 16) return 0;
    std::uint64_t tag = 0;
    for (std::size_t i = 0; i < 16; ++i) {
        const char c = sha256[i];
        const int digit = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10
                          : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
        if (digit < 0) return 0;
        tag = tag << 4 | static_cast<std::uint64_t>(digit);
    }
    return tag;
}

// A boot identifier from the kernel's random source: monitors tell this boot from every
// earlier one by it even if the saved incarnation went back (HeartbeatMonitor).
std::uint32_t draw_boot_id() {
    std::uint32_t boot = 0;
    std::size_t got = 0;
    while (got < sizeof boot) {
        const ssize_t n = getrandom(reinterpret_cast<char*>(&boot) + got, sizeof boot - got, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            throw std::runtime_error(std::string("cannot draw a boot identifier: getrandom: ") +
                                     std::strerror(errno));
        }
        got += static_cast<std::size_t>(n);
    }
    return boot;
}

}  // namespace

void NodeRuntime::Impl::boot() {
    if (!options.trace_path.empty()) {
        trace = std::fopen(options.trace_path.c_str(), "a");
        if (trace == nullptr) {
            throw std::runtime_error("cannot open trace " + options.trace_path + ": " +
                                     std::strerror(errno));
        }
    }
    // Persistent state: a node that finds its own earlier state boots as the spec's Restart
    // (a Worker waiting to be commanded; never a resurrected Master). --cold-start discards
    // that state (epoch, view, incarnation) and boots the initial configuration; the Storage
    // node keeps its checkpoints either way, and on a first boot hands them to the protocol
    // (NodeOptions::kept_checkpoints) so the boot switch resumes the tasks from them.
    std::optional<fsm::PersistentState> restart;
    std::vector<fsm::StoredCheckpoint> kept_checkpoints;
    std::uint64_t saved_ground_seq = 0;
    const bool storage = self == topology.storage_node();
    if (!options.storage_db_path.empty()) {
        db = std::make_unique<StateDb>(options.storage_db_path);
        // Without --cold-start, an unreadable protocol state stops the boot: booting the
        // initial configuration instead could bring back an epoch the cluster left.
        std::string note;
        std::optional<StoredState> stored = options.cold_start ? load_state_or_warn() : db->load_state(&note);
        if (!note.empty()) spdlog::warn("{}: {}", name(), note);
        // The boot that saved this state has ended: heartbeats name it as this one's
        // previous boot (HeartbeatMonitor), a cold start too.
        if (stored) previous_boot = stored->boot;
        // A cold start keeps the last ground command's seq too: a replay stays refused.
        if (stored) saved_ground_seq = static_cast<std::uint64_t>(std::max<std::int64_t>(stored->ground_seq, 0));
        // The image's lifecycle: a node never flies a mission revision older than the last
        // one it flew (a cold start does not change that). A rollback is a new revision.
        if (stored && stored->revision > mission.revision.value_or(0)) {
            throw ImageRefused{"the mission image is revision " + std::to_string(mission.revision.value_or(0)) +
                               ", older than revision " + std::to_string(stored->revision) + " this node flew (" +
                               db->path() + "): refused. A node flies only revisions that grow; to go back to an "
                               "older mission, compile it again with a revision above " +
                               std::to_string(stored->revision)};
        }
        if (stored && options.cold_start) {
            spdlog::warn("{}: cold start: discarding the protocol state in {} (epoch {}, "
                         "incarnation {}); booting the initial configuration",
                         name(), db->path(), stored->epoch, stored->incarnation);
            stored.reset();
        } else if (stored && !stored->image.empty() && !options.image_sha256.empty() &&
                   stored->image != options.image_sha256) {
            // An update: the saved view names configurations by the image it was saved
            // with. The node boots as a cold start does; checkpoints (by task name), the
            // revision, the ground's seq and the boot identifier are kept.
            spdlog::warn("{}: the protocol state in {} was saved flying image {}, this node flies {} "
                         "(an update): discarded as by --cold-start; booting the initial configuration",
                         name(), db->path(), stored->image.substr(0, 16), options.image_sha256.substr(0, 16));
            stored.reset();
        }
        if (storage) {
            std::vector<std::string> lost;
            for (NamedCheckpoint& checkpoint : db->load_checkpoints(&lost)) {
                const auto task = topology.task_id(checkpoint.task);
                if (!task) continue;
                kept_checkpoints.push_back({*task, checkpoint.version, std::move(checkpoint.state)});
            }
            for (const std::string& why : lost) spdlog::error("{}: {}", name(), why);
            lost_checkpoints = lost.size();
        }
        if (stored) {
            fsm::PersistentState state;
            state.epoch = stored->epoch;
            state.view = stored->view;
            state.incarnation = stored->incarnation;
            state.boot = stored->boot;
            state.held_out = stored->held_out;  // the ground's holds stay (not on a cold start)
            state.paused = stored->paused;      // and its pauses
            state.checkpoints = std::move(kept_checkpoints);
            kept_checkpoints.clear();
            spdlog::info("{}: restarting from {} (epoch {}, incarnation {}, {} checkpoints)", name(),
                         db->path(), state.epoch, state.incarnation, state.checkpoints.size());
            restart = std::move(state);
        } else if (!kept_checkpoints.empty()) {
            spdlog::info("{}: first boot keeping {} checkpoints from {}", name(),
                         kept_checkpoints.size(), db->path());
        }
    }

    ground.emplace(options.security.enabled(), options.operator_identity, options.operator_problem,
                   options.image_sha256.substr(0, 16), saved_ground_seq);
    if (!options.operator_problem.empty()) {
        spdlog::error("{}: the ground's operator: {}: this node takes no ground command until it is given "
                      "a valid operator certificate and grant (docs/operations.md)",
                      name(), options.operator_problem);
    }

    net::dds::DdsConfig dds;
    dds.address = self;
    dds.domain_id = options.domain_id;
    dds.network_interface = options.network_interface;
    dds.peers = options.peers;
    dds.security = options.security;
    dds.heartbeat_period = std::chrono::milliseconds(topology.heartbeat_period_ns() / 1'000'000);
    dds.heartbeat_miss_limit = static_cast<std::uint32_t>(topology.miss_limit());
    // The loop must never wait long on a reliable write (heartbeats are due every period): a
    // write that finds no room within this fails and is counted; the protocols retransmit,
    // and components resend what they need.
    dds.max_blocking_time = std::chrono::milliseconds(20);
    // Every node of the mission may run on one host (an emulated cluster): each takes a
    // participant index in each of its two domains, and tools (keel-observe, the DDS tools,
    // an injector) a few more. Cyclone's default of 30 refused a 32-node mission's nodes.
    dds.max_auto_participant_index = net::dds::participant_indices_for(topology.node_count());
    std::vector<net::NodeAddress> addresses;
    for (int id = 0; id < topology.node_count(); ++id) addresses.push_back(static_cast<net::NodeAddress>(id));
    net::dds::DdsConfig protocol_config =
        protocol_dds_config(dds, addresses, largest_stated_state(mission));
    if (!topology.processing_nodes().contains(self)) {
        // Only processing nodes command (and their permissions alone let them write it).
        protocol_config.receive_only_kinds = {net::MessageKind::reconfiguration_command};
    }
    std::unique_ptr<net::Transport> transport = std::make_unique<net::dds::DdsTransport>(protocol_config);
#if KEEL_FAULT_INJECTION
    net::FaultConfig faults;  // no loss, delay or duplication; partitions by control command
    faults.plan = plan;
    transport = std::make_unique<net::FaultTransport>(std::move(transport), faults);
#endif
    net::FilterConfig filter;
    for (int id = 0; id < topology.node_count(); ++id) {
        filter.known_nodes.insert(static_cast<net::NodeAddress>(id));
    }
    filter.log_name = "keel.net." + name();
    endpoint = std::make_unique<net::Endpoint>(std::move(transport), filter);
    if (storage && db) {
        net::Endpoint* loop = endpoint.get();
        persister = std::make_unique<CheckpointPersister>(db->path(), [loop] { loop->wake(); });
    }

    tasking::ExecutorLimits limits;
    // Components run on the executor's pool, never on the loop: a long execution (an ACCA
    // pass over a scene) must not delay heartbeats. The pool's and the data plane's threads
    // (and its DDS participant's) are created at the tasks' priority, below the loop's
    // (under --realtime; scheduling.hpp).
    std::optional<TaskPriorityScope> at_task_priority;
    at_task_priority.emplace(scheduling);
    limits.threads = std::clamp<std::size_t>(std::thread::hardware_concurrency(), 2, 4);
    executor = std::make_unique<tasking::Executor>(clock, limits);
    // Each execution at its task's rank among the mission's priorities, and the worker back
    // at the tasks' priority between executions (so that a worker woken for a task of the
    // top rank is not held below a running one). Not when the tasks' threads could not be
    // lowered below the loop (TaskPriorityScope left them at its priority).
    if (scheduling.realtime && scheduling.task_priority > 0 && scheduling.task_priority < scheduling.loop_priority) {
        std::vector<std::int64_t> ranks;
        for (const mission::Task& task : mission.tasks) ranks.push_back(task.priority.value_or(0));
        executor->set_dispatch_hook([priorities = TaskPriorities(scheduling.task_priority, std::move(ranks)),
                                     top = scheduling.task_priority,
                                     node = name()](const tasking::TaskSpec* spec) noexcept {
            static std::atomic<bool> said{false};
            const int result = set_thread_fifo(spec != nullptr ? priorities.of(spec->priority) : top);
            if (result != 0 && spec != nullptr && !said.exchange(true)) {
                try {
                    spdlog::warn("{}: task {} runs at the tasks' priority, not its own: {}", node, spec->name,
                                 std::strerror(result));
                } catch (...) {
                }
            }
        });
    }
    tasks.resize(static_cast<std::size_t>(topology.task_count()));
    const auto configure_start = std::chrono::steady_clock::now();
    const std::size_t component_count = instances.size();
    for (tasking::TaskInstance& instance : instances) {
        const auto id = topology.task_id(instance.spec.name);
        if (!id) continue;
        TaskSlot& slot = tasks[*id];
        slot.name = instance.spec.name;
        slot.checkpoint = instance.spec.checkpoint;
        slot.period_ms = instance.spec.period_ms;
        slot.configured_phase = instance.spec.phase;
        auto added = executor->add(std::move(instance));
        if (!added.id) {
            throw std::runtime_error("task " + slot.name + ": " + added.result.message);
        }
        slot.executor_id = *added.id;
    }
    instances.clear();
    executor->start();
    configure_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(
                        std::chrono::steady_clock::now() - configure_start)
                        .count();
    spdlog::info("{}: configured {} components in {:.3f} ms", name(), component_count,
                 static_cast<double>(configure_ns) / 1e6);
    subscriptions.emplace(mission, topology);
    std::map<std::string, fsm::TaskId, std::less<>> producers;
    std::map<std::int64_t, fsm::TaskId> ports;
    for (std::size_t task = 0; task < mission.tasks.size(); ++task) {
        producers[mission.tasks[task].name] = static_cast<fsm::TaskId>(task);
        ports[mission.tasks[task].port] = static_cast<fsm::TaskId>(task);
    }
    // Samples travel on a participant and a thread of their own (data_plane.hpp).
    std::unique_ptr<net::Transport> data_transport =
        std::make_unique<net::dds::DdsTransport>(data_plane_dds_config(
            dds, addresses,
            options.data_domain_id.value_or(net::dds::data_domain_for(options.domain_id)),
            largest_stated_sample(mission)));
#if KEEL_FAULT_INJECTION
    // The same partitions for samples as for the protocol's messages.
    data_transport = std::make_unique<net::FaultTransport>(std::move(data_transport), faults);
#endif
    net::FilterConfig data_filter = filter;
    data_filter.log_name = "keel.data." + name();
    data_plane = std::make_unique<DataPlane>(
        std::make_unique<net::Endpoint>(std::move(data_transport), data_filter), self,
        std::move(producers), std::move(ports), *executor);
    std::vector<std::size_t> sample_limits;
    for (const mission::Task& task : mission.tasks) {
        sample_limits.push_back(task.max_sample_bytes ? static_cast<std::size_t>(*task.max_sample_bytes) : 0);
    }
    data_plane->set_sample_limits(std::move(sample_limits));
    executor->set_output_sink(data_plane.get());
    data_plane->start();
    at_task_priority.reset();
    if (!scheduling.problems.empty()) {
        spdlog::warn("{}: scheduling: {}", name(), scheduling.problems);
    }

    fsm::NodeOptions protocol_options;
    protocol_options.tracing = trace != nullptr;
    protocol_options.boot = draw_boot_id();
    protocol_options.previous_boot = previous_boot;
    protocol_options.image = image_tag(options.image_sha256);
    protocol_options.kept_checkpoints = std::move(kept_checkpoints);
    const TimeNs start = now();
    boot_ns = start;
    protocol = restart ? std::make_unique<fsm::NodeProtocol>(topology, self, start, protocol_options, *restart)
                       : std::make_unique<fsm::NodeProtocol>(topology, self, start, protocol_options);
    driver = std::make_unique<NodeDriver>(*protocol, *this,
                                          DriverOptions{.coalesce_heartbeats = true, .lines_before_sends = true,
                                                        .one_send_per_command = true});
    spdlog::info("{}: mission {} ({}), node address {}, DDS domain {} on {}, incarnation {} boot {:08x}",
                 name(), mission.name, options.mission_path, self, options.domain_id,
                 options.network_interface, protocol->monitor().incarnation(), protocol_options.boot);
    if (kFaultInjection) {
        spdlog::info("{}: a test build: fault injection on (partition, deaf, heal on stdin); a "
                     "flight build is configured with KEEL_FAULT_INJECTION=OFF", name());
    }
    drive();
    after_step();
}

void NodeRuntime::Impl::shutdown() {
    if (persister) {
        // Every checkpoint taken is written, and its trace line with it.
        persister->stop();
        settle_checkpoints();
    }
    if (data_plane) data_plane->stop();
    if (executor) {
        for (TaskSlot& slot : tasks) {
            if (slot.active) executor->deactivate(slot.executor_id);
            slot.active = false;
        }
        executor->stop();
    }
    if (protocol && db) {
        try {
            db->save_state(current_state());
        } catch (const StateDbError& error) {
            spdlog::error("{}: node state not persisted: {}", name(), error.what());
        }
    }
    if (endpoint) {
        const net::TransportCounters c = endpoint->counters();
        spdlog::info("{}: sent {}, received {}, dropped malformed {}, oversized {}, unknown sender {}, "
                     "stale epoch {}, forged sender {}, replayed {}; bad payload {}, payload naming "
                     "another sender {}", name(), c.sent, c.received, c.dropped_malformed,
                     c.dropped_oversized, c.dropped_unknown_sender, c.dropped_stale_epoch,
                     c.dropped_forged_sender, c.dropped_replayed, counters.bad_payload,
                     counters.forged_sender);
        if (data_plane) {
            const DataPlaneCounters data = data_plane->counters();
            const net::TransportCounters d = data_plane->transport_counters();
            spdlog::info("{}: bytes taken from DDS: protocol {}, samples {}; samples sent {}, "
                         "received {}, send failed {}, queue dropped {}, not addressed here {}, "
                         "above max_sample_bytes {}",
                         name(), c.received_bytes, d.received_bytes, data.samples_sent,
                         data.samples_received, data.send_failed, data.queue_dropped,
                         d.ignored_not_addressed, data.sample_too_large);
        }
    }
    endpoint.reset();
    if (trace != nullptr) {
        std::fclose(trace);
        trace = nullptr;
    }
}

TimeNs NodeRuntime::Impl::next_wait_ns() const {
    const TimeNs current = now();
    TimeNs wait = std::min(kMaxWaitNs, protocol->next_tick_ns() - current);
    // Components run on the pool: their outputs, checkpoints and health events are picked up
    // at this pace (a tenth of the shortest period, at most every 5 ms while any task runs).
    for (const TaskSlot& slot : tasks) {
        if (!slot.active) continue;
        wait = std::min(wait, kActiveWaitNs);
        if (slot.period_ms) {
            wait = std::min(wait, std::max(kMinPeriodicWaitNs, *slot.period_ms * 1'000'000 / 10));
        }
    }
    return std::max<TimeNs>(wait, 0);
}

void NodeRuntime::Impl::read_envelopes() {
    // Everything that queued up, the heartbeats' acknowledgements first: a loop that ran late
    // judges its lease on all it received, not on the first message it reads.
    batch.clear();
    endpoint->poll([&](net::Envelope&& envelope) { batch.push_back(std::move(envelope)); });
    if (batch.size() > 1) {
        for (const net::Envelope& envelope : batch) {
            // Heartbeats, and monitors' replies (on the acknowledgement topic).
            if (envelope.kind != net::MessageKind::heartbeat &&
                envelope.kind != net::MessageKind::acknowledgement) {
                continue;
            }
            fsm::DecodedMessage decoded = fsm::decode(envelope.payload);
            if (decoded.ok() && fsm::sender_of(*decoded.message) == envelope.source) {
                protocol->note_acks(*decoded.message);
            }
        }
    }
    for (net::Envelope& envelope : batch) on_envelope(std::move(envelope));
}

void NodeRuntime::Impl::on_envelope(net::Envelope&& envelope) {
    if (carries_protocol(envelope.kind)) {
        fsm::DecodedMessage decoded = fsm::decode(envelope.payload);
        if (!decoded.ok()) {
            std::lock_guard lock(counters_mutex);
            ++counters.bad_payload;
            if (net::log_this_drop(counters.bad_payload)) {
                spdlog::warn("{}: dropped {} from node {} (bad payload #{}): {} ({})", name(),
                             net::to_string(envelope.kind), envelope.source, counters.bad_payload,
                             fsm::to_string(decoded.error), decoded.detail);
            }
            return;
        }
        const fsm::Message& message = *decoded.message;
        if (fsm::sender_of(message) != envelope.source || kind_of(message) != envelope.kind) {
            std::lock_guard lock(counters_mutex);
            ++counters.forged_sender;
            if (net::log_this_drop(counters.forged_sender)) {
                spdlog::warn("{}: dropped {} claiming sender {} in an envelope from node {} on {} "
                             "(forged sender #{})",
                             name(), fsm::kind_name(message), fsm::sender_of(message), envelope.source,
                             net::to_string(envelope.kind), counters.forged_sender);
            }
            return;
        }
        protocol->step(message, now());
        warn_of_refusals();
        drive();
    }
    // Samples are the data plane's: its own participant reads them (data_plane.hpp).
}

std::string NodeRuntime::Impl::refused_json() const {
    const fsm::NodeStats& stats = protocol->stats();
    const auto by_kind = [](const auto& counts) {
        fsm::JsonObject object;
        for (std::size_t kind = 0; kind < counts.size(); ++kind) {
            if (counts[kind] != 0) object.field(fsm::kind_name(kind), counts[kind]);
        }
        return object.str();
    };
    return fsm::JsonObject()
        .raw("malformed", by_kind(stats.malformed))
        .raw("unauthorized", by_kind(stats.unauthorized))
        .field("commands_refused", stats.commands_refused)
        .field("ahead_dropped", stats.ahead_dropped)
        .field("commands_unbacked", stats.commands_unbacked)
        .field("prepared_diverged", stats.prepared_diverged)
        .field("passed_over", stats.passed_over)
        .field("activations_held", protocol->config_switch().activations_held())
        .str();
}

void NodeRuntime::Impl::warn_of_refusals() {
    // A node on another mission image: said once per node and image.
    for (int index = 0; index < topology.node_count(); ++index) {
        const auto node = static_cast<fsm::NodeId>(index);
        const std::uint64_t image = protocol->foreign_image(node);
        if (image == 0 || image == foreign_image_warned[node]) continue;
        foreign_image_warned[node] = image;
        spdlog::warn("{}: {} flies another mission image (sha256 {:016x}..., this node flies {}...): "
                     "it takes no part here until it flies this one, and everything it sends is "
                     "dropped (dropped.foreign_image)",
                     name(), topology.node_name(node), image, options.image_sha256.substr(0, 16));
    }
    const fsm::NodeStats& stats = protocol->stats();
    std::uint64_t total = stats.commands_refused;
    for (const std::uint64_t count : stats.malformed) total += count;
    for (const std::uint64_t count : stats.unauthorized) total += count;
    if (total == refusals_warned) return;
    // At most one line a second: a flood is counted, not logged message by message.
    const TimeNs current = now();
    if (refusals_warned != 0 && current - refusals_warned_at < 1'000'000'000) return;
    spdlog::warn("{}: refused {} message(s) since the last report (fault model 3), the last: {}", name(),
                 total - refusals_warned, protocol->last_refusal());
    refusals_warned = total;
    refusals_warned_at = current;
}

std::string utc_text(std::time_t at) {
    std::tm utc{};
    gmtime_r(&at, &utc);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
    return text;
}

void NodeRuntime::Impl::warn_of_expiry() {
    if (options.credential_expiries.empty()) return;
    const std::time_t wall = std::time(nullptr);
    if (expiry_warned_at != 0 && wall - expiry_warned_at < 3600) return;
    for (const net::dds::CredentialExpiry& expiry : options.credential_expiries) {
        if (!expiry.due(wall)) continue;
        expiry_warned_at = wall;
        spdlog::warn("{}: {} ({}) expires on {} (in {:.1f} days): renew the credentials before then "
                     "(docs/security.md, \"Credentials: expiry, renewal and revocation\"); after it "
                     "this node or its peers refuse them",
                     name(), expiry.what, expiry.file, utc_text(expiry.at),
                     static_cast<double>(expiry.at - wall) / 86'400.0);
        return;
    }
}

std::string NodeRuntime::Impl::credentials_json() const {
    if (options.credential_expiries.empty()) return "null";
    const net::dds::CredentialExpiry& first = options.credential_expiries.front();
    const std::time_t wall = std::time(nullptr);
    bool due = false;
    for (const auto& expiry : options.credential_expiries) due = due || expiry.due(wall);
    return fsm::JsonObject()
        .field("first_expiry", utc_text(first.at))
        .field("what", first.what)
        .field("file", first.file)
        .field("in_s", static_cast<std::int64_t>(first.at - wall))
        .field("warning", due)
        .str();
}

void NodeRuntime::Impl::warn_if_no_master() {
    if (protocol->stats().warm_boots > warm_boots_logged) {
        warm_boots_logged = protocol->stats().warm_boots;
        spdlog::info("{}: warm boot: every node restarted from its saved state and waits to be "
                     "commanded; Master of epoch {} in {} (spec/MasterElection.tla, WarmBoot)",
                     name(), protocol->epoch(), topology.config_name(protocol->manager().driving().config));
    }
    if (!protocol->waiting() || no_master_warned || protocol->is_master()) return;
    const TimeNs silent_ns = now() - boot_ns;
    const TimeNs limit_ns =
        kNoMasterWarningPeriods * topology.miss_limit() * topology.heartbeat_period_ns();
    if (silent_ns < limit_ns) return;
    no_master_warned = true;
    spdlog::warn(
        "{}: restarted from its persisted state ({}, epoch {}) and no Master has commanded it "
        "in {:.1f} s. A restarted node rejoins as a Worker and never resumes a mastership; "
        "after a whole-cluster power cycle the master of the phase's initial configuration "
        "takes over once it has heard every processing node waiting, so a processing node "
        "has not come back, or a node heard was not restarted from its state. Bring the "
        "missing node back, or restart every node with --cold-start: they boot the initial "
        "configuration, and the Storage node's checkpoints are kept and resumed.",
        name(), db ? db->path() : std::string("?"), protocol->epoch(),
        static_cast<double>(silent_ns) / 1e9);
}

void NodeRuntime::Impl::run_tasks() {
    // Checkpointing service: each new snapshot of a checkpointed task becomes a step of the
    // task for the protocol, which flushes it to the Storage node.
    for (tasking::Snapshot& snapshot : executor->take_checkpoints()) {
        const auto task = topology.task_id(snapshot.task);
        if (!task || !tasks[*task].active) continue;
        std::vector<std::uint8_t> bytes = encode_snapshot(snapshot);
        if (const auto& bound = topology.task(*task).max_state_bytes; bound && bytes.size() > *bound) {
            // The component broke its mission's bound: the task's error (restart from its
            // last checkpoint, then resign), and the state is never sent.
            {
                std::lock_guard lock(counters_mutex);
                ++counters.state_too_large;
            }
            handle_health({snapshot.task, tasking::HealthEventKind::error, std::nullopt, 0,
                           "a checkpoint state of " + std::to_string(snapshot.payload.size()) +
                               " bytes, above its max_state_bytes " +
                               std::to_string(*bound - fsm::kSnapshotHeaderBytes)});
            continue;
        }
        tasks[*task].last_state = bytes;
        protocol->task_stepped(*task, std::move(bytes), now());
        drive();
    }
    for (const tasking::HealthEvent& event : executor->take_health_events()) handle_health(event);
    std::vector<tasking::HealthEvent> failed_to_start;
    failed_to_start.swap(unstarted);
    for (const tasking::HealthEvent& event : failed_to_start) handle_health(event);
}

void NodeRuntime::Impl::handle_health(const tasking::HealthEvent& event) {
    const auto task = topology.task_id(event.task);
    {
        std::lock_guard lock(counters_mutex);
        ++counters.health_events;
    }
    if (!task || !tasks[*task].active) return;
    TaskSlot& slot = tasks[*task];
    spdlog::warn("{}: task {} unhealthy ({}): {}", name(), slot.name, tasking::to_string(event.kind),
                 event.detail);
    if (trace != nullptr) {
        write_trace({"health", "TaskUnhealthy",
                     fsm::JsonObject()
                         .field("n", name())
                         .field("t", slot.name)
                         .field("kind", tasking::to_string(event.kind))
                         .str(),
                     fsm::JsonObject().field("restarts", slot.restarts).str()});
    }
    if (slot.restarts < kMaxLocalRestarts) {
        // Restart: the component stops and starts again from its latest checkpoint.
        ++slot.restarts;
        {
            std::lock_guard lock(counters_mutex);
            ++counters.task_restarts;
        }
        executor->deactivate(slot.executor_id);
        std::optional<tasking::Snapshot> snapshot;
        if (slot.checkpoint && !slot.last_state.empty()) snapshot = decode_snapshot(slot.last_state, slot.name);
        const tasking::LifecycleResult result = start_task(slot, snapshot, "its last");
        spdlog::info("{}: restarted task {} ({})", name(), slot.name,
                     result.succeeded() ? "ok" : result.message);
        return;
    }
    // Relocate: the decision graph is keyed by node, so the node resigns (NodeProtocol::resign):
    // a Worker or Observer asks its Master to exclude it; the Master steps down, flushes its
    // checkpoints and says it is excluded, so the first Observer takes over. Either way the
    // graph's edge for this node moves what it hosts.
    if (protocol->resign_state() != fsm::NodeProtocol::Resign::none) return;  // already resigning
    const fsm::View& view = protocol->view();
    if (protocol->is_master()) {
        spdlog::error("{}: task {} keeps failing after {} restart(s) on the Master; stepping down so "
                      "the next Observer relocates it", name(), slot.name, slot.restarts);
    } else {
        spdlog::error("{}: task {} keeps failing after {} restart(s); asking {} to relocate it",
                      name(), slot.name, slot.restarts, topology.node_name(view.master));
    }
    protocol->resign(now());
    drive();
}

void NodeRuntime::Impl::handle_command(const std::string& line, bool& quit) {
    const std::vector<std::string> words = split_words(line);
    if (words.empty()) return;
    const std::string& verb = words[0];
    if (verb == "quit") {
        quit = true;
    } else if (verb == "status") {
        print_status(true);
    } else if (!kFaultInjection && (verb == "heal" || verb == "partition" || verb == "deaf")) {
        spdlog::warn("{}: '{}' refused: this keel-node is a flight build, without fault injection "
                     "(KEEL_FAULT_INJECTION=OFF)", name(), verb);
#if KEEL_FAULT_INJECTION
    } else if (verb == "heal") {
        plan->heal();
        spdlog::info("{}: partitions healed", name());
    } else if (verb == "partition") {
        std::set<net::NodeAddress> others;
        for (std::size_t i = 1; i < words.size(); ++i) {
            const auto node = topology.node_id(words[i]);
            if (!node) {
                spdlog::warn("{}: partition: unknown node '{}'", name(), words[i]);
                continue;
            }
            if (*node != self) others.insert(*node);
        }
        plan->partition({self}, others);
        spdlog::info("{}: partitioned from {} node(s)", name(), others.size());
    } else if (verb == "deaf") {
        // Receive omission (fault model 2): nothing from the named nodes (all: none named)
        // reaches this node; it still sends. `heal` ends it.
        std::size_t count = 0;
        for (fsm::NodeId node = 0; node < topology.node_count(); ++node) {
            if (node == self) continue;
            const bool named = words.size() == 1 ||
                std::find(words.begin() + 1, words.end(), topology.node_name(node)) != words.end();
            if (!named) continue;
            plan->block(node, self);
            ++count;
        }
        spdlog::info("{}: deaf to {} node(s)", name(), count);
#endif
    } else if (verb == "ground") {
        // The seq is saved before the command acts: a node without a state database, or
        // whose disk failed, takes none (it could not refuse a replay after a restart).
        const auto admitted = ground->admit(std::string_view(line).substr(line.find("ground") + 6),
                                            std::time(nullptr), db != nullptr && !driver->state_failed());
        if (const auto* refusal = std::get_if<GroundRefusal>(&admitted)) {
            spdlog::warn("{}: ground command refused ({}): {}", name(), refusal->kind, refusal->why);
            return;
        }
        const auto& command = std::get<GroundCommand>(admitted);
        // Its seq is on the disk before it acts: replayed after a restart, it is refused.
        if (!driver->save_state(now())) return;
        spdlog::info("{}: ground command seq {} admitted: {} {}", name(), command.seq, command.verb,
                     fmt::join(command.arguments, " "));
        act_on_ground(command.verb, command.arguments);
    } else if ((verb == "phase" || verb == "recover" || verb == "exclude" || verb == "readmit" ||
                verb == "pause-task" || verb == "resume-task") &&
               words.size() == 2) {
        if (const auto refusal = ground->admit_unsigned(verb)) {
            spdlog::warn("{}: {} {} refused ({}): {}", name(), verb, words[1], refusal->kind, refusal->why);
            return;
        }
        act_on_ground(verb, {words[1]});
    } else {
        spdlog::warn("{}: unknown control command '{}'", name(), line);
    }
}

void NodeRuntime::Impl::act_on_ground(const std::string& verb, const std::vector<std::string>& arguments) {
    const std::string& argument = arguments.front();
    if (verb == "designate") {
        // The ground's vote (spec/Designate.tla): every node keeps the latest designation;
        // the designee takes over once its side's declarations stood the tie's grace.
        const auto node = topology.node_id(argument);
        const auto number = [&](std::size_t i) -> std::optional<std::int64_t> {
            try {
                std::size_t used = 0;
                const long long value = std::stoll(arguments.at(i), &used);
                if (used != arguments.at(i).size() || value < 0 || value > 1'000'000'000) return std::nullopt;
                return value;
            } catch (const std::exception&) {
                return std::nullopt;
            }
        };
        const auto wait = number(1);
        const auto span = number(2);
        const auto echo = number(3);
        if (!node || !wait || !span || !echo || *wait > 1'000'000 || *span > 1'000'000 ||
            *echo > std::numeric_limits<std::uint32_t>::max()) {
            spdlog::warn("{}: designate {}: expected NODE WAIT SPAN ECHO (a node of the mission, whole "
                         "periods, the designee's heartbeat number)",
                         name(), fmt::join(arguments, " "));
            return;
        }
        const std::string why = protocol->ground_designate(*node, static_cast<int>(*wait), static_cast<int>(*span),
                                                           static_cast<std::uint32_t>(*echo), now());
        drive();
        if (!why.empty()) {
            spdlog::warn("{}: designate {} refused: {}", name(), argument, why);
        } else {
            spdlog::info("{}: designate {}: the ground's vote is for {}", name(), argument, argument);
        }
        return;
    }
    if (verb == "phase") {
        const auto phase = topology.phase_id(argument);
        if (!phase) {
            spdlog::warn("{}: phase: unknown phase '{}'", name(), argument);
            return;
        }
        // Only the Master acts on it (the ground sends it to every node); the initial
        // Master still waiting for its lease keeps it for after the boot switch.
        if (protocol->role() == fsm::Role::Master) {
            protocol->request_phase(*phase, now());
            drive();
        }
    } else if (verb == "recover") {
        // Leave safe mode for this configuration (fault model 2, item 3).
        const auto config = topology.config_id(argument);
        if (!config || *config == fsm::kSafeConfig) {
            spdlog::warn("{}: recover: unknown configuration '{}'", name(), argument);
            return;
        }
        if (protocol->role() != fsm::Role::Master) return;  // the Master decides
        const std::string why = protocol->request_recovery(*config, now());
        drive();
        if (why.empty()) {
            spdlog::info("{}: recover: leaving safe mode for {}", name(), argument);
        } else {
            spdlog::warn("{}: recover {} refused: {}", name(), argument, why);
        }
    } else if (verb == "exclude" || verb == "readmit") {
        // The ground holds a node out (the acting Master excludes it by its own switch once
        // its walk from its view passes; a Master named steps down; no Master readmits it),
        // or lets it back. Every node keeps the set.
        const auto node = topology.node_id(argument);
        if (!node) {
            spdlog::warn("{}: {}: unknown node '{}'", name(), verb, argument);
            return;
        }
        const std::string why = verb == "exclude" ? protocol->ground_exclude(*node, now())
                                                  : protocol->ground_readmit(*node, now());
        drive();
        if (!why.empty()) {
            spdlog::warn("{}: {} {} refused: {}", name(), verb, argument, why);
        } else if (*node == self && verb == "exclude") {
            spdlog::warn("{}: held out by the ground: the Master excludes it (a Master steps down), and "
                         "it stays out until the ground readmits it",
                         name());
        } else {
            spdlog::info("{}: {} {}: the ground holds out {}", name(), verb, argument,
                         fsm::json_nodes(topology, protocol->held_out()));
        }
    } else if (verb == "pause-task" || verb == "resume-task") {
        // The ground stops a task where it runs, keeping it placed (or lets it run again).
        // Every node keeps the set, so the task stays paused wherever a switch moves it.
        const auto task = topology.task_id(argument);
        if (!task) {
            spdlog::warn("{}: {}: unknown task '{}'", name(), verb, argument);
            return;
        }
        const std::string why = verb == "pause-task" ? protocol->ground_pause(*task, now())
                                                     : protocol->ground_resume(*task, now());
        drive();
        if (!why.empty()) {
            spdlog::warn("{}: {} {} refused: {}", name(), verb, argument, why);
        } else {
            spdlog::info("{}: {} {}: the ground pauses {}", name(), verb, argument,
                         fsm::json_tasks(topology, protocol->paused()));
        }
    }
}

net::Envelope NodeRuntime::Impl::envelope_for(net::NodeAddress to, const fsm::Message& message) {
    // The lines written before it (the driver writes a step's lines before its messages)
    // reach the file before the message leaves: a node killed now keeps them.
    if (trace != nullptr) std::fflush(trace);
    scratch.clear();
    fsm::encode_into(message, scratch);
    endpoint->set_local_epoch(protocol->epoch());
    return endpoint->make_envelope(kind_of(message), to, 0, scratch);
}

void NodeRuntime::Impl::send(fsm::NodeId to, const fsm::Message& message) {
    endpoint->send(envelope_for(to, message));
}

void NodeRuntime::Impl::send_to_each(const std::vector<fsm::NodeId>& to, const fsm::Message& message) {
    destinations.assign(to.begin(), to.end());
    endpoint->send_to_each(envelope_for(net::broadcast_address, message), destinations);
}

void NodeRuntime::Impl::drive() {
    driver->drive(now());
    follow_phase();
    if (trace != nullptr) std::fflush(trace);
}

void NodeRuntime::Impl::declared_failed(const fsm::act::DeclareFailed& declared) {
    spdlog::warn("{}: declared {} failed", name(), topology.node_name(declared.node));
}

void NodeRuntime::Impl::entered_safe_mode() {
    spdlog::warn("{}: entering safe mode: only essential tasks run, on this node", name());
}

std::optional<std::uint64_t> NodeRuntime::Impl::store_checkpoint(fsm::act::StoreCheckpoint& store) {
    if (!persister) return std::nullopt;
    return persister->store(store.task, topology.task(store.task).name, store.version, std::move(store.state),
                            store.replaces);
}

void NodeRuntime::Impl::disk_failed(std::string_view what) {
    stopping_for_disk = true;
    spdlog::error("{}: {}: it asks to be excluded and stops (exit {}); restart it once its disk "
                  "is fixed",
                  name(), what, kDiskFailureExit);
    print_status(true);
}

StoredState NodeRuntime::Impl::current_state() const {
    return StoredState{protocol->epoch(), protocol->view(), protocol->monitor().incarnation(),
                       protocol->monitor().boot(), mission.revision.value_or(0),
                       static_cast<std::int64_t>(ground->last_seq()), protocol->held_out(),
                       options.image_sha256, protocol->paused()};
}

bool NodeRuntime::Impl::save_state() {
    if (!db) return true;
    // Only what a restart needs besides checkpoints (those are stored as they come).
    const StoredState stored = current_state();
    if (persisted && persisted->epoch == stored.epoch && persisted->view == stored.view &&
        persisted->incarnation == stored.incarnation && persisted->boot == stored.boot &&
        persisted->revision == stored.revision && persisted->ground_seq == stored.ground_seq &&
        persisted->held_out == stored.held_out && persisted->image == stored.image &&
        persisted->paused == stored.paused) {
        return true;
    }
    const std::int64_t started = steady_ns();
    try {
        db->save_state(stored);
    } catch (const StateDbError& error) {
        spdlog::error("{}: node state not saved: {}", name(), error.what());
        return false;
    }
    const std::int64_t took = steady_ns() - started;
    ++state_writes;
    state_write_ns += took;
    state_write_max_ns = std::max(state_write_max_ns, took);
    persisted = stored;
    return true;
}

void NodeRuntime::Impl::settle_checkpoints() {
    // No driver: the boot failed before the protocol started, and nothing was stored.
    if (!persister || !driver) return;
    for (const CheckpointPersister::Written& written : persister->take_written()) {
        if (written.error.empty()) {
            driver->checkpoint_written(written.task, written.ticket);
            continue;
        }
        spdlog::error("{}: checkpoint of {} version {} not stored: {}", name(), topology.task(written.task).name,
                      fsm::version_text(written.version), written.error);
        driver->checkpoint_failed(written.task, written.ticket, now());
    }
    if (trace != nullptr) std::fflush(trace);
}

// A phase change that keeps a task on this node (the switch leaves it active) reaches it
// too: it is deactivated, configured with the new phase's parameters and activated again
// from its latest state (core/tasking/DESIGN.md, step 2). Activate actions configure the
// tasks they start themselves.
void NodeRuntime::Impl::follow_phase() {
    const std::string& phase = topology.phase(topology.phase_of(protocol->view())).name;
    for (TaskSlot& slot : tasks) {
        if (!slot.active || slot.configured_phase == phase) continue;
        auto spec = tasking::make_task_spec(mission, slot.name, phase);
        auto* ok = std::get_if<tasking::TaskSpec>(&spec);
        if (ok == nullptr) {
            slot.configured_phase = phase;  // the task has no spec in this phase: nothing to apply
            continue;
        }
        executor->deactivate(slot.executor_id);
        const auto configured = executor->configure(slot.executor_id, std::move(*ok));
        if (!configured.succeeded()) {
            spdlog::warn("{}: task {}: configure for phase {}: {}", name(), slot.name, phase,
                         configured.message);
        }
        slot.configured_phase = phase;
        std::optional<tasking::Snapshot> snapshot;
        if (slot.checkpoint && !slot.last_state.empty()) snapshot = decode_snapshot(slot.last_state, slot.name);
        if (start_task(slot, snapshot, "its last").succeeded()) {
            spdlog::info("{}: {} stays here in phase {}: reconfigured", name(), slot.name, phase);
        }
    }
}

void NodeRuntime::Impl::activate(const fsm::act::Activate& action) {
    if (action.task >= tasks.size()) return;
    TaskSlot& slot = tasks[action.task];
    const fsm::View& view = protocol->view();
    const fsm::PhaseId phase_id = topology.phase_of(view);
    const std::string& phase = topology.phase(phase_id).name;
    if (slot.active) executor->deactivate(slot.executor_id);
    if (slot.configured_phase != phase) {
        auto spec = tasking::make_task_spec(mission, slot.name, phase);
        if (auto* ok = std::get_if<tasking::TaskSpec>(&spec)) {
            const auto result = executor->configure(slot.executor_id, std::move(*ok));
            if (result.succeeded()) slot.configured_phase = phase;
            else spdlog::warn("{}: task {}: configure for phase {}: {}", name(), slot.name, phase, result.message);
        }
    }
    std::optional<tasking::Snapshot> snapshot;
    if (!action.state.empty()) {
        snapshot = decode_snapshot(action.state, slot.name);
        if (!snapshot) spdlog::warn("{}: task {}: checkpoint version {} does not decode; starting fresh",
                                    name(), slot.name, fsm::version_text(action.version));
    }
    const tasking::LifecycleResult result = start_task(slot, snapshot, fsm::version_text(action.version));
    slot.active = true;
    slot.restarts = 0;
    slot.last_state = action.state;
    if (result.succeeded()) {
        spdlog::info("{}: activated {} at version {}{}", name(), slot.name, fsm::version_text(action.version),
                     action.restored ? " (restored from the Storage node)" : "");
    }
}

tasking::LifecycleResult NodeRuntime::Impl::start_task(TaskSlot& slot, const std::optional<tasking::Snapshot>& snapshot,
                                                       const std::string& version) {
    const tasking::Executor::Activation activation = executor->activate_or_fresh(slot.executor_id, snapshot);
    if (activation.refused) {
        // A state the component cannot read is lost, as one that does not decode: the task
        // starts fresh, and the loss is said.
        spdlog::error("{}: task {}: the component refused its checkpoint version {} ({}); starting fresh",
                      name(), slot.name, version, *activation.refused);
    }
    if (!activation.result.succeeded()) {
        // It does not run here although the cluster places it here: the task's error, as
        // an unhealthy task's (restart, then resign so the graph moves it), handled after
        // the action that started it (handle_health may resign, which drives the protocol).
        spdlog::error("{}: task {}: activate: {}", name(), slot.name, activation.result.message);
        unstarted.push_back({slot.name, tasking::HealthEventKind::error, std::nullopt, 0,
                             "did not start: " + activation.result.message});
    }
    return activation.result;
}

void NodeRuntime::Impl::deactivate(fsm::TaskId task) {
    if (task >= tasks.size()) return;
    TaskSlot& slot = tasks[task];
    if (!slot.active) return;
    executor->deactivate(slot.executor_id);
    slot.active = false;
    spdlog::info("{}: deactivated {}", name(), slot.name);
}

void NodeRuntime::Impl::write_trace(const fsm::act::Trace& trace_action) {
    if (trace == nullptr) return;
    std::string line = "{\"t_ns\":" + std::to_string(wall_clock_ns()) + ",\"node\":";
    fsm::append_json_string(line, name());
    line += ",\"fsm\":";
    fsm::append_json_string(line, trace_action.fsm);
    line += ",\"action\":";
    fsm::append_json_string(line, trace_action.action);
    line += ",\"args\":" + (trace_action.args.empty() ? std::string("{}") : trace_action.args);
    line += ",\"vars\":" + (trace_action.vars.empty() ? std::string("{}") : trace_action.vars);
    line += "}\n";
    std::fwrite(line.data(), 1, line.size(), trace);
}

void NodeRuntime::Impl::after_step() {
    const fsm::Epoch epoch = protocol->epoch();
    if (epoch != floor_epoch) {
        floor_epoch = epoch;
        endpoint->set_epoch_floor(epoch);
        endpoint->set_local_epoch(epoch);
        data_plane->set_epoch(epoch);
    }
    const fsm::View& view = protocol->view();
    if (!routed_view || !(*routed_view == view)) {
        routed_view = view;
        if (subscriptions->update(view)) {
            std::vector<std::vector<fsm::NodeId>> routes;
            for (int task = 0; task < topology.task_count(); ++task) {
                routes.push_back(subscriptions->destinations(static_cast<fsm::TaskId>(task)));
            }
            data_plane->set_routes(std::move(routes));
            if (self_is_interface()) {
                spdlog::info("{}: subscriptions for {}: {}", name(), topology.config_name(view.config),
                             subscriptions->describe());
            }
        }
        if (view.is_safe() && !safe_mode_logged) {
            safe_mode_logged = true;
            spdlog::warn("{}: cluster in safe mode (master {})", name(), topology.node_name(view.master));
        }
    }
    driver->save_state(now());
    print_status(false);
}

std::string NodeRuntime::Impl::role_name() const {
    // A node that asked to be excluded, until a view readmits it or it restarts (a Master
    // that stepped down keeps the Master role in its election until the view that excludes
    // it arrives): operators see one Master.
    if (protocol->resign_state() != fsm::NodeProtocol::Resign::none) return "Resigned";
    switch (protocol->role()) {
        case fsm::Role::Master: return "Master";
        case fsm::Role::Observer: return "Observer";
        case fsm::Role::Worker: break;
    }
    const mission::Node& node = mission.nodes.at(self);
    if (node.is_storage()) return "Storage";
    if (!node.is_processing()) return "Interface";
    return "Worker";
}

void NodeRuntime::Impl::print_status(bool force) {
    const fsm::View& view = protocol->view();
    fsm::TaskSet running;
    for (std::size_t id = 0; id < tasks.size(); ++id) {
        if (tasks[id].active) running.insert(static_cast<fsm::TaskId>(id));
    }
    // On the Master: the tasks its view places, less those the ground paused (as it took
    // the ground's commands).
    fsm::TaskSet expected;
    if (protocol->is_master()) {
        for (int id = 0; id < topology.task_count(); ++id) {
            if (topology.host(view, static_cast<fsm::TaskId>(id)) != fsm::kNoNode &&
                !protocol->paused().contains(static_cast<fsm::TaskId>(id))) {
                expected.insert(static_cast<fsm::TaskId>(id));
            }
        }
    }
    const std::string role = role_name();
    const std::string config = topology.config_name(view.config);
    const std::string& phase = topology.phase(topology.phase_of(view)).name;
    const bool driving = protocol->is_master() &&
                         protocol->config_switch().master_stage() == fsm::MasterStage::Idle;
    // The tasks by id, in increasing order: "3,7,12".
    auto members = [](const fsm::TaskSet& set) {
        std::string text;
        set.for_each([&](fsm::TaskId id) {
            if (!text.empty()) text += ',';
            text += std::to_string(id);
        });
        return text;
    };
    const std::string key = role + "|" + std::to_string(protocol->epoch()) + "|" + config + "|" +
                            phase + "|" + members(running) + "|" + members(expected) + "|" +
                            (driving ? "d" : "-") + (protocol->stood_down() ? "s" : "-") +
                            (protocol->holds_vote() ? "v" : "-");
    if (!force && key == last_status_key) return;
    last_status_key = key;
    net::NodeState state;
    state.node = self;
    state.name = name();
    state.role = role == "Master"     ? net::Role::master
                 : role == "Observer" ? net::Role::observer
                 : role == "Storage"  ? net::Role::storage
                 : role == "Interface" ? net::Role::interface
                 : role == "Resigned"  ? net::Role::resigned
                                       : net::Role::worker;
    state.epoch = protocol->epoch();
    state.configuration_id = view.config;
    state.configuration = config;
    state.phase = phase;
    endpoint->publish_node_state(state);
    if (!options.status_sink) return;
    const net::TransportCounters c = endpoint->counters();
    const net::TransportCounters data =
        data_plane ? data_plane->transport_counters() : net::TransportCounters{};
    // Per task it runs: executions, samples in and out since the process started (the
    // console's data rates are their differences over time).
    fsm::JsonObject task_counts;
    for (const TaskSlot& slot : tasks) {
        if (!slot.active) continue;
        const tasking::TaskStats stats = executor->stats(slot.executor_id);
        task_counts.raw(slot.name, fsm::JsonObject()
                                       .field("executions", stats.executions)
                                       .field("inputs", stats.inputs_received)
                                       .field("outputs", stats.outputs)
                                       .str());
    }
    std::string line = fsm::JsonObject()
                           .field("t_ns", wall_clock_ns())
                           .field("node", name())
                           .field("role", role)
                           .field("epoch", protocol->epoch())
                           .field("seq", protocol->view().seq)
                           .field("config", config)
                           .field("phase", phase)
                           // The nodes its view excludes (the graph's failed set).
                           .raw("failed", fsm::json_nodes(topology, protocol->view().failed))
                           // The Master drives its view, no switch under way (a Master
                           // handed a view drives it only once it holds its lease).
                           .field("driving", driving)
                           // spec/Designate.tla (a mission with heartbeat.tie_grace): its
                           // lease lapsed in a tie and it stands down; it holds the ground's
                           // vote; its latest heartbeat's number (what `designate` echoes).
                           .field("stood_down", protocol->stood_down())
                           .field("vote", protocol->holds_vote())
                           .field("heartbeat_seq", static_cast<std::uint64_t>(protocol->monitor().seq()))
                           .raw("tasks", fsm::json_tasks(topology, running))
                           .raw("expected_tasks", fsm::json_tasks(topology, expected))
                           .raw("task_counts", task_counts.str())
                           .raw("dropped", fsm::JsonObject()
                                               .field("malformed", c.dropped_malformed)
                                               .field("oversized", c.dropped_oversized)
                                               .field("unknown_sender", c.dropped_unknown_sender)
                                               .field("stale_epoch", c.dropped_stale_epoch)
                                               .field("bad_payload", counters.bad_payload)
                                               // A payload naming another sender than its
                                               // envelope, or an envelope naming another
                                               // node than its writer speaks for.
                                               .field("forged_sender", counters.forged_sender +
                                                                           c.dropped_forged_sender +
                                                                           data.dropped_forged_sender)
                                               .field("replayed", c.dropped_replayed + data.dropped_replayed)
                                               // Samples above their task's max_sample_bytes.
                                               .field("sample_too_large",
                                                      data_plane ? data_plane->counters().sample_too_large : 0)
                                               // Checkpoint states above their task's
                                               // max_state_bytes (never sent).
                                               .field("state_too_large", counters.state_too_large)
                                               // Checkpoint writes (the Storage node) and
                                               // requests no honest node sends, and
                                               // requests left for the requester to repeat
                                               // (CheckpointStore, request_budget.hpp).
                                               .field("foreign_checkpoint",
                                                      (protocol->store() != nullptr
                                                           ? protocol->store()->refused_writes()
                                                           : 0) +
                                                          protocol->request_budget().refused())
                                               .field("request_limited",
                                                      protocol->request_budget().limited())
                                               // A stored checkpoint whose writer hosts
                                               // the task in neither of the Storage node's
                                               // last two views, replaced by the host's
                                               // older write (a foreign pin, fault model 3).
                                               .field("overridden_checkpoint",
                                                      protocol->store() != nullptr
                                                          ? protocol->store()->overridden()
                                                          : 0)
                                               // Heartbeats of a boot of their sender
                                               // that has ended (overtaken by the next).
                                               .field("retired_boot",
                                                      protocol->stats().retired_boot_heartbeats)
                                               // Hand-overs naming a boot of this node
                                               // that has ended (a restart within their
                                               // repeats).
                                               .field("stale_hand_over", protocol->stats().hand_overs_stale)
                                               // Messages of a node flying another
                                               // mission image (it takes no part).
                                               .field("foreign_image", protocol->stats().foreign_image)
                                               // Stored or handed-off states offered with a
                                               // step count no correct run reaches
                                               // (fsm::kMaxAdoptedCount): treated as lost.
                                               .field("unadoptable_state",
                                                      protocol->config_switch().unadoptable_states())
                                               .str())
                           // Fault model 3 (core/fsm/admission.hpp): messages refused
                           // for an id the mission lacks or a sender whose role may not
                           // send them, by kind; Commands refused as no Master's.
                           .raw("refused", refused_json())
                           // What --realtime got (scheduling.hpp): the loop's and the
                           // tasks' SCHED_FIFO priorities (0: normal), memory locked, the
                           // passes the loop's budget cut short, and why not real-time.
                           .raw("scheduling", fsm::JsonObject()
                                                  .field("realtime", scheduling.realtime)
                                                  .field("loop_priority", scheduling.loop_priority)
                                                  .field("task_priority", scheduling.task_priority)
                                                  .field("memory_locked", scheduling.memory_locked)
                                                  .field("budget_percent",
                                                         budget ? options.scheduling.budget_percent : 100)
                                                  .field("throttled", budget ? budget->throttled() : 0)
                                                  .field("fallback", scheduling.fallback)
                                                  .field("lock_error", scheduling.lock_error)
                                                  .str())
                           // Ground commands admitted and refused, by reason (ground.hpp).
                           .raw("ground", ground->json())
                           .raw("held_out", fsm::json_nodes(topology, protocol->held_out()))
                           .raw("paused", fsm::json_tasks(topology, protocol->paused()))
                           // Ticks a Master left held-out nodes in: their exclusion would
                           // reach safe mode from its view (NodeStats).
                           .field("ground_withheld", protocol->stats().ground_exclusions_withheld)
                           // The first of the node's credentials to expire (warn_of_expiry).
                           .raw("credentials", credentials_json())
                           // Checkpoints read back from disk at boot that failed their
                           // checksum: lost, not restored (the Storage node only).
                           .field("lost_checkpoints", lost_checkpoints)
                           // Take-overs (or a Master's move past a newer epoch) not made
                           // because the epoch they would open is within a lap of the
                           // width: only --cold-start helps then.
                           .field("take_overs_refused", protocol->stats().take_overs_refused)
                           // Readmissions (hand-overs) not made for the same reason.
                           .field("readmissions_refused", protocol->stats().readmissions_refused)
                           // Disk failures: the node's state not saved, checkpoints not
                           // written (the Storage node); either makes the node resign.
                           .raw("disk_errors", fsm::JsonObject()
                                                   .field("state", driver->counters().state_save_errors)
                                                   .field("checkpoints",
                                                          driver->counters().checkpoint_write_errors)
                                                   .str())
                           // Serialized bytes the protocol's participant took from DDS
                           // (checkpoints reach the Storage node only: they are addressed).
                           .field("protocol_taken_bytes", c.received_bytes)
                           // Serialized bytes the data plane took from DDS (samples of
                           // other nodes' components, and any flood addressed here).
                           .field("data_taken_bytes", data.received_bytes)
                           // The Storage node's disk (CheckpointPersister): checkpoints
                           // written, replaced while waiting by a newer one of their task,
                           // and messages or trace lines waiting for a write.
                           // The node's own state saves (save_state): their number, and
                           // their time in total and at most, in microseconds.
                           .raw("state_writes", fsm::JsonObject()
                                                    .field("count", state_writes)
                                                    .field("total_us", state_write_ns / 1000)
                                                    .field("max_us", state_write_max_ns / 1000)
                                                    .str())
                           .raw("checkpoint_writes",
                                persister ? fsm::JsonObject()
                                                .field("written", persister->writes())
                                                .field("coalesced", persister->coalesced())
                                                .field("held", static_cast<std::uint64_t>(driver->held()))
                                                .str()
                                          : std::string("null"))
                           .str();
    options.status_sink(line);
}

}  // namespace keel::node
