#include "core/fsm/config_switch.hpp"

#include <cassert>

#include "core/fsm/admission.hpp"
#include "core/fsm/json.hpp"
#include "core/fsm/online.hpp"

namespace keel::fsm {

const char* to_string(Stage stage) {
    switch (stage) {
        case Stage::Stable: return "Stable";
        case Stage::Deactivating: return "Deactivating";
        case Stage::Prepared: return "Prepared";
        case Stage::Activating: return "Activating";
    }
    return "Stable";
}

const char* to_string(MasterStage stage) {
    switch (stage) {
        case MasterStage::Idle: return "Idle";
        case MasterStage::Preparing: return "Preparing";
        case MasterStage::Activating: return "Activating";
    }
    return "Idle";
}

ConfigSwitch::ConfigSwitch(const Topology& topology, NodeId self, const View& view,
                           bool restarted, Mutant mutant)
    : topology_(&topology),
      self_(self),
      mutant_(mutant),
      budget_(topology),
      view_(view),
      synced_(!restarted),
      version_(static_cast<std::size_t>(topology.task_count())),
      state_(static_cast<std::size_t>(topology.task_count())),
      holders_pending_(static_cast<std::size_t>(topology.task_count())),
      gathered_found_(static_cast<std::size_t>(topology.task_count())),
      gathered_version_(static_cast<std::size_t>(topology.task_count())),
      gathered_state_(static_cast<std::size_t>(topology.task_count())),
      newer_prepared_(static_cast<std::size_t>(topology.node_count())) {
    assert(self < topology.node_count());
    assert(view.config != kNoConfig);
}

void ConfigSwitch::boot_activate_mutant(Outbox& out) {
    if (!synced_ || !mutant_on(mutant_, Mutant::boot_activates)) return;
    const TaskSet mine = excluded() ? TaskSet{} : topology_->tasks_on(view_, self_);
    mine.for_each([&](TaskId task) { activate(task, Version{}, {}, false, out); });
}

bool ConfigSwitch::storage_available() const {
    const NodeId storage = topology_->storage_node();
    return storage != kNoNode && !view_.failed.contains(storage);
}

// --- participant ---

bool ConfigSwitch::would_adopt(const View& target) const {
    const bool same = target.epoch == view_.epoch && target.seq == view_.seq;
    return newer_than(target.epoch, target.seq, view_.epoch, view_.seq) || (same && !synced_);
}

bool ConfigSwitch::receive_command(const Command& command, Epoch epoch, Outbox& out) {
    const View& target = command.view;
    const bool same = target.epoch == view_.epoch && target.seq == view_.seq;
    if (!would_adopt(target)) {
        // A duplicate of the switch under way: the Master missed the ack, send it again.
        if (same && !excluded()) {
            if (stage_ == Stage::Prepared) ack(AckKind::Prepared, out);
            if (stage_ == Stage::Stable) ack(AckKind::Activated, out);
        }
        return false;
    }
    synced_ = true;
    // The boot switch (seq 1 of the initial epoch) follows a view that ran nothing.
    placed_before_ = TaskSet{};
    host_lost_ = TaskSet{};
    if (view_.epoch > 1 || view_.seq > 0) {
        for (NodeId node = 0; node < topology_->node_count(); ++node) {
            const TaskSet placed = topology_->tasks_on(view_, node);
            placed_before_ = placed_before_ | placed;
            if (target.failed.contains(node) && node != self_) host_lost_ = host_lost_ | placed;
        }
    }
    view_ = target;
    joint_ = command.joint;
    stage_ = Stage::Deactivating;
    // Members that acked Prepared for this view before its Command reached this node.
    peers_prepared_ = NodeSet{};
    activate_held_ = false;
    const std::uint64_t digest = view_digest(view_);
    for (NodeId node = 0; node < topology_->node_count(); ++node) {
        const PeerPrepared& peer = newer_prepared_[node];
        if (node != self_ && !view_.failed.contains(node) && peer.epoch == view_.epoch &&
            peer.seq == view_.seq && peer.digest == digest) {
            peers_prepared_.insert(node);
        }
    }
    restoring_ = TaskSet{};
    gathering_ = TaskSet{};
    // `from` and `out` (the view's excluded nodes): rule 5's check on the trace
    // (TraceConfigSwitch: every exclusion a Command adds to the view the node last
    // checked has a Backed line before it).
    if (out.tracing()) {
        JsonObject args;
        args.field("n", topology_->node_name(self_))
            .field("c", topology_->config_name(target.config))
            .field("epoch", target.epoch)
            .field("seq", target.seq)
            .field("from", command.from < topology_->node_count() ? topology_->node_name(command.from)
                                                                   : std::string("none"))
            .raw("out", json_nodes(*topology_, target.failed));
        if (target.config == kOnlineConfig) args.raw("online", online_json(*topology_, *target.online));
        trace("ReceiveCommand", args.str(), out);
    }
    deactivate_leaving(out);
    if (!storage_available()) {
        // A final flush still pending when the view excludes the Storage node would be
        // lost: the hand-off it carried waits for the Storage node's return instead.
        unstored_ = unstored_ | (unflushed_ & handed_off_);
        unflushed_ = TaskSet{};
    }
    if (excluded()) {
        // The cluster has excluded this node: it runs nothing and takes no further part.
        // What it handed off may be a lineage the cluster has since abandoned (it ran on,
        // cut off, past what the others could restore): it holds nothing any more.
        handed_off_ = TaskSet{};
        unstored_ = TaskSet{};
        unflushed_ = TaskSet{};
        stage_ = Stage::Stable;
        return true;
    }
    // Hand-offs made while the Storage node was excluded go to it as soon as a view
    // includes it again, before this node acks Prepared: whoever starts the task next in
    // this view or a later one restores from the Storage node, which then holds them
    // (a readmitted Storage node, or a Master whose view predates its exclusion).
    if (storage_available() && !mutant_on(mutant_, Mutant::handoff_not_flushed)) {
        unstored_.for_each([&](TaskId task) {
            unflushed_.insert(task);
            send_final(task, view_.epoch, out);
        });
    }
    if (mutant_on(mutant_, Mutant::activate_before_deactivate)) {
        topology_->tasks_on(view_, self_).minus(active_).for_each([&](TaskId task) {
            if (!topology_->task(task).checkpoint) activate(task, Version{}, {}, false, out);
        });
    }
    (void)epoch;
    maybe_prepared(out);
    return true;
}

void ConfigSwitch::deactivate_leaving(Outbox& out) {
    const TaskSet keep = excluded() ? TaskSet{} : topology_->tasks_on(view_, self_);
    deactivate(active_.minus(keep), out);
}

void ConfigSwitch::deactivate(TaskSet tasks, Outbox& out) {
    tasks.for_each([&](TaskId task) {
        active_.erase(task);
        // Held, or waiting to resume: already stopped.
        if (!holding_ && !releasing_.contains(task) && !paused_.contains(task)) out.push(act::Deactivate{task});
        releasing_.erase(task);
        // A member's state at hand-off is what the task's next host starts from (from the
        // Storage node, or from here when the Storage node is excluded). A node fenced out
        // of the cluster may hold a lineage the cluster abandoned: it holds nothing.
        if (topology_->task(task).checkpoint && !excluded()) {
            handed_off_.insert(task);
            if (!storage_available()) unstored_.insert(task);
        } else {
            handed_off_.erase(task);
            unstored_.erase(task);
        }
        trace("Deactivate",
              JsonObject().field("n", topology_->node_name(self_)).field("t", topology_->task(task).name).str(),
              out);
        if (topology_->task(task).checkpoint && storage_available() && !excluded()) {
            unflushed_.insert(task);
            send_final(task, view_.epoch, out);
        }
    });
}

void ConfigSwitch::send_final(TaskId task, Epoch epoch, Outbox& out) {
    out.send(topology_->storage_node(),
             CheckpointWrite{self_, epoch, task, version_[task], true, state_[task]});
    trace("FlushCheckpoint",
          JsonObject()
              .field("n", topology_->node_name(self_))
              .field("t", topology_->task(task).name)
              .version(version_[task])
              .field("final", true)
              .str(),
          out);
}

void ConfigSwitch::maybe_prepared(Outbox& out) {
    if (stage_ != Stage::Deactivating || !unflushed_.empty()) return;
    stage_ = Stage::Prepared;
    ack(AckKind::Prepared, out);
}

void ConfigSwitch::receive_activate(const ActivateCommand& activate_command, Epoch epoch,
                                    Outbox& out) {
    if (activate_command.epoch != view_.epoch || activate_command.seq != view_.seq) return;
    if (excluded()) return;
    if (stage_ == Stage::Stable) {
        // A duplicate: the Master missed the ack, send it again. Not after a restart until
        // a Command is adopted: the saved view's tasks do not run here, and the node may
        // have gone down before it activated them (a restart is Stable and runs nothing;
        // ConfigSwitch.tla allows an Activated ack only as the resend of one made before).
        if (synced_) ack(AckKind::Activated, out);
        return;
    }
    if (stage_ != Stage::Prepared) return;
    // Rule 4: the Master's word that every member is prepared is not enough; each member's
    // own is (a lying Master activates before a member stopped the task, or has sent two
    // members two views under this id).
    if (!peers_complete()) {
        if (!activate_held_) {
            activate_held_ = true;
            ++activations_held_;
            // A member's Prepared may have been lost on its way here: this node's own goes
            // to the members it lacks, and those past theirs answer at once, rather than
            // when this node repeats it at its next period.
            NodeSet missing = topology_->all_nodes().minus(view_.failed).minus(peers_prepared_);
            missing.erase(self_);
            send_prepared(missing, false, out);
        }
        held_epoch_ = epoch;
        return;
    }
    start_activation(epoch, out);
}

void ConfigSwitch::start_activation(Epoch epoch, Outbox& out) {
    stage_ = Stage::Activating;
    activate_held_ = false;
    // Every node the view does not exclude acked Prepared: all of them have adopted the
    // view, so no one goes by a joint view any more.
    joint_.clear();
    // Rule 4 on the trace: the members whose Prepared of this very view this node holds
    // (`peers`), and those the view excludes (`out`): every other node is in one of them
    // (spec/trace/TraceConfigSwitch.tla, PeersPreparedLine).
    trace("ReceiveActivate",
          JsonObject()
              .field("n", topology_->node_name(self_))
              .field("epoch", view_.epoch)
              .field("seq", view_.seq)
              .raw("peers", json_nodes(*topology_, peers_prepared_))
              .raw("out", json_nodes(*topology_, view_.failed))
              .str(),
          out);
    activate_arriving(epoch, out);
}

bool ConfigSwitch::peers_complete() const {
    if (mutant_on(mutant_, Mutant::no_peer_prepared) || mutant_on(mutant_, Mutant::no_receiver_checks)) return true;
    NodeSet members = topology_->all_nodes().minus(view_.failed);
    members.erase(self_);
    return peers_prepared_.includes(members);
}

void ConfigSwitch::receive_prepared(const Ack& ack, Outbox& out) {
    if (ack.kind != AckKind::Prepared || ack.from == self_ || ack.from >= topology_->node_count()) return;
    if (ack.epoch == view_.epoch && ack.seq == view_.seq) {
        if (ack.view != view_digest(view_) || view_.failed.contains(ack.from)) return;
        const bool repeated = peers_prepared_.contains(ack.from);
        peers_prepared_.insert(ack.from);
        if (!repeated) trace_heard_prepared(ack, out);
        // A member that repeats its Prepared (tick(), or on an Activate it holds) is still
        // waiting, maybe for this node's, which it may have missed. This node answers (a
        // reply, never answered in turn) once past its own Prepared, or prepared itself
        // and hearing it again. (A node past its Prepared sends none but replies, so no
        // two nodes answer each other for ever.)
        const bool past = stage_ == Stage::Activating || (stage_ == Stage::Stable && view_.seq > 0);
        if (!ack.reply && !excluded() && synced_ && (past || (repeated && stage_ == Stage::Prepared))) {
            NodeSet to;
            to.insert(ack.from);
            send_prepared(to, true, out);
        }
        if (activate_held_ && stage_ == Stage::Prepared && peers_complete()) {
            start_activation(held_epoch_, out);
        }
        return;
    }
    PeerPrepared& peer = newer_prepared_[ack.from];
    if (newer_than(ack.epoch, ack.seq, view_.epoch, view_.seq) &&
        !newer_than(peer.epoch, peer.seq, ack.epoch, ack.seq)) {
        const bool first = peer.epoch != ack.epoch || peer.seq != ack.seq || peer.digest != ack.view;
        peer = PeerPrepared{ack.epoch, ack.seq, ack.view};
        if (first) trace_heard_prepared(ack, out);
    }
}

void ConfigSwitch::trace_heard_prepared(const Ack& ack, Outbox& out) const {
    // The first receipt of a member's Prepared of a view: the member said it had saved that
    // view (a restarted node's Restored line is held to it).
    trace("HeardPrepared",
          JsonObject()
              .field("n", topology_->node_name(self_))
              .field("from", topology_->node_name(ack.from))
              .field("epoch", ack.epoch)
              .field("seq", ack.seq)
              .str(),
          out);
}

bool ConfigSwitch::prepared_newer_switch(NodeId node) const {
    if (node >= topology_->node_count()) return false;
    const PeerPrepared& peer = newer_prepared_[node];
    return peer.epoch == view_.epoch && peer.seq > view_.seq;
}

bool ConfigSwitch::vouched(const View& target, NodeId sender) const { return voucher(target, sender).has_value(); }

std::optional<NodeId> ConfigSwitch::voucher(const View& target, NodeId sender) const {
    const std::uint64_t digest = view_digest(target);
    for (NodeId node = 0; node < topology_->node_count(); ++node) {
        const PeerPrepared& peer = newer_prepared_[node];
        if (node != sender && node != self_ && !target.failed.contains(node) && peer.epoch == target.epoch &&
            peer.seq == target.seq && peer.digest == digest) {
            return node;
        }
    }
    return std::nullopt;
}

void ConfigSwitch::activate_arriving(Epoch epoch, Outbox& out) {
    const TaskSet arriving = topology_->tasks_on(view_, self_).minus(active_);
    arriving.for_each([&](TaskId task) {
        const bool checkpointed = topology_->task(task).checkpoint &&
                                  !mutant_on(mutant_, Mutant::no_checkpoint_restore);
        const bool restore = checkpointed && storage_available();
        if (checkpointed && !storage_available() && !mutant_on(mutant_, Mutant::no_holder_restore)) {
            gather_from_holders(task, epoch, out);
        } else if (restore) {
            restoring_.insert(task);
            out.send(topology_->storage_node(), CheckpointRequest{self_, epoch, view_.seq, task});
        } else {
            activate(task, Version{}, {}, false, out);
        }
    });
    maybe_activated(out);
}

void ConfigSwitch::gather_from_holders(TaskId task, Epoch epoch, Outbox& out) {
    gathered_found_[task] = handed_off_.contains(task);
    gathered_version_[task] = gathered_found_[task] ? version_[task] : Version{};
    gathered_state_[task] = gathered_found_[task] ? state_[task] : std::vector<std::uint8_t>{};
    NodeSet holders;
    for (NodeId node = 0; node < topology_->node_count(); ++node) {
        if (node != self_ && !view_.failed.contains(node)) holders.insert(node);
    }
    holders_pending_[task] = holders;
    restoring_.insert(task);
    gathering_.insert(task);
    trace("AskHolders",
          JsonObject()
              .field("n", topology_->node_name(self_))
              .field("t", topology_->task(task).name)
              .raw("holders", json_nodes(*topology_, holders))
              .str(),
          out);
    if (holders.empty()) {
        finish_gathering(task, out);
        return;
    }
    holders.for_each([&](NodeId node) {
        out.send(node, CheckpointRequest{self_, epoch, view_.seq, task});
    });
}

void ConfigSwitch::finish_gathering(TaskId task, Outbox& out) {
    restoring_.erase(task);
    gathering_.erase(task);
    if (gathered_found_[task]) ++holder_restores_;
    const bool lost = placed_before_.contains(task) &&
                      (!gathered_found_[task] || host_lost_.contains(task));
    if (lost) {
        // The Storage node is excluded and the task's newest state is out of reach: no
        // member holds any, or its last host is excluded too (what it ran since its
        // last hand-off is gone). Reported, counted, and started from what is left.
        ++unrecoverable_starts_;
        trace("StateOutOfReach",
              JsonObject()
                  .field("n", topology_->node_name(self_))
                  .field("t", topology_->task(task).name)
                  .version(gathered_version_[task])
                  .str(),
              out);
    }
    // A start without the Storage node from a hand-off, or an unrecoverable one, opens a
    // new lineage named by this view: what the cluster goes on with is then newer than a
    // state of the lineage it may abandon, which an excluded Storage node may still hold
    // with more steps (spec/Handoff.tla, "Lineages"). A start from nothing that loses
    // nothing keeps the initial lineage.
    std::optional<std::uint64_t> opened;
    if ((gathered_found_[task] || lost) && !mutant_on(mutant_, Mutant::lineage_kept)) {
        opened = lineage_of(view_.epoch, view_.seq);
    }
    activate(task, gathered_version_[task], std::move(gathered_state_[task]),
             gathered_found_[task], out, opened);
    gathered_state_[task].clear();
}

void ConfigSwitch::answer_checkpoint_request(const CheckpointRequest& request, TimeNs now,
                                             Outbox& out) {
    if (request.task >= topology_->task_count() || request.from >= topology_->node_count() ||
        request.from == self_ || excluded() || !budget_.admit(request, view_, now)) {
        return;
    }
    CheckpointReply reply;
    reply.from = self_;
    reply.epoch = request.epoch;
    reply.seq = request.seq;
    reply.task = request.task;
    reply.found = handed_off_.contains(request.task) && !active_.contains(request.task);
    if (reply.found) {
        reply.version = version_[request.task];
        reply.state = state_[request.task];
    }
    out.send(request.from, std::move(reply));
}

void ConfigSwitch::activate(TaskId task, Version version, std::vector<std::uint8_t> state,
                            bool restored, Outbox& out, std::optional<std::uint64_t> opened) {
    active_.insert(task);
    handed_off_.erase(task);
    unstored_.erase(task);
    // A state of a lineage of an epoch above this view's (the kept checkpoints a Storage
    // node hands a cluster that cold-started at epoch 1, or a value-faulty Storage node's)
    // runs on in a lineage of this view: its writes would otherwise be versions from the
    // future, which the Storage node refuses, and the switch would wait for a flush that
    // is never acknowledged (keel-sim --liar, prototype3 seed 12602).
    if (!opened && lineage_epoch(version.lineage) > view_.epoch) opened = lineage_of(view_.epoch, view_.seq);
    // The line logs the state the task starts from; `opened`, the lineage it runs in now.
    JsonObject line;
    line.field("n", topology_->node_name(self_))
        .field("t", topology_->task(task).name)
        .version(version)
        .field("restored", restored);
    if (opened) line.raw("opened", json_lineage(*opened));
    const Version from = version;
    if (opened) version.lineage = *opened;
    version_[task] = version;
    state_[task] = state;
    trace("Activate", line.str(), out);
    if (!holding_ && !paused_.contains(task)) out.push(act::Activate{task, version, std::move(state), restored, false, from});
}

void ConfigSwitch::hold(Outbox& out) {
    if (holding_) return;
    holding_ = true;
    active_.minus(releasing_).minus(paused_).for_each([&](TaskId task) { out.push(act::Deactivate{task}); });
    releasing_ = TaskSet{};
    if (active_.minus(paused_).empty()) return;  // nothing stopped: no line
    trace("Hold", JsonObject().field("n", topology_->node_name(self_)).str(), out);
}

void ConfigSwitch::release(Outbox& out) {
    if (!holding_) return;
    holding_ = false;
    if (!active_.empty()) trace("Release", JsonObject().field("n", topology_->node_name(self_)).str(), out);
    // A checkpointed task resumes from the newer of its own state and the stored one: while
    // held, this node may have been excluded and the task run elsewhere (it cannot know),
    // so the Storage node is asked first (resume_released). Others resume at once. A task
    // the ground paused stays stopped.
    active_.minus(paused_).for_each([&](TaskId task) { restart(task, out); });
}

void ConfigSwitch::restart(TaskId task, Outbox& out) {
    if (topology_->task(task).checkpoint && storage_available() && !excluded() &&
        !mutant_on(mutant_, Mutant::no_checkpoint_restore)) {
        releasing_.insert(task);
        out.send(topology_->storage_node(), CheckpointRequest{self_, view_.epoch, view_.seq, task});
    } else {
        out.push(act::Activate{task, version_[task], state_[task], false, true, version_[task]});
    }
}

bool ConfigSwitch::pause(TaskId task, Outbox& out) {
    assert(task < topology_->task_count());
    if (paused_.contains(task)) return false;
    paused_.insert(task);
    trace("GroundPause",
          JsonObject().field("n", topology_->node_name(self_)).field("t", topology_->task(task).name).str(), out);
    if (mutant_on(mutant_, Mutant::pause_keeps_running)) return true;
    // Running: stopped now. Waiting for the Storage node to resume it: it stays stopped.
    if (active_.contains(task) && !holding_ && !releasing_.contains(task)) out.push(act::Deactivate{task});
    releasing_.erase(task);
    return true;
}

bool ConfigSwitch::resume(TaskId task, Outbox& out) {
    assert(task < topology_->task_count());
    if (!paused_.contains(task)) return false;
    paused_.erase(task);
    trace("GroundResume",
          JsonObject().field("n", topology_->node_name(self_)).field("t", topology_->task(task).name).str(), out);
    // Placed here and not held by the lease: it runs again (release() restarts it later
    // otherwise; one still being restored starts as its restore completes).
    if (active_.contains(task) && !holding_) {
        restart(task, out);
    }
    return true;
}

bool ConfigSwitch::resume_released(const CheckpointReply& reply, Outbox& out) {
    if (!releasing_.contains(reply.task) || reply.epoch != view_.epoch || reply.seq != view_.seq) {
        return false;
    }
    const TaskId task = reply.task;
    releasing_.erase(task);
    if (!active_.contains(task)) return true;
    // As a start does (activate): a state of a lineage of an epoch above this view's runs
    // on in a lineage of this view, or its writes would be versions from the future, which
    // the Storage node refuses (spec/ValueFault.tla, RunLineage: a value-faulty Storage
    // node's answer to the resumption). Compared as it will run: one of this view's
    // lineage with fewer steps than this node's own state is older, not newer.
    Version resumed = reply.version;
    if (lineage_epoch(resumed.lineage) > view_.epoch) resumed.lineage = lineage_of(view_.epoch, view_.seq);
    const bool stored_newer = reply.found && adoptable(reply.version) && resumed > version_[task];
    const Version from = stored_newer ? reply.version : version_[task];
    if (stored_newer) {
        version_[task] = resumed;
        state_[task] = reply.state;
    }
    out.push(act::Activate{task, version_[task], state_[task], stored_newer, true, from});
    return true;
}

bool ConfigSwitch::adoptable(const Version& version) {
    if (version.count <= kMaxAdoptedCount) return true;
    ++unadoptable_states_;
    return false;
}

void ConfigSwitch::maybe_activated(Outbox& out) {
    if (stage_ != Stage::Activating || !restoring_.empty()) return;
    stage_ = Stage::Stable;
    ack(AckKind::Activated, out);
}

void ConfigSwitch::receive_checkpoint_ack(const CheckpointAck& checkpoint_ack, Outbox& out) {
    const TaskId task = checkpoint_ack.task;
    if (task >= topology_->task_count() || !unflushed_.contains(task)) return;
    if (checkpoint_ack.version < version_[task]) return;  // an ack of an older write
    unflushed_.erase(task);
    unstored_.erase(task);
    maybe_prepared(out);
}

void ConfigSwitch::receive_checkpoint_reply(const CheckpointReply& reply, Epoch epoch,
                                            Outbox& out) {
    (void)epoch;
    if (reply.task >= topology_->task_count()) return;
    if (gathering_.contains(reply.task)) {
        const TaskId task = reply.task;
        if (stage_ != Stage::Activating || reply.epoch != view_.epoch || reply.seq != view_.seq ||
            reply.from >= topology_->node_count() || !holders_pending_[task].contains(reply.from)) {
            return;
        }
        holders_pending_[task].erase(reply.from);
        // A state beyond the adoptable count counts as holding nothing.
        if (reply.found && adoptable(reply.version) &&
            (!gathered_found_[task] || reply.version > gathered_version_[task])) {
            gathered_found_[task] = true;
            gathered_version_[task] = reply.version;
            gathered_state_[task] = reply.state;
        }
        if (holders_pending_[task].empty()) {
            finish_gathering(task, out);
            maybe_activated(out);
        }
        return;
    }
    // Everything else answers a request to the Storage node.
    if (reply.from != topology_->storage_node()) return;
    if (resume_released(reply, out)) return;
    if (stage_ != Stage::Activating || reply.epoch != view_.epoch || reply.seq != view_.seq) return;
    if (!restoring_.contains(reply.task)) return;
    restoring_.erase(reply.task);
    if (reply.found && !adoptable(reply.version)) {
        // A stored count no correct run reaches (a writer's value fault): treated as lost.
        // The task starts from no state in a lineage of this view, newer than a stored one
        // of an earlier view, so that its writes are taken (one forged in this view's own
        // epoch is replaced by the host's next write, CheckpointStore::host_wins, unless
        // its writer hosted the task in the previous view).
        activate(reply.task, Version{}, {}, false, out, lineage_of(view_.epoch, view_.seq));
    } else {
        activate(reply.task, reply.found ? reply.version : Version{}, reply.state, reply.found, out);
    }
    maybe_activated(out);
}

void ConfigSwitch::task_stepped(TaskId task, std::vector<std::uint8_t> state, Epoch epoch,
                                Outbox& out) {
    if (task >= topology_->task_count() || !active_.contains(task)) return;
    // A step that ends after the pause stopped it (ordering contract 4 keeps it out).
    if (paused_.contains(task) && !mutant_on(mutant_, Mutant::pause_keeps_running)) return;
    ++version_[task].count;
    state_[task] = std::move(state);
    if (topology_->task(task).checkpoint && storage_available() && !excluded()) {
        out.send(topology_->storage_node(),
                 CheckpointWrite{self_, epoch, task, version_[task], false, state_[task]});
        trace("FlushCheckpoint",
              JsonObject()
                  .field("n", topology_->node_name(self_))
                  .field("t", topology_->task(task).name)
                  .version(version_[task])
                  .field("final", false)
                  .str(),
              out);
    }
}

void ConfigSwitch::send_prepared(NodeSet to, bool reply, Outbox& out) const {
    const std::uint64_t digest = view_digest(view_) + (mutant_on(mutant_, Mutant::prepared_other_digest) ? 1 : 0);
    const Ack prepared{self_, view_.epoch, view_.seq, AckKind::Prepared, digest, reply};
    to.for_each([&](NodeId node) { out.send(node, prepared); });
}

void ConfigSwitch::ack(AckKind kind, Outbox& out) {
    if (kind == AckKind::Prepared) {
        // To every member (rule 4), and to the Master's driver when this node is the Master.
        NodeSet members = topology_->all_nodes().minus(view_.failed);
        if (view_.master != self_) members.erase(self_);
        send_prepared(members, false, out);
    } else {
        out.send(view_.master, Ack{self_, view_.epoch, view_.seq, kind});
    }
    trace("Ack",
          JsonObject().field("n", topology_->node_name(self_)).field("kind", to_string(kind)).str(),
          out);
}

void ConfigSwitch::resign(Outbox& out) {
    step_down();
    stage_ = Stage::Stable;
    restoring_ = TaskSet{};
    trace("Resign", JsonObject().field("n", topology_->node_name(self_)).str(), out);
    deactivate(active_, out);
}

// --- driver ---

void ConfigSwitch::boot_as_master() {
    driving_ = true;
    master_view_ = view_;
    master_stage_ = MasterStage::Idle;
}

void ConfigSwitch::broadcast(const Message& message, NodeSet except, Outbox& out) const {
    topology_->all_nodes().minus(master_view_.failed).minus(except).for_each(
        [&](NodeId node) { out.send(node, message); });
}

void ConfigSwitch::start_switch(const View& target, Outbox& out, std::vector<View> joint) {
    assert(target.master == self_);
    driving_ = true;
    master_view_ = target;
    master_joint_ = std::move(joint);
    master_stage_ = MasterStage::Preparing;
    prepared_ = NodeSet{};
    activated_ = NodeSet{};
    // Traced with the driver's variables (masterStage, masterConfig, masterSeq): the
    // trace validator compares those at this line (verify/keel_verify/trace/switch.py).
    if (out.tracing()) {
        JsonObject args;
        args.field("m", topology_->node_name(self_))
            .field("c", topology_->config_name(target.config))
            .field("epoch", target.epoch)
            .field("seq", target.seq);
        if (target.config == kOnlineConfig) args.raw("online", online_json(*topology_, *target.online));
        trace("BroadcastCommand", args.str(), out);
    }
    broadcast(Command{self_, target, master_joint_}, NodeSet{}, out);
}

bool ConfigSwitch::receive_ack(const Ack& received, Outbox& out) {
    if (!driving_ || received.epoch != master_view_.epoch || received.seq != master_view_.seq) {
        return false;
    }
    const NodeSet live = topology_->all_nodes().minus(master_view_.failed);
    if (!live.contains(received.from)) return false;
    if (received.kind == AckKind::Prepared) {
        // Prepared for another view under this id is no ack of this switch.
        if (received.view != view_digest(master_view_)) return false;
        if (master_stage_ != MasterStage::Preparing) return false;
        prepared_.insert(received.from);
        if (!prepared_.includes(live)) return false;
        master_stage_ = MasterStage::Activating;
        trace("BroadcastActivate",
              JsonObject().field("m", topology_->node_name(self_)).field("seq", master_view_.seq).str(),
              out);
        broadcast(ActivateCommand{self_, master_view_.epoch, master_view_.seq}, NodeSet{}, out);
        return false;
    }
    activated_.insert(received.from);
    if (master_stage_ != MasterStage::Activating || !activated_.includes(live)) return false;
    master_stage_ = MasterStage::Idle;
    trace("CompleteSwitch",
          JsonObject()
              .field("m", topology_->node_name(self_))
              .field("c", topology_->config_name(master_view_.config))
              .field("seq", master_view_.seq)
              .str(),
          out);
    return true;
}

void ConfigSwitch::tick(Epoch epoch, Outbox& out) {
    unflushed_.for_each([&](TaskId task) { send_final(task, view_.epoch, out); });
    // Prepared, and waiting for the Activate or a member's Prepared: this node's own goes
    // again to the members that have not acked theirs (one may have missed it; those past
    // their Prepared answer).
    if (stage_ == Stage::Prepared && !excluded()) {
        NodeSet members = topology_->all_nodes().minus(view_.failed).minus(peers_prepared_);
        members.erase(self_);
        send_prepared(members, false, out);
    }
    if (stage_ == Stage::Activating) {
        restoring_.for_each([&](TaskId task) {
            if (gathering_.contains(task)) {
                holders_pending_[task].for_each([&](NodeId node) {
                    out.send(node, CheckpointRequest{self_, epoch, view_.seq, task});
                });
                return;
            }
            out.send(topology_->storage_node(), CheckpointRequest{self_, epoch, view_.seq, task});
        });
    }
    const TaskSet releasing = releasing_;
    releasing.for_each([&](TaskId task) {
        if (!storage_available()) {
            // The Storage node was excluded meanwhile: the task resumes from its own state.
            releasing_.erase(task);
            out.push(act::Activate{task, version_[task], state_[task], false, true, version_[task]});
            return;
        }
        out.send(topology_->storage_node(), CheckpointRequest{self_, view_.epoch, view_.seq, task});
    });
    if (!driving_ || mutant_on(mutant_, Mutant::no_retransmit)) return;
    if (master_stage_ == MasterStage::Preparing) {
        broadcast(Command{self_, master_view_, master_joint_}, prepared_, out);
    } else if (master_stage_ == MasterStage::Activating) {
        broadcast(ActivateCommand{self_, master_view_.epoch, master_view_.seq}, activated_, out);
    }
}

void ConfigSwitch::trace_restored(Epoch saved, Outbox& out) const {
    trace("Restored",
          JsonObject()
              .field("n", topology_->node_name(self_))
              .field("c", topology_->config_name(view_.config))
              .field("epoch", view_.epoch)
              .field("seq", view_.seq)
              .field("saved", saved)
              .str(),
          out);
}

void ConfigSwitch::trace(const char* action, std::string args, Outbox& out) const {
    if (out.tracing()) out.trace("switch", action, std::move(args), vars_json());
}

std::string ConfigSwitch::vars_json() const {
    // Each active task's count, and the lineages other than the initial one.
    std::string versions = "{";
    std::string lineages = "{";
    bool first = true;
    bool first_lineage = true;
    active_.for_each([&](TaskId task) {
        if (!first) versions.push_back(',');
        first = false;
        append_json_string(versions, topology_->task(task).name);
        versions.push_back(':');
        versions += std::to_string(version_[task].count);
        if (version_[task].lineage == 0) return;
        if (!first_lineage) lineages.push_back(',');
        first_lineage = false;
        append_json_string(lineages, topology_->task(task).name);
        lineages.push_back(':');
        lineages += json_lineage(version_[task].lineage);
    });
    versions.push_back('}');
    lineages.push_back('}');
    JsonObject vars;
    vars.field("role", to_string(role_))
        .field("epoch", view_.epoch)
        .field("seq", view_.seq)
        .field("config", topology_->config_name(view_.config))
        .field("stage", to_string(stage_))
        .raw("active", json_tasks(*topology_, active_))
        .raw("unflushed", json_tasks(*topology_, unflushed_))
        .raw("version", versions);
    if (!first_lineage) vars.raw("lineage", lineages);
    if (driving_) {
        vars.field("masterStage", to_string(master_stage_))
            .field("masterConfig", topology_->config_name(master_view_.config))
            .field("masterSeq", master_view_.seq)
            .raw("failed", json_nodes(*topology_, master_view_.failed));
    }
    return vars.str();
}

}  // namespace keel::fsm
