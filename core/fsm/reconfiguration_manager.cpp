#include "core/fsm/reconfiguration_manager.hpp"

#include <cassert>

#include "core/fsm/json.hpp"

namespace keel::fsm {

ReconfigurationManager::ReconfigurationManager(const Topology& topology, NodeId self,
                                               Mutant mutant)
    : topology_(&topology), self_(self), mutant_(mutant) {}

void ReconfigurationManager::boot_as_master(const View& initial) {
    assert(initial.master == self_);
    active_ = true;
    driving_ = initial;
}

View ReconfigurationManager::boot_switch(Outbox& out) {
    assert(active_ && driving_.seq == 0);
    // The failed nodes are kept: empty at boot; a Master that was handed over the view
    // (hand_over) drives it without the nodes its predecessor excluded.
    const View next = next_view(driving_.config, driving_.failed);
    driving_ = next;
    trace("BootSwitch",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("c", topology_->config_name(next.config))
              .str(),
          out);
    return next;
}

View ReconfigurationManager::next_view(ConfigId config, NodeSet failed) const {
    View view;
    view.epoch = driving_.epoch;
    view.seq = driving_.seq + 1;
    view.config = config;
    view.base = config == kSafeConfig ? (driving_.is_safe() ? driving_.base : driving_.config)
                                      : config;
    view.master = self_;
    view.failed = failed;
    return view;
}

View ReconfigurationManager::take_over(const View& view, Epoch epoch, NodeSet suspects,
                                       const TakeOverEvidence& evidence, Outbox& out) {
    active_ = true;
    driving_ = view;
    driving_.epoch = epoch;
    driving_.seq = 0;
    const NodeSet failed = view.failed | suspects;
    std::vector<NodeId> fresh;
    failed.minus(view.failed).for_each([&](NodeId node) { fresh.push_back(node); });
    ConfigId target = kSafeConfig;
    if (!view.is_safe()) {
        target = topology_->walk(view.config, fresh, failed).config;
        // The graph must make this node the Master (docs/missions.md: the first alive observer);
        // a graph that names another cannot be followed, and safe mode is the answer.
        if (target != kSafeConfig && topology_->config(target).master != self_) target = kSafeConfig;
    }
    const View next = next_view(target, failed);
    driving_ = next;
    if (out.tracing()) {
        std::string declared = "{";
        for (const auto& [node, by] : evidence.declared) {
            if (declared.size() > 1) declared += ',';
            append_json_string(declared, topology_->node_name(node));
            declared += ':' + json_nodes(*topology_, by);
        }
        declared += '}';
        JsonObject args;
        args.field("n", topology_->node_name(self_))
            .field("c", topology_->config_name(target))
            .raw("was", json_nodes(*topology_, view.failed))
            .raw("mem", json_nodes(*topology_, evidence.members))
            .raw("ev", declared);
        if (!evidence.passed.empty()) args.raw("passed", json_nodes(*topology_, evidence.passed));
        if (!evidence.newer.empty()) args.raw("newer", json_nodes(*topology_, evidence.newer));
        if (!evidence.unprepared.empty()) args.raw("unprepared", json_nodes(*topology_, evidence.unprepared));
        if (evidence.gm) args.field("gm", true);
        if (!evidence.voted.empty()) args.raw("vote", json_nodes(*topology_, evidence.voted));
        trace("BecomeMaster", args.str(), out);
    }
    if (next.is_safe()) out.push(act::EnterSafeMode{});
    return next;
}

View ReconfigurationManager::warm_boot(Epoch epoch, ConfigId target, Outbox& out) {
    assert(target != kSafeConfig && topology_->config(target).master == self_);
    active_ = true;
    driving_ = View{};
    driving_.epoch = epoch;
    driving_.seq = 0;
    driving_.config = target;
    driving_.base = target;
    driving_.master = self_;
    const View next = next_view(target, NodeSet{});
    driving_ = next;
    trace("BecomeMaster",
          JsonObject()
              .field("n", topology_->node_name(self_))
              .field("c", topology_->config_name(target))
              .raw("was", "[]")
              .raw("mem", "[]")
              .raw("ev", "{}")
              .field("warm", true)
              .str(),
          out);
    return next;
}

View ReconfigurationManager::reclaim(Epoch epoch, Outbox& out) {
    assert(active_ && epoch > driving_.epoch);
    driving_.epoch = epoch;
    driving_.seq = 1;
    // The driven view again: it excludes no node it did not exclude before.
    trace("BecomeMaster",
          JsonObject()
              .field("n", topology_->node_name(self_))
              .field("c", topology_->config_name(driving_.config))
              .raw("was", json_nodes(*topology_, driving_.failed))
              .str(),
          out);
    return driving_;
}

std::optional<View> ReconfigurationManager::exclude(NodeId failed, const Evidence& evidence,
                                                       Outbox& out) {
    assert(active_);
    if (failed == self_ || driving_.failed.contains(failed)) return std::nullopt;
    NodeSet all_failed = driving_.failed;
    all_failed.insert(failed);
    ConfigId target = driving_.config;
    if (!driving_.is_safe()) {
        const bool keep_placement = mutant_on(mutant_, Mutant::ignore_failed_node_in_placement) &&
                                    topology_->config(driving_.config).master != failed;
        if (!keep_placement) {
            target = topology_->walk(driving_.config, {failed}, all_failed).config;
            if (target != kSafeConfig && topology_->config(target).master != self_) {
                target = kSafeConfig;
            }
        }
    }
    const bool entering_safe = target == kSafeConfig && !driving_.is_safe();
    const View next = next_view(target, all_failed);
    driving_ = next;
    if (out.tracing()) {
        JsonObject args;
        args.field("m", topology_->node_name(self_))
            .field("f", topology_->node_name(failed))
            .field("c", topology_->config_name(target))
            .field("own", evidence.own)
            .field("ground", evidence.ground)
            .raw("mem", json_nodes(*topology_, evidence.members))
            .raw("ev", json_nodes(*topology_, evidence.declared));
        if (evidence.gm) args.field("gm", true);
        if (evidence.vote) args.field("vote", true);
        trace("Exclude", args.str(), out);
    }
    if (entering_safe) out.push(act::EnterSafeMode{});
    return next;
}

std::optional<View> ReconfigurationManager::on_phase(PhaseId phase, Outbox& out) {
    assert(active_);
    if (driving_.is_safe() || phase >= topology_->phase_count()) return std::nullopt;
    if (topology_->config(driving_.config).phase == phase) return std::nullopt;
    const ConfigId target = topology_->phase_target(driving_.config, phase);
    if (target == kNoConfig) return std::nullopt;
    // The verifier rejects a phase edge into a configuration that uses a failed node
    // (phase-transition-invalid); should one slip through, the phase change is refused
    // rather than placing a task on a node the cluster has excluded.
    for (NodeId host : topology_->config(target).host) {
        if (host != kNoNode && driving_.failed.contains(host)) return std::nullopt;
    }
    const View next = next_view(target, driving_.failed);
    driving_ = next;
    trace("RequestPhase",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("c", topology_->config_name(target))
              .field("phase", topology_->phase(phase).name)
              .str(),
          out);
    return next;
}

std::optional<View> ReconfigurationManager::ground_recovery(ConfigId target, std::string* why,
                                                           Outbox& out) {
    assert(active_ && why != nullptr);
    const auto refuse = [&](std::string reason) -> std::optional<View> {
        *why = std::move(reason);
        return std::nullopt;
    };
    if (!driving_.is_safe()) return refuse("the cluster is not in safe mode");
    if (target == kSafeConfig || static_cast<int>(target) >= topology_->config_count()) {
        return refuse("no such configuration");
    }
    const TopologyConfig& config = topology_->config(target);
    const PhaseId phase = topology_->config(driving_.base).phase;
    if (config.phase != phase) {
        return refuse(config.name + " belongs to phase " + topology_->phase(config.phase).name +
                      ", safe mode was entered in phase " + topology_->phase(phase).name);
    }
    if (config.master != self_) {
        return refuse(config.name + "'s master is " + topology_->node_name(config.master) +
                      ", not this Master " + topology_->node_name(self_));
    }
    std::string used;
    const auto check = [&](NodeId node, const std::string& as) {
        if (node != kNoNode && driving_.failed.contains(node) && used.empty()) {
            used = topology_->node_name(node) + " (" + as + ")";
        }
    };
    check(config.master, "master");
    for (NodeId observer : config.observers) check(observer, "observer");
    for (std::size_t task = 0; task < config.host.size(); ++task) {
        check(config.host[task], "host of " + topology_->task(static_cast<TaskId>(task)).name);
    }
    if (!used.empty()) return refuse(config.name + " uses " + used + ", which the cluster excluded");
    const View next = next_view(target, driving_.failed);
    driving_ = next;
    trace("GroundRecovery",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("c", config.name)
              .str(),
          out);
    return next;
}

View ReconfigurationManager::readmit(NodeId node, ConfigId target, Outbox& out) {
    assert(active_ && driving_.failed.contains(node) && topology_->config(target).master == self_);
    NodeSet failed = driving_.failed;
    failed.erase(node);
    driving_.epoch = topology_->next_epoch(self_, driving_.epoch);
    driving_.seq = 0;
    const View next = next_view(target, failed);
    driving_ = next;
    trace("Readmit",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("r", topology_->node_name(node))
              .field("c", topology_->config_name(target))
              .str(),
          out);
    return next;
}

View ReconfigurationManager::hand_over(NodeId node, ConfigId target, Outbox& out) {
    const NodeId successor = topology_->config(target).master;
    assert(active_ && driving_.failed.contains(node) && successor != self_);
    View next;
    next.epoch = topology_->next_epoch(successor, driving_.epoch);
    next.seq = 0;
    next.config = target;
    next.base = target;
    next.master = successor;
    next.failed = driving_.failed;
    next.failed.erase(node);
    trace("HandOver",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("r", topology_->node_name(node))
              .field("c", topology_->config_name(target))
              .field("to", topology_->node_name(successor))
              .field("epoch", next.epoch)
              .str(),
          out);
    return next;
}

void ReconfigurationManager::trace(const char* action, std::string args, Outbox& out) const {
    if (!out.tracing()) return;
    out.trace("switch", action, std::move(args),
              JsonObject()
                  .field("masterConfig", topology_->config_name(driving_.config))
                  .field("masterSeq", driving_.seq)
                  .field("epoch", driving_.epoch)
                  .raw("failed", json_nodes(*topology_, driving_.failed))
                  .str());
}

}  // namespace keel::fsm
