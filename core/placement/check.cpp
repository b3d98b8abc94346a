#include "core/placement/check.hpp"

#include <algorithm>
#include <array>
#include <cstdint>

namespace keel::placement {

namespace {

bool in_range(const Model& model, int node) { return node >= 0 && node < model.node_count(); }

bool failed_node(const FailedSet& failed, int node) {
    return static_cast<std::size_t>(node) < failed.size() && failed[static_cast<std::size_t>(node)];
}

// a + b, saturating: loads come from the mission, but a sum must not overflow.
std::int64_t add(std::int64_t a, std::int64_t b) {
    return a > kUnbounded - b ? kUnbounded : a + b;
}

}  // namespace

std::vector<Finding> check(const Model& model, int phase_id, const FailedSet& failed,
                           const Configuration& config, Shedding shedding) {
    std::vector<Finding> found;
    auto report = [&](const char* kind, int task, int node, std::string message) {
        found.push_back(Finding{kind, task, node, std::move(message)});
    };
    if (phase_id < 0 || phase_id >= model.phase_count()) {
        report("malformed", kNone, kNone, "phase " + std::to_string(phase_id) + " does not exist");
        return found;
    }
    if (config.host.size() != static_cast<std::size_t>(model.task_count())) {
        report("malformed", kNone, kNone,
               "the placement names " + std::to_string(config.host.size()) +
                   " tasks, the mission has " + std::to_string(model.task_count()));
        return found;
    }
    const PhaseInfo& phase = model.phase(phase_id);
    auto node_name = [&](int node) { return model.node(node).name; };

    // Tasks: each of the phase placed on an alive node that can run it; no other task.
    // Each node's summed load (on the stack: every node runs this per Command, and the
    // proof per placement).
    std::array<std::int64_t, Model::kMaxNodes> cpu;
    std::array<std::int64_t, Model::kMaxNodes> mem;
    std::fill_n(cpu.begin(), model.node_count(), 0);
    std::fill_n(mem.begin(), model.node_count(), 0);
    bool checkpointed = false;
    std::string checkpointed_task;
    for (int t = 0; t < model.task_count(); ++t) {
        const TaskInfo& task = model.task(t);
        const int host = config.host[static_cast<std::size_t>(t)];
        const bool of_phase = phase.in_phase[static_cast<std::size_t>(t)] != 0;
        if (host == kNone) {
            if (of_phase && (shedding == Shedding::forbidden || task.essential)) {
                report("task-missing", t, kNone,
                       "task " + task.name + " of phase " + phase.name + " is not placed" +
                           (task.essential && shedding == Shedding::allowed
                                ? " (essential: never shed)"
                                : ""));
            }
            continue;
        }
        if (!in_range(model, host)) {
            report("malformed", t, kNone,
                   "task " + task.name + " is placed on node " + std::to_string(host) +
                       ", the mission has " + std::to_string(model.node_count()));
            continue;
        }
        if (!of_phase) {
            report("task-missing", t, host,
                   "task " + task.name + " is placed on " + node_name(host) +
                       " but is not a task of phase " + phase.name);
        }
        if (failed_node(failed, host)) {
            report("task-on-failed-node", t, host,
                   "task " + task.name + " is placed on failed node " + node_name(host));
        }
        if (!model.capable(t, host)) {
            report("capability", t, host,
                   "task " + task.name + " is placed on " + node_name(host) +
                       ", which lacks a capability it requires");
        }
        cpu[static_cast<std::size_t>(host)] = add(cpu[static_cast<std::size_t>(host)], task.cpu);
        mem[static_cast<std::size_t>(host)] = add(mem[static_cast<std::size_t>(host)], task.mem_mb);
        if (task.checkpoint && !checkpointed) {
            checkpointed = true;
            checkpointed_task = task.name;
        }
    }
    for (int n = 0; n < model.node_count(); ++n) {
        const NodeInfo& node = model.node(n);
        const auto i = static_cast<std::size_t>(n);
        if (cpu[i] > node.cpu) {
            report("capacity", kNone, n,
                   node.name + " is loaded with cpu " + std::to_string(cpu[i]) + " > capacity " +
                       std::to_string(node.cpu));
        }
        if (mem[i] > node.mem_mb) {
            report("capacity", kNone, n,
                   node.name + " is loaded with mem_mb " + std::to_string(mem[i]) +
                       " > capacity " + std::to_string(node.mem_mb));
        }
    }

    // The master and the observers: alive processing nodes, distinct.
    int alive_processing = 0;
    bool storage_alive = false;
    for (int n = 0; n < model.node_count(); ++n) {
        if (failed_node(failed, n)) continue;
        if (model.node(n).processing) ++alive_processing;
        if (model.node(n).storage) storage_alive = true;
    }
    if (!in_range(model, config.master)) {
        report("malformed", kNone, kNone,
               "master " + std::to_string(config.master) + " is not a node of the mission");
    } else {
        if (!model.node(config.master).processing) {
            report("master-invalid", kNone, config.master,
                   "master " + node_name(config.master) + " is not a processing node");
        }
        if (failed_node(failed, config.master)) {
            report("master-invalid", kNone, config.master,
                   "master " + node_name(config.master) + " has failed");
        }
    }
    std::array<bool, Model::kMaxNodes> seen;
    std::fill_n(seen.begin(), model.node_count(), false);
    for (const int observer : config.observers) {
        if (!in_range(model, observer)) {
            report("malformed", kNone, kNone,
                   "observer " + std::to_string(observer) + " is not a node of the mission");
            continue;
        }
        const std::string& name = model.node(observer).name;
        if (observer == config.master) {
            report("observer-invalid", kNone, observer, "observer " + name + " is also the master");
        } else if (seen[static_cast<std::size_t>(observer)]) {
            report("observer-invalid", kNone, observer, "observer " + name + " is listed twice");
        } else if (!model.node(observer).processing) {
            report("observer-invalid", kNone, observer,
                   "observer " + name + " is not a processing node");
        }
        if (observer != config.master && failed_node(failed, observer)) {
            report("observer-invalid", kNone, observer, "observer " + name + " has failed");
        }
        seen[static_cast<std::size_t>(observer)] = true;
    }
    if (config.observers.empty() && alive_processing >= 2) {
        report("observer-invalid", kNone, kNone,
               "no observer while " + std::to_string(alive_processing) +
                   " processing nodes are alive");
    }
    if (checkpointed && !storage_alive) {
        report("storage-unavailable", kNone, kNone,
               "checkpointed task " + checkpointed_task + " is placed and no storage node is alive");
    }
    return found;
}

}  // namespace keel::placement
