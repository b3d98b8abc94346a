// Random fault plans: what one seed does to a cluster, and the run that executes it.
//
// A plan draws, from its seed alone, a network model (loss, duplication, delay spread),
// up to tolerance.node_failures + 1 disruptive faults — crashes (processing, storage or
// interface nodes, sometimes followed by a restart), symmetric or one-way partitions that
// heal, a node that resigns (NodeProtocol::resign), a node whose process starts after the
// start-up grace (so the cluster goes on without it and fences it when it boots), a node
// that cannot receive for a while (deaf, or deaf to some nodes only, then healed), a paused
// process (SIGSTOP) — up to
// two planned phase changes, all inside a fault window, and boot skew: some nodes' processes
// start late but within the start-up grace, as real processes do. With PlanOptions::liar,
// one node is value-faulty for a while instead (fault model 3). Disk faults (a power loss
// at a node's next write, a disk whose writes fail from an instant; both end the node's
// process, which restarts later) and the disk's write latency come from streams of their
// own; PlanOptions::disk_faults puts three of them in every run, each at a phase switch,
// where the driver's rules matter (core/node/driver.hpp). Then the network
// heals and the run must reach agreement (SwitchConverges) within the settle limit. Every
// checker runs after every step. The same seed and options replay the same run exactly.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nodes/sim/src/simulation.hpp"

namespace keel::sim {

struct PlannedFault {
    enum class Kind {
        crash, restart, partition, block, heal, phase, resign, deaf, pause, deaf_to, lie,
        disk_fail,              // Simulation::fail_disk
        power_loss,             // Simulation::power_loss_at_write
        checkpoint_power_loss,  // Simulation::power_loss_at_write(node, true)
        disk_full,              // Simulation::fill_disk
        ground_pause,           // Simulation::ground_pause(task, true): the ground's pause-task
        ground_resume,          // Simulation::ground_pause(task, false): its resume-task
        ground_designate,       // Simulation::ground_designate(node): the ground's designate
    };
    TimeNs t_ns = 0;
    Kind kind = Kind::crash;
    NodeId node = fsm::kNoNode;
    NodeSet side_a;
    NodeSet side_b;
    fsm::PhaseId phase = 0;
    TimeNs duration_ns = 0;  // pause, lie
    bool rolled_back = false;  // restart: from a saved state that went back
    bool power_cycle = false;  // crash: one of a whole-cluster power cycle's (one fault)
    fsm::TaskId task = 0;      // ground_pause, ground_resume
};

// PlanOptions::disk_faults: none drawn on purpose (a disk fault may still be drawn, within
// the failure budget), or one at each of three phase changes, of every class or of one.
enum class DiskFaults { drawn, all, storage_power_loss, master_power_loss, storage_full };
std::optional<DiskFaults> parse_disk_faults(std::string_view name);
std::string_view to_string(DiskFaults faults);

struct PlanOptions {
    TimeNs fault_window_ns = 5000 * kMs;
    std::optional<double> loss;       // overrides the drawn loss rate
    std::optional<int> max_failures;  // overrides tolerance.node_failures + 1
    // Fault model 3: one node of any role lies for a while (Simulation::lie), then is
    // restarted (a reboot clears the upset). Fault model 2's disruptive faults are then
    // drawn only with max_failures (default 0): the rules assume the other nodes correct.
    bool liar = false;
    // Unless `drawn`: every run has three disk faults and no other disruptive fault (but
    // max_failures), each at the instant of a planned phase change (when the Storage node
    // stores final checkpoints and every node saves a new view), on a slow disk: a power
    // loss at the Storage node's next checkpoint write (storage_power_loss), at the initial
    // Master's next write (master_power_loss), the Storage node's disk filling up so that
    // its checkpoint writes fail (storage_full), or one of each (all); each node restarts
    // afterwards. The campaigns for the driver's mutants (release-held-early,
    // save-after-send, ignore-failed-write, in that order).
    DiskFaults disk_faults = DiskFaults::drawn;
    // The ground pauses a task the mission may pause (one not essential) at a random
    // instant of the fault window, and in most runs resumes it later (docs/operations.md,
    // `pause-task`): every other fault goes on around it. Not a disruptive fault (the
    // cluster's tolerance is untouched). A stream of its own.
    bool ground_pauses = false;
    // The ground designates a processing node (spec/Designate.tla; docs/operations.md,
    // `designate`) one to three times at random instants of the fault window, each waiting
    // out the spans the ground gave another node (Simulation::ground_designate): every
    // other fault goes on around them. For a mission with heartbeat.tie_grace (the others
    // refuse it). A stream of its own.
    bool ground_designates = false;
};

struct RunPlan {
    NetworkModel network;
    DiskModel disk;
    TimeNs fault_window_ns = 0;
    TimeNs settle_limit_ns = 0;
    std::vector<PlannedFault> faults;  // in time order
    int disruptive = 0;  // crashes, partitions, resigns, boots after the grace (the failure budget they use)
    // When each node's process starts (SimOptions::boot_ns); empty: all at time zero.
    std::vector<TimeNs> boot_ns;
    // The ground designates (PlanOptions::ground_designates): spec/Designate.tla's
    // AtMostOneRunningMasterInv and NoExcludedRunsInv are checked on the run's ground truth
    // (two running Masters, a task on two running nodes: none at all).
    bool ground_designates = false;
    // Each node's clock (SimOptions::clocks): its own zero, and a drift of up to
    // ±200 ppm (a crystal's, aged and hot).
    std::vector<SimOptions::Clock> clocks;
};

RunPlan random_plan(const fsm::Topology& topology, std::uint64_t seed, const PlanOptions& options);
std::string describe(const fsm::Topology& topology, const PlannedFault& fault);

struct RunOptions {
    PlanOptions plan;
    fsm::Mutant mutant = fsm::Mutant::none;
    bool tracing = false;
};

// headless: no Master at the end, beyond the tolerance; lease_stalled: no Master because
// no Observer holds the lease a take-over needs (spec/Lease.tla: a monitor it cannot hear
// may be alive and take over too), within the tolerance or not: counted, not a violation.
enum class Outcome { agreed, headless, lease_stalled, violated };
const char* to_string(Outcome outcome);

struct RunResult {
    Outcome outcome = Outcome::agreed;
    std::vector<Violation> violations;
    std::optional<TimeNs> agreement_ns;  // from the end of the fault window
    std::uint64_t steps = 0;
    std::uint64_t messages = 0;
    TimeNs end_ns = 0;
    TimeNs two_masters_ns = 0;  // Simulation::two_masters_ns
    TimeNs double_run_ns = 0;   // Simulation::double_run_ns
};

// Executes `plan` on `sim` (which must be fresh, built with the plan's boot_ns) and
// stabilizes.
RunResult execute(Simulation& sim, const RunPlan& plan);
// random_plan + a fresh Simulation + execute.
RunResult run_seed(const fsm::Topology& topology, std::uint64_t seed, const RunOptions& options);

}  // namespace keel::sim
