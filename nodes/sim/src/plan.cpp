#include "nodes/sim/src/plan.hpp"

#include <algorithm>

namespace keel::sim {

std::optional<DiskFaults> parse_disk_faults(std::string_view name) {
    for (const DiskFaults faults : {DiskFaults::drawn, DiskFaults::all, DiskFaults::storage_power_loss,
                                    DiskFaults::master_power_loss, DiskFaults::storage_full}) {
        if (to_string(faults) == name) return faults;
    }
    return std::nullopt;
}

std::string_view to_string(DiskFaults faults) {
    switch (faults) {
        case DiskFaults::drawn: return "drawn";
        case DiskFaults::all: return "all";
        case DiskFaults::storage_power_loss: return "storage-power-loss";
        case DiskFaults::master_power_loss: return "master-power-loss";
        case DiskFaults::storage_full: return "storage-full";
    }
    return "drawn";
}

const char* to_string(Outcome outcome) {
    switch (outcome) {
        case Outcome::agreed: return "agreed";
        case Outcome::headless: return "headless";
        case Outcome::lease_stalled: return "lease-stalled";
        case Outcome::violated: return "violated";
    }
    return "violated";
}

namespace {

NodeSet random_subset(Rng& rng, NodeSet from) {
    NodeSet subset;
    from.for_each([&](NodeId n) {
        if (rng.chance(0.5)) subset.insert(n);
    });
    return subset;
}

NodeId pick(Rng& rng, NodeSet from) {
    const auto index = rng.below(static_cast<std::uint64_t>(from.size()));
    NodeId chosen = fsm::kNoNode;
    std::uint64_t i = 0;
    from.for_each([&](NodeId n) {
        if (i++ == index) chosen = n;
    });
    return chosen;
}

}  // namespace

RunPlan random_plan(const fsm::Topology& topology, std::uint64_t seed, const PlanOptions& options) {
    // The plan has its own stream, apart from the network's, so that changing the network
    // model does not change which faults a seed injects.
    Rng rng(seed ^ 0xA5A5'5A5A'C3C3'3C3Cull);
    const TimeNs period = topology.heartbeat_period_ns();
    RunPlan plan;
    plan.fault_window_ns = options.fault_window_ns;
    plan.settle_limit_ns = std::max<TimeNs>(10'000 * kMs, 80 * period);

    static constexpr double losses[] = {0, 0, 0, 0.01, 0.02, 0.05};
    static constexpr double duplicates[] = {0, 0, 0.01, 0.05};
    plan.network.loss = options.loss.value_or(losses[rng.below(std::size(losses))]);
    plan.network.duplicate = duplicates[rng.below(std::size(duplicates))];
    plan.network.delay_min_ns = kMs / 5;
    const TimeNs spreads[] = {kMs, 5 * kMs, std::min<TimeNs>(20 * kMs, period / 3)};
    plan.network.delay_max_ns = spreads[rng.below(std::size(spreads))];

    const NodeSet all = topology.all_nodes();
    const bool targeted_disk = options.disk_faults != DiskFaults::drawn;
    const int budget = options.max_failures.value_or(
        options.liar || targeted_disk ? 0 : topology.node_failures_tolerated() + 1);
    const double draw = rng.uniform();
    const int disruptive = draw < 0.15 ? 0 : (draw < 0.6 ? std::min(1, budget) : budget);
    const TimeNs early = std::min<TimeNs>(500 * kMs, plan.fault_window_ns / 4);
    const TimeNs late = plan.fault_window_ns - early;
    NodeSet crashed;
    for (int k = 0; k < disruptive; ++k) {
        const TimeNs t = rng.between(early, late);
        const double kind = rng.uniform();
        if (kind < 0.7) {
            const NodeSet candidates = (kind < 0.5 ? topology.processing_nodes() : all).minus(crashed);
            if (candidates.empty()) continue;
            const NodeId node = pick(rng, candidates);
            crashed.insert(node);
            ++plan.disruptive;
            plan.faults.push_back({t, PlannedFault::Kind::crash, node, {}, {}, 0, 0});
            if (rng.chance(0.3)) {
                plan.faults.push_back({std::min(plan.fault_window_ns, t + rng.between(50 * kMs, 2000 * kMs)),
                                       PlannedFault::Kind::restart, node, {}, {}, 0, 0});
            }
        } else {
            NodeSet a = rng.chance(0.5) ? NodeSet{} : random_subset(rng, all);
            if (a.empty() || a == all) {
                a = NodeSet{};
                a.insert(pick(rng, all));
            }
            const NodeSet b = all.minus(a);
            const bool one_way = rng.chance(0.4);
            ++plan.disruptive;
            plan.faults.push_back({t, one_way ? PlannedFault::Kind::block : PlannedFault::Kind::partition,
                                   fsm::kNoNode, a, b, 0, 0});
            plan.faults.push_back({std::min(plan.fault_window_ns, t + rng.between(100 * kMs, 2500 * kMs)),
                                   PlannedFault::Kind::heal,
                                   fsm::kNoNode, {}, {}, 0, 0});
        }
    }
    const int phases = topology.phase_count() > 1 ? static_cast<int>(rng.below(3)) : 0;
    for (int k = 0; k < phases; ++k) {
        plan.faults.push_back({rng.between(early, late), PlannedFault::Kind::phase, fsm::kNoNode, {}, {},
                               static_cast<fsm::PhaseId>(rng.below(static_cast<std::uint64_t>(topology.phase_count()))), 0});
    }
    // Drawn after everything above so that a seed keeps the faults it had before these
    // were added.
    const TimeNs grace = topology.startup_grace_periods() * period;
    // Boot skew the grace absorbs: every late node is heard, miss_limit + 1 periods spare.
    const TimeNs absorbed = grace - (topology.miss_limit() + 1) * period;
    if (rng.chance(0.3) && absorbed > 0) {
        plan.boot_ns.assign(static_cast<std::size_t>(topology.node_count()), 0);
        all.for_each([&](NodeId n) {
            if (rng.chance(0.5)) plan.boot_ns[n] = rng.between(0, absorbed);
        });
    }
    // A node that starts after the grace: declared failed before it boots, then fenced.
    if (plan.disruptive < budget && rng.chance(0.12)) {
        const NodeSet candidates = all.minus(crashed);
        if (!candidates.empty()) {
            const NodeId node = pick(rng, candidates);
            plan.boot_ns.resize(static_cast<std::size_t>(topology.node_count()), 0);
            plan.boot_ns[node] = grace + rng.between(2 * period, std::max(3 * period, plan.fault_window_ns / 2));
            crashed.insert(node);
            ++plan.disruptive;
        }
    }
    // A node that asks to be excluded (a task keeps failing there).
    if (plan.disruptive < budget && rng.chance(0.12)) {
        const NodeSet candidates = topology.processing_nodes().minus(crashed);
        if (!candidates.empty()) {
            plan.faults.push_back({rng.between(early, late), PlannedFault::Kind::resign, pick(rng, candidates), {}, {}, 0, 0});
            ++plan.disruptive;
        }
    }
    // Fault model 2, drawn last for the same reason. A deaf node (receive omission: it
    // still sends) until the network heals; a paused process (SIGSTOP) that resumes.
    if (plan.disruptive < budget && rng.chance(0.15)) {
        const TimeNs t = rng.between(early, late);
        plan.faults.push_back({t, PlannedFault::Kind::deaf, pick(rng, all), {}, {}, 0, 0});
        plan.faults.push_back({std::min(plan.fault_window_ns, t + rng.between(100 * kMs, 2500 * kMs)),
                               PlannedFault::Kind::heal, fsm::kNoNode, {}, {}, 0, 0});
        ++plan.disruptive;
    }
    if (plan.disruptive < budget && rng.chance(0.15)) {
        const NodeSet candidates = all.minus(crashed);
        if (!candidates.empty()) {
            plan.faults.push_back({rng.between(early, late), PlannedFault::Kind::pause, pick(rng, candidates), {},
                                   {}, 0, rng.between(period / 2, 2000 * kMs)});
            ++plan.disruptive;
        }
    }
    // A processing node deaf to some of the others only (a starved receive path): it
    // declares nodes the rest of the cluster hears.
    if (plan.disruptive < budget && rng.chance(0.15)) {
        const NodeId node = pick(rng, topology.processing_nodes());
        NodeSet from = random_subset(rng, all);
        from.erase(node);
        if (from.empty()) {
            NodeSet others = all;
            others.erase(node);
            from.insert(pick(rng, others));
        }
        const TimeNs t = rng.between(early, late);
        plan.faults.push_back({t, PlannedFault::Kind::deaf_to, node, from, {}, 0, 0});
        plan.faults.push_back({std::min(plan.fault_window_ns, t + rng.between(300 * kMs, 2500 * kMs)),
                               PlannedFault::Kind::heal, fsm::kNoNode, {}, {}, 0, 0});
        ++plan.disruptive;
    }
    // Some restarts find a saved state that went back (a lost write, a restored file). A
    // stream of its own, so that every seed keeps the faults it had before.
    Rng rollback(seed ^ 0x5EED'B007'0000'0001ull);
    for (PlannedFault& fault : plan.faults) {
        if (fault.kind == PlannedFault::Kind::restart) fault.rolled_back = rollback.chance(0.4);
    }
    // A whole-cluster power cycle (a bus-wide reset): every node goes down at once and
    // boots again from its saved state, each after its own delay; the cluster must elect
    // a Master by itself (WarmBoot). Only in a plan with no other disruptive fault, after
    // every node has booted. A stream of its own, so that every seed keeps the faults it
    // had before.
    Rng cycle(seed ^ 0x5EED'C7C1'0000'0002ull);
    if (plan.disruptive == 0 && !options.liar && !targeted_disk && cycle.chance(0.3)) {
        TimeNs booted = 0;
        for (const TimeNs at : plan.boot_ns) booted = std::max(booted, at);
        const TimeNs from = std::max(early, booted + 3 * period);
        if (from < late) {
            const TimeNs t = cycle.between(from, late);
            all.for_each([&](NodeId n) {
                plan.faults.push_back({t, PlannedFault::Kind::crash, n, {}, {}, 0, 0, false, true});
                plan.faults.push_back({std::min(plan.fault_window_ns, t + cycle.between(50 * kMs, 1500 * kMs)),
                                       PlannedFault::Kind::restart, n, {}, {}, 0, 0});
            });
            ++plan.disruptive;
        }
    }
    // Fault model 3: a node of any role lies from some time in the fault window, for up to
    // the rest of it, and is then restarted: a reboot clears the upset, and a node caught
    // lying is readmitted only after a restart. Its stream is its own.
    Rng liar(seed ^ 0x5EED'11A2'0000'0003ull);
    if (options.liar) {
        const NodeId node = static_cast<NodeId>(liar.below(static_cast<std::uint64_t>(topology.node_count())));
        const TimeNs t = liar.between(early, late / 2);
        const TimeNs until = liar.between(t + period, late);
        plan.faults.push_back({t, PlannedFault::Kind::lie, node, {}, {}, 0, until - t});
        plan.faults.push_back({until, PlannedFault::Kind::crash, node, {}, {}, 0, 0});
        plan.faults.push_back({std::min(plan.fault_window_ns, until + liar.between(period, 3 * period)),
                               PlannedFault::Kind::restart, node, {}, {}, 0, 0});
        ++plan.disruptive;
    }
    // The disk: its write latency, and a disk fault within the failure budget (a power loss
    // at the node's next write, or a disk whose writes fail from now on), the node
    // restarted afterwards. A stream of its own, so that every seed keeps the faults it had
    // before.
    Rng disk(seed ^ 0x5EED'D15C'0000'0004ull);
    // From a small state on flash to a large one on a worn card (16 MiB took SQLite 95 ms
    // here, docs/benchmarks.md).
    static constexpr TimeNs disk_spreads[][2] = {
        {kMs / 5, kMs}, {kMs / 2, 5 * kMs}, {kMs, 20 * kMs}, {10 * kMs, 100 * kMs}};
    const auto& spread = disk_spreads[disk.below(std::size(disk_spreads))];
    plan.disk.write_min_ns = spread[0];
    plan.disk.write_max_ns = spread[1];
    const NodeId storage = topology.storage_node();
    auto disk_fault = [&](TimeNs t, PlannedFault::Kind kind, NodeId node) {
        plan.faults.push_back({t, kind, node, {}, {}, 0, 0});
        // A failing disk the node has not written to yet leaves it up: stopped here.
        const TimeNs down = t + disk.between(300 * kMs, 600 * kMs);
        plan.faults.push_back({down, PlannedFault::Kind::crash, node, {}, {}, 0, 0});
        plan.faults.push_back({down + disk.between(50 * kMs, 500 * kMs), PlannedFault::Kind::restart, node, {}, {}, 0, 0});
    };
    if (targeted_disk) {
        // Three switches, a disk fault at each (PlanOptions::disk_faults).
        const fsm::PhaseId first = topology.phase_of(topology.initial_view());
        // After every node booted and the boot switch is done; each fault has its slot,
        // time to take the node down and up again and for the cluster to settle.
        TimeNs booted = 0;
        for (const TimeNs at : plan.boot_ns) booted = std::max(booted, at);
        const TimeNs start = std::max(early, booted + 5 * period);
        const TimeNs slot = 1600 * kMs;
        plan.fault_window_ns = std::max(plan.fault_window_ns, start + 3 * slot);
        // The power loss on a processing node strikes the initial Master: its step both
        // commands and acknowledges a new view (the other nodes' first message of a switch
        // may be a final checkpoint, which names no view).
        const NodeId processing = topology.initial_view().master;
        // A slow disk (large checkpoints): a periodic write is often still under way when a
        // switch's final checkpoint arrives, so what the Storage node says of the task waits.
        plan.disk.write_min_ns = period / 2;
        plan.disk.write_max_ns = 2 * period;
        struct Fault {
            PlannedFault::Kind kind;
            NodeId node;
        };
        const Fault storage_power_loss{PlannedFault::Kind::checkpoint_power_loss, storage};
        const Fault master_power_loss{PlannedFault::Kind::power_loss, processing};
        const Fault storage_full{PlannedFault::Kind::disk_full, storage};
        Fault faults[3] = {storage_power_loss, master_power_loss, storage_full};
        if (options.disk_faults != DiskFaults::all) {
            const Fault only = options.disk_faults == DiskFaults::storage_power_loss  ? storage_power_loss
                               : options.disk_faults == DiskFaults::master_power_loss ? master_power_loss
                                                                                       : storage_full;
            std::fill(std::begin(faults), std::end(faults), only);
        }
        for (int k = 0; k < 3; ++k) {
            if (faults[k].node == fsm::kNoNode) continue;  // a mission without a Storage node
            const TimeNs t = start + k * slot + disk.between(0, 300 * kMs);
            const auto phase = static_cast<fsm::PhaseId>((first + 1 + k) % std::max(1, topology.phase_count()));
            // Armed first: the phase change's own step may be the write it strikes.
            const NodeId node = faults[k].node == fsm::kNoNode ? processing : faults[k].node;
            disk_fault(t, faults[k].kind, node);
            plan.faults.push_back({t, PlannedFault::Kind::phase, fsm::kNoNode, {}, {}, phase, 0});
            ++plan.disruptive;
        }
    } else if (!options.liar && plan.disruptive < budget && disk.chance(0.15)) {
        // Drawn like any other disruptive fault.
        const NodeSet candidates = all.minus(crashed);
        const NodeId node = storage != fsm::kNoNode && disk.chance(0.5) ? storage
                            : candidates.empty()                        ? fsm::kNoNode
                                                                        : pick(disk, candidates);
        if (node != fsm::kNoNode) {
            static constexpr PlannedFault::Kind kinds[] = {
                PlannedFault::Kind::power_loss, PlannedFault::Kind::disk_fail,
                PlannedFault::Kind::checkpoint_power_loss, PlannedFault::Kind::disk_full};
            disk_fault(disk.between(early, late - 1200 * kMs), kinds[disk.below(std::size(kinds))], node);
            ++plan.disruptive;
        }
    }
    // The ground's pause of a task, and its resume in most runs (PlanOptions::ground_pauses).
    // A stream of its own, so that every seed keeps the faults it had before.
    Rng ground(seed ^ 0x5EED'6A05'0000'0005ull);
    if (options.ground_pauses) {
        std::vector<fsm::TaskId> pausable;
        for (fsm::TaskId task = 0; task < topology.task_count(); ++task) {
            if (!topology.task(task).essential) pausable.push_back(task);
        }
        if (!pausable.empty()) {
            const fsm::TaskId task = pausable[ground.below(pausable.size())];
            const TimeNs t = ground.between(early, late);
            plan.faults.push_back({t, PlannedFault::Kind::ground_pause, fsm::kNoNode, {}, {}, 0, 0, false, false, task});
            if (ground.chance(0.7)) {
                plan.faults.push_back({std::min(plan.fault_window_ns, t + ground.between(period, 2500 * kMs)),
                                       PlannedFault::Kind::ground_resume, fsm::kNoNode, {}, {}, 0, 0, false, false,
                                       task});
            }
        }
    }
    // The ground's designations (PlanOptions::ground_designates). A stream of its own.
    Rng votes(seed ^ 0x5EED'D051'0000'0005ull);
    plan.ground_designates = options.ground_designates;
    if (options.ground_designates) {
        const NodeSet candidates = topology.processing_nodes();
        const int count = 1 + static_cast<int>(votes.below(3));
        // Where the plan cuts the cluster in two, the designations follow the cut in most
        // runs, alternating its sides (a tie is where the vote counts, and a second
        // designee on the other side is where its wait matters); else at any instant.
        const PlannedFault* cut = nullptr;
        for (const PlannedFault& fault : plan.faults) {
            if (fault.kind == PlannedFault::Kind::partition && !(fault.side_a & candidates).empty() &&
                !(fault.side_b & candidates).empty()) {
                cut = &fault;
                break;
            }
        }
        // No cut drawn: in most runs the ground's campaign cuts the processing nodes in two
        // halves itself, for the rest of the window (a tie where their view has an even
        // number of monitors; the other nodes on either side), a disruptive fault within
        // the run's budget like any other.
        if (cut == nullptr && candidates.size() >= 2 && plan.disruptive < budget && votes.chance(0.7)) {
            PlannedFault split{votes.between(early, late / 2), PlannedFault::Kind::partition, fsm::kNoNode, {}, {}, 0, 0};
            std::vector<NodeId> order;
            candidates.for_each([&](NodeId n) { order.push_back(n); });
            for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[votes.below(i)]);
            for (std::size_t i = 0; i < order.size(); ++i) (i < order.size() / 2 ? split.side_a : split.side_b).insert(order[i]);
            topology.all_nodes().minus(candidates).for_each([&](NodeId n) {
                (votes.chance(0.5) ? split.side_a : split.side_b).insert(n);
            });
            plan.faults.push_back(split);
            ++plan.disruptive;
            cut = &plan.faults.back();
        }
        const bool follow = cut != nullptr && votes.chance(0.8);
        const TimeNs cut_at = follow ? cut->t_ns : 0;
        const NodeSet sides[2] = {follow ? cut->side_a & candidates : candidates,
                                  follow ? cut->side_b & candidates : candidates};
        TimeNs at = cut_at + votes.between(400 * kMs, 1200 * kMs);
        std::vector<PlannedFault> designations;
        for (int i = 0; i < count && !candidates.empty(); ++i) {
            const TimeNs t = follow ? at : votes.between(early, late);
            // The uplink reaches each node on its own (spec/Designate.tla's Receivers): the
            // designee, and each other node in most runs.
            const NodeId designee = pick(votes, sides[i % 2]);
            NodeSet reached;
            topology.all_nodes().for_each([&](NodeId n) {
                if (n == designee || votes.chance(0.6)) reached.insert(n);
            });
            designations.push_back({t, PlannedFault::Kind::ground_designate, designee, reached, {}, 0, 0});
            at += votes.between(100 * kMs, 1500 * kMs);
        }
        plan.faults.insert(plan.faults.end(), designations.begin(), designations.end());
    }
    // Every node's clock starts at its own zero (a board's monotonic clock, hours apart)
    // and runs fast or slow. A stream of its own.
    Rng clocks(seed ^ 0x5EED'C10C'0000'0005ull);
    for (NodeId n = 0; n < topology.node_count(); ++n) {
        plan.clocks.push_back({static_cast<TimeNs>(clocks.below(10'000'000'000'000ull)),
                               static_cast<std::int64_t>(clocks.below(401)) - 200});
    }
    std::stable_sort(plan.faults.begin(), plan.faults.end(),
                     [](const PlannedFault& x, const PlannedFault& y) { return x.t_ns < y.t_ns; });
    return plan;
}

std::string describe(const fsm::Topology& topology, const PlannedFault& fault) {
    auto names = [&](NodeSet set) {
        std::string out;
        set.for_each([&](NodeId n) {
            if (!out.empty()) out += " ";
            out += topology.node_name(n);
        });
        return out;
    };
    const std::string at = std::to_string(fault.t_ns / kMs) + "ms ";
    switch (fault.kind) {
        case PlannedFault::Kind::crash:
            return at + "crash " + topology.node_name(fault.node) + (fault.power_cycle ? " (power cycle)" : "");
        case PlannedFault::Kind::restart:
            return at + "restart " + topology.node_name(fault.node) + (fault.rolled_back ? " rolled-back" : "");
        case PlannedFault::Kind::partition: return at + "partition " + names(fault.side_a) + " | " + names(fault.side_b);
        case PlannedFault::Kind::block: return at + "partition " + names(fault.side_a) + " -> " + names(fault.side_b);
        case PlannedFault::Kind::heal: return at + "heal";
        case PlannedFault::Kind::phase: return at + "phase " + topology.phase(fault.phase).name;
        case PlannedFault::Kind::resign: return at + "resign " + topology.node_name(fault.node);
        case PlannedFault::Kind::deaf: return at + "deaf " + topology.node_name(fault.node);
        case PlannedFault::Kind::deaf_to: return at + "deaf " + topology.node_name(fault.node) + " to " + names(fault.side_a);
        case PlannedFault::Kind::pause:
            return at + "pause " + topology.node_name(fault.node) + " " + std::to_string(fault.duration_ns / kMs) + "ms";
        case PlannedFault::Kind::lie:
            return at + "lie " + topology.node_name(fault.node) + " " + std::to_string(fault.duration_ns / kMs) + "ms";
        case PlannedFault::Kind::disk_fail: return at + "disk-fail " + topology.node_name(fault.node);
        case PlannedFault::Kind::ground_pause: return at + "pause-task " + topology.task(fault.task).name;
        case PlannedFault::Kind::ground_resume: return at + "resume-task " + topology.task(fault.task).name;
        case PlannedFault::Kind::ground_designate:
            return at + "designate " + topology.node_name(fault.node) + " reaching " + names(fault.side_a);
        case PlannedFault::Kind::power_loss: return at + "power-loss " + topology.node_name(fault.node);
        case PlannedFault::Kind::checkpoint_power_loss:
            return at + "power-loss " + topology.node_name(fault.node) + " at its next checkpoint write";
        case PlannedFault::Kind::disk_full: return at + "disk-full " + topology.node_name(fault.node);
    }
    return at;
}

RunResult execute(Simulation& sim, const RunPlan& plan) {
    sim.set_network(plan.network);
    sim.set_disk(plan.disk);
    RunResult result;
    for (const auto& fault : plan.faults) {
        sim.run_until(fault.t_ns);
        if (!sim.violations().empty()) break;
        switch (fault.kind) {
            case PlannedFault::Kind::crash: sim.crash(fault.node); break;
            case PlannedFault::Kind::restart: sim.restart(fault.node, fault.rolled_back); break;
            case PlannedFault::Kind::partition: sim.partition(fault.side_a, fault.side_b); break;
            case PlannedFault::Kind::block:
                fault.side_a.for_each([&](NodeId a) {
                    fault.side_b.for_each([&](NodeId b) { sim.block(a, b); });
                });
                break;
            case PlannedFault::Kind::heal: sim.heal(); break;
            case PlannedFault::Kind::phase: sim.request_phase(fault.phase); break;
            case PlannedFault::Kind::resign: sim.resign(fault.node); break;
            case PlannedFault::Kind::deaf: sim.deaf(fault.node); break;
            case PlannedFault::Kind::deaf_to: sim.deaf_to(fault.node, fault.side_a); break;
            case PlannedFault::Kind::pause: sim.pause(fault.node, fault.duration_ns); break;
            case PlannedFault::Kind::lie: sim.lie(fault.node, fault.duration_ns); break;
            case PlannedFault::Kind::disk_fail: sim.fail_disk(fault.node); break;
            case PlannedFault::Kind::ground_pause: sim.ground_pause(fault.task, true); break;
            case PlannedFault::Kind::ground_resume: sim.ground_pause(fault.task, false); break;
            case PlannedFault::Kind::ground_designate: sim.ground_designate(fault.node, fault.side_a); break;
            case PlannedFault::Kind::power_loss: sim.power_loss_at_write(fault.node); break;
            case PlannedFault::Kind::checkpoint_power_loss: sim.power_loss_at_write(fault.node, true); break;
            case PlannedFault::Kind::disk_full: sim.fill_disk(fault.node); break;
        }
    }
    if (sim.violations().empty()) sim.run_until(plan.fault_window_ns);
    if (sim.violations().empty()) result.agreement_ns = sim.stabilize(plan.settle_limit_ns);
    // Within the mission's tolerance a cluster must never lose its head, but for the lease.
    // A Master whose lease lapsed stepped down as a resignation does (spec/Lease.tla), and a
    // planned resignation is a disruptive fault: so is that step-down, though the network's
    // losses caused it, not the plan (prototype3 seed 3025: at boot, three messages lost in
    // a row while its other voter had not booted).
    int lease_lost = 0;
    for (NodeId n = 0; n < sim.topology().node_count(); ++n) {
        if (sim.booted(n) && sim.node(n).stats().lease_step_downs > 0) ++lease_lost;
    }
    // A value-faulty Master that fenced correct nodes may leave the cluster headless (not
    // covered: docs/fault-model.md); counted as headless.
    if (sim.violations().empty() && !sim.acting_master() && !sim.lease_stalled() &&
        !sim.headless_by_fencing() &&
        plan.disruptive + lease_lost <= sim.topology().node_failures_tolerated()) {
        sim.report("SwitchConverges", "no Master after " + std::to_string(plan.disruptive) +
                                          " disruptive fault(s), within the tolerance of " +
                                          std::to_string(sim.topology().node_failures_tolerated()));
    }
    // The ground's vote must never put two Masters, or a task on two nodes, to work at
    // once (spec/Designate.tla): the lease alone bounds it at no time at all otherwise.
    if (plan.ground_designates && sim.violations().empty()) {
        if (sim.two_masters_ns() > 0) {
            sim.report("AtMostOneRunningMasterInv", "two running Masters for " +
                                                        std::to_string(sim.two_masters_ns() / 1000) + " us");
        } else if (sim.double_run_ns() > 0) {
            sim.report("NoExcludedRunsInv", "a task on two running nodes for " +
                                                std::to_string(sim.double_run_ns() / 1000) + " us");
        }
    }
    result.violations = sim.violations();
    result.steps = sim.steps();
    result.messages = sim.messages_sent();
    result.end_ns = sim.now();
    result.two_masters_ns = sim.two_masters_ns();
    result.double_run_ns = sim.double_run_ns();
    if (!result.violations.empty()) {
        result.outcome = Outcome::violated;
    } else {
        result.outcome = sim.acting_master() ? Outcome::agreed
                         : sim.lease_stalled() ? Outcome::lease_stalled
                                               : Outcome::headless;
    }
    return result;
}

RunResult run_seed(const fsm::Topology& topology, std::uint64_t seed, const RunOptions& options) {
    SimOptions sim_options;
    sim_options.seed = seed;
    sim_options.mutant = options.mutant;
    sim_options.tracing = options.tracing;
    const RunPlan plan = random_plan(topology, seed, options.plan);
    sim_options.boot_ns = plan.boot_ns;
    sim_options.clocks = plan.clocks;
    Simulation sim(topology, sim_options);
    return execute(sim, plan);
}

}  // namespace keel::sim
