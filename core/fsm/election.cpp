#include "core/fsm/election.hpp"

#include <algorithm>
#include <cassert>

#include "core/fsm/json.hpp"

namespace keel::fsm {

Election::Election(const Topology& topology, NodeId self, const View& view, Epoch epoch,
                   bool restarted, Mutant mutant)
    : topology_(&topology),
      self_(self),
      mutant_(mutant),
      role_(restarted ? Role::Worker : topology.role_in(view, self)),
      epoch_(epoch),
      leader_(restarted ? kNoNode : view.master) {
    assert(self < topology.node_count());
    if (view.failed.contains(self)) role_ = Role::Worker;
}

bool Election::is_stale(Epoch message_epoch) const {
    if (mutant_on(mutant_, Mutant::election_no_epoch_check)) return false;
    return message_epoch < epoch_;
}

void Election::receive_command(const Command& command, Outbox& out) {
    const Role before = role_;
    if (command.view.epoch > epoch_) epoch_ = command.view.epoch;
    leader_ = command.view.master;  // the sender, but for a hand-over
    last_command_ = command.view.epoch;
    role_ = command.view.failed.contains(self_) ? Role::Worker
                                                : topology_->role_in(command.view, self_);
    // A Command proves its sender alive: whatever this node suspected of it was wrong.
    suspects_.erase(command.from);
    if (out.tracing()) {
        out.trace("election", "ReceiveCommand",
                  JsonObject()
                      .field("n", topology_->node_name(self_))
                      .field("from", topology_->node_name(command.from))
                      .field("epoch", command.view.epoch)
                      .field("stepDown", before == Role::Master && role_ != Role::Master)
                      .str(),
                  vars_json());
    }
}

bool Election::suspect(NodeId node, const View& view, bool may_act, Outbox& out, NodeSet passed) {
    suspects_.insert(node);
    if (out.tracing()) {
        out.trace("election", "Suspect",
                  JsonObject().field("n", topology_->node_name(self_)).field("m", topology_->node_name(node)).str(),
                  vars_json());
    }
    if (mutant_on(mutant_, Mutant::election_no_epoch_check)) {
        return role_ == Role::Observer && !view.failed.contains(self_) && node == view.master;
    }
    return may_take_over(view, may_act, passed);
}

bool Election::may_take_over(const View& view, bool may_act, NodeSet passed) const {
    if (role_ != Role::Observer || view.failed.contains(self_)) return false;
    // A node that hears nobody at all is more likely cut off than the last survivor: it
    // does not take over (the spec's BecomeMaster with one more guard, so every safety
    // property still holds), and the side of a partition that still has company keeps
    // the cluster.
    return may_act && ahead_all_suspected(view, passed);
}

bool Election::ahead_all_suspected(const View& view, NodeSet passed) const {
    // The succession of the view: its Master, then its Observers in priority order.
    if (!(suspects_ | view.failed).contains(view.master)) return false;
    const NodeSet gone = suspects_ | view.failed | passed;
    for (NodeId observer : topology_->observers(view)) {
        if (observer == self_) return true;
        if (!gone.contains(observer)) return false;
    }
    return false;
}

Epoch Election::become_master(const View& view, Outbox& out,
                              const std::vector<std::pair<NodeId, Epoch>>& passed, NodeSet newer,
                              NodeSet unprepared) {
    assert(role_ == Role::Observer);
    (void)view;
    epoch_ = mutant_on(mutant_, Mutant::election_no_epoch_check) ? epoch_ + 1
                                                        : topology_->next_epoch(self_, epoch_);
    role_ = Role::Master;
    leader_ = self_;
    if (out.tracing()) {
        JsonObject args;
        args.field("n", topology_->node_name(self_)).field("epoch", epoch_);
        if (!passed.empty()) {
            JsonObject heard;
            for (const auto& [node, epoch] : passed) heard.field(topology_->node_name(node), epoch);
            args.raw("passed", heard.str());
        }
        if (!newer.empty()) args.raw("newer", json_nodes(*topology_, newer));
        if (!unprepared.empty()) args.raw("unprepared", json_nodes(*topology_, unprepared));
        out.trace("election", "BecomeMaster", args.str(), vars_json());
    }
    return epoch_;
}

Epoch Election::reclaim(Epoch seen, Outbox& out) {
    assert(role_ == Role::Master);
    epoch_ = mutant_on(mutant_, Mutant::election_no_epoch_check) ? seen + 1 : topology_->next_epoch(self_, seen);
    leader_ = self_;
    if (out.tracing()) {
        out.trace("election", "BecomeMaster",
                  JsonObject().field("n", topology_->node_name(self_)).field("epoch", epoch_).field("above", seen).str(),
                  vars_json());
    }
    return epoch_;
}

Epoch Election::warm_boot(Epoch above, Outbox& out) {
    assert(role_ != Role::Master);
    const Epoch floor = std::max(above, epoch_);
    epoch_ = topology_->next_epoch(self_, floor);
    role_ = Role::Master;
    leader_ = self_;
    if (out.tracing()) {
        out.trace("election", "WarmBoot",
                  JsonObject().field("n", topology_->node_name(self_)).field("epoch", epoch_).field("above", floor).str(),
                  vars_json());
    }
    return epoch_;
}

void Election::open_epoch(Epoch epoch, Outbox& out) {
    assert(role_ == Role::Master && epoch > epoch_ && topology_->owner(epoch) == self_);
    epoch_ = epoch;
    if (out.tracing()) {
        out.trace("election", "OpenEpoch",
                  JsonObject().field("n", topology_->node_name(self_)).field("epoch", epoch_).str(),
                  vars_json());
    }
}

std::string Election::vars_json() const {
    return JsonObject()
        .field("role", to_string(role_))
        .field("epoch", epoch_)
        .raw("leader", json_node(*topology_, leader_))
        .raw("suspects", json_nodes(*topology_, suspects_))
        .field("lastCommand", last_command_)
        .str();
}

}  // namespace keel::fsm
