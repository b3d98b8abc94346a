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
    const View next = next_view(Target::graph(driving_.config), driving_.failed);
    driving_ = next;
    trace("BootSwitch",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("c", topology_->config_name(next.config))
              .str(),
          out);
    return next;
}

View ReconfigurationManager::next_view(const Target& target, NodeSet failed) const {
    View view;
    view.epoch = driving_.epoch;
    view.seq = driving_.seq + 1;
    view.config = target.config;
    if (target.is_safe()) {
        // Safe mode keeps the configuration it was entered from (an online one whole).
        view.base = driving_.is_safe() ? driving_.base : driving_.config;
        view.online = driving_.online;
    } else {
        view.base = target.config;
        view.online = target.online;
    }
    view.master = self_;
    view.failed = failed;
    return view;
}

void ReconfigurationManager::target_fields(JsonObject& args, const Target& target) const {
    args.field("c", topology_->config_name(target.config));
    if (target.online) args.raw("online", online_json(*topology_, *target.online));
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
    // The graph (or the placer) must make this node the Master (docs/missions.md: the
    // first alive observer); one that names another cannot be followed, and safe mode is
    // the answer.
    Target target = failure_target(*topology_, view, fresh, failed, self_);
    if (mutant_on(mutant_, Mutant::online_gives_up) && view.config == kOnlineConfig) target = Target::safe();
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
        args.field("n", topology_->node_name(self_));
        target_fields(args, target);
        args.raw("was", json_nodes(*topology_, view.failed))
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
    const View next = next_view(Target::graph(target), NodeSet{});
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
    Target target = Target::safe();
    if (!driving_.is_safe()) {
        const bool keep_placement = mutant_on(mutant_, Mutant::ignore_failed_node_in_placement) &&
                                    driving_.config != kOnlineConfig &&
                                    topology_->config(driving_.config).master != failed;
        target = keep_placement ? Target::graph(driving_.config)
                                : failure_target(*topology_, driving_, {failed}, all_failed, self_);
        if (mutant_on(mutant_, Mutant::online_gives_up) && driving_.config == kOnlineConfig) target = Target::safe();
    }
    const bool entering_safe = target.is_safe() && !driving_.is_safe();
    const View next = next_view(target, all_failed);
    driving_ = next;
    if (out.tracing()) {
        JsonObject args;
        args.field("m", topology_->node_name(self_)).field("f", topology_->node_name(failed));
        target_fields(args, target);
        args.field("own", evidence.own)
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
    if (topology_->phase_of(driving_) == phase) return std::nullopt;
    // The graph's phase edge, or the placer where the phase is placed online (online.hpp);
    // nothing when neither gives a configuration this Master drives without a failed node.
    const std::optional<Target> target = phase_target(*topology_, driving_, phase, self_);
    if (!target) return std::nullopt;
    const View next = next_view(*target, driving_.failed);
    driving_ = next;
    if (out.tracing()) {
        JsonObject args;
        args.field("m", topology_->node_name(self_));
        target_fields(args, *target);
        args.field("phase", topology_->phase(phase).name);
        trace("RequestPhase", args.str(), out);
    }
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
    const PhaseId phase = topology_->phase_of(driving_);
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
    const View next = next_view(Target::graph(target), driving_.failed);
    driving_ = next;
    trace("GroundRecovery",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("c", config.name)
              .str(),
          out);
    return next;
}

View ReconfigurationManager::readmit(NodeId node, const Target& target, Outbox& out) {
    assert(active_ && driving_.failed.contains(node) && master_of(*topology_, target) == self_);
    NodeSet failed = driving_.failed;
    failed.erase(node);
    driving_.epoch = topology_->next_epoch(self_, driving_.epoch);
    driving_.seq = 0;
    const View next = next_view(target, failed);
    driving_ = next;
    if (out.tracing()) {
        JsonObject args;
        args.field("m", topology_->node_name(self_)).field("r", topology_->node_name(node));
        target_fields(args, target);
        trace("Readmit", args.str(), out);
    }
    return next;
}

View ReconfigurationManager::hand_over(NodeId node, const Target& target, Outbox& out) {
    const NodeId successor = master_of(*topology_, target);
    assert(active_ && driving_.failed.contains(node) && successor != self_ && !target.is_safe());
    View next;
    next.epoch = topology_->next_epoch(successor, driving_.epoch);
    next.seq = 0;
    next.config = target.config;
    next.base = target.config;
    next.online = target.online;
    next.master = successor;
    next.failed = driving_.failed;
    next.failed.erase(node);
    if (out.tracing()) {
        JsonObject args;
        args.field("m", topology_->node_name(self_)).field("r", topology_->node_name(node));
        target_fields(args, target);
        args.field("to", topology_->node_name(successor)).field("epoch", next.epoch);
        trace("HandOver", args.str(), out);
    }
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
