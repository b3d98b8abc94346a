#include "core/fsm/node_protocol.hpp"

#include <algorithm>
#include <cassert>
#include <type_traits>
#include <variant>

#include "core/fsm/admission.hpp"
#include "core/fsm/json.hpp"
#include "core/fsm/online.hpp"
#include "core/fsm/overloaded.hpp"

namespace keel::fsm {

namespace {

// The Command's index in Message (NodeStats counts by it).
template <typename T, typename Variant>
struct IndexIn;
template <typename T, typename... Ts>
struct IndexIn<T, std::variant<Ts...>> {
    static constexpr std::size_t value = [] {
        constexpr bool same[] = {std::is_same_v<T, Ts>...};
        for (std::size_t i = 0; i < sizeof...(Ts); ++i) {
            if (same[i]) return i;
        }
        return sizeof...(Ts);
    }();
};
constexpr std::size_t kCommandIndex = IndexIn<Command, Message>::value;
static_assert(kCommandIndex < std::variant_size_v<Message>);

TimeNs first_boundary(TimeNs now, TimeNs offset, TimeNs period) {
    if (now <= offset) return offset;
    const TimeNs periods = (now - offset + period - 1) / period;
    return offset + periods * period;
}

View boot_view(const Topology& topology, const PersistentState* restart) {
    return restart != nullptr ? restart->view : topology.initial_view();
}

}  // namespace

NodeProtocol::NodeProtocol(const Topology& topology, NodeId self, TimeNs now,
                           const NodeOptions& options)
    : NodeProtocol(topology, self, now, options, nullptr) {}

NodeProtocol::NodeProtocol(const Topology& topology, NodeId self, TimeNs now,
                           const NodeOptions& options, const PersistentState& restart)
    : NodeProtocol(topology, self, now, options, &restart) {}

NodeProtocol::NodeProtocol(const Topology& topology, NodeId self, TimeNs now,
                           const NodeOptions& options, const PersistentState* restart)
    : topology_(&topology),
      self_(self),
      options_(options),
      out_(options.tracing),
      monitor_(topology, self, restart != nullptr ? restart->incarnation + 1 : 1,
               first_boundary(now, options.phase_offset_ns, topology.heartbeat_period_ns()),
               options.mutant, options.boot),
      election_(topology, self, boot_view(topology, restart),
                restart != nullptr ? restart->epoch : 1, restart != nullptr, options.mutant),
      manager_(topology, self, options.mutant),
      switch_(topology, self, boot_view(topology, restart), restart != nullptr, options.mutant),
      now_(now),
      booted_ns_(now),
      reports_now_(static_cast<std::size_t>(topology.node_count())),
      reports_before_(static_cast<std::size_t>(topology.node_count())) {
    if (topology.tie_grace() > 0) {
        std::array<TimeNs, kMaxNodes> none{};
        none.fill(-1);
        report_since_.assign(static_cast<std::size_t>(topology.node_count()), none);
    }
    assert(self < topology.node_count());
    assert(options.phase_offset_ns >= 0 && options.phase_offset_ns < topology.heartbeat_period_ns());
    const View& view = switch_.view();
    if (self == topology.storage_node()) {
        store_.emplace(topology, self);
        store_->set_view(view);
        store_->restore(restart != nullptr ? restart->checkpoints : options.kept_checkpoints);
        if (restart != nullptr) store_->trace_recovered(out_);
    }
    vetted_ = view;
    monitor_.set_previous_boot(options.previous_boot != 0 ? options.previous_boot
                                                          : (restart != nullptr ? restart->boot : 0));
    monitor_.set_image(options.image);
    // Saved state read back from the disk: only the mission's nodes (the rest is no node).
    if (restart != nullptr) {
        held_out_ = restart->held_out & topology.all_nodes();
        TaskSet paused;
        // The mission's tasks that may be paused only (an essential one never is).
        restart->paused.for_each([&](TaskId task) {
            if (task < topology.task_count() && !topology.task(task).essential) paused.insert(task);
        });
        switch_.restore_paused(paused);
    }
    restarted_ = restart != nullptr;
    if (restarted_) {
        switch_.trace_restored(restart->epoch, out_);
        announce_restart();
    }
    switch_.set_role(election_.role());
    switch_.boot_activate_mutant(out_);
    update_watch();
    // The boot switch (contract point 1): the initial Master commands the initial
    // configuration at seq 1; nobody runs anything before its Activate. It starts once the
    // Master holds its lease (enforce_lease), at once if no other monitor could object.
    if (restart == nullptr && view.master == self && !view.failed.contains(self)) {
        boot_pending_ = true;
        enforce_lease();
        deliver_internal(0);
    }
}

namespace {

// Declarations an exclusion needs in a view (spec/Quorum.tla): a majority of the view's
// members (the monitors it has not excluded, the node decided on among them when it is
// one), but never more than the voters left. Two quorums of one view always share a
// member, so two sides of a partition cannot both decide; with one voter left it decides
// alone, and the lease makes both sides of a 1|1 split stop.
int quorum_needed(int members, int voters) { return std::max(1, std::min(members / 2 + 1, voters)); }

}  // namespace

TimeNs NodeProtocol::lease_expiry_ns() const {
    if (!is_master()) {
        // Joint views (spec/Quorum.tla, rule 3b): a node that is not the Master holds its
        // lease by its view and by the joint views its Command carried, where a node that
        // has not adopted the view yet may decide against it.
        const View& view = switch_.view();
        TimeNs expiry = lease_expiry_ns(view, NodeSet{}, false);
        if (no_joint_views()) return expiry;
        for (const View& joint : switch_.joint()) {
            expiry = std::min(expiry, lease_expiry_ns(joint, view.failed.minus(joint.failed), true));
        }
        return expiry;
    }
    const View& driving = manager_.driving();
    // While a readmission switch is under way, nodes that have not adopted it yet go by
    // the view without the readmitted node, whose quorum may be smaller: the lease must
    // hold by both.
    TimeNs expiry = lease_expiry_ns(driving, NodeSet{}, false);
    if (!joining_.empty()) expiry = std::min(expiry, lease_expiry_ns(driving, joining_, false));
    // Joint views (spec/Quorum.tla): until every node has adopted the view this Master
    // drives, some node may still go by a view the Master left, and decide by its quorum.
    // The lease holds by each of them too; the nodes excluded since were decided on (with
    // evidence in every such view) and do not count against it.
    for (const View& pending : pending_) {
        if (no_joint_views()) break;
        expiry = std::min(expiry, lease_expiry_ns(pending, driving.failed.minus(pending.failed), true));
    }
    return expiry;
}

TimeNs NodeProtocol::lease_expiry_ns(NodeSet without) const {
    return lease_expiry_ns(is_master() ? manager_.driving() : switch_.view(), without, false);
}

TimeNs NodeProtocol::lease_expiry_ns(const View& view, NodeSet without, bool joint) const {
    if (mutant_on(options_.mutant, Mutant::no_lease)) return kForever;
    // The voters: the monitors of the view, but this node and the failed.
    const bool master = is_master() || boot_pending_;
    // A node that said it left (it restarted, resigned, or knows itself excluded) declares
    // no one any more: it is no voter.
    NodeSet voters = topology_->monitors(view).minus(view.failed);
    monitor_.failed().for_each([&](NodeId node) {
        if (!monitor_.forgettable(node)) voters.erase(node);
    });
    const bool member = voters.contains(self_);
    voters.erase(self_);
    const NodeSet all_voters = voters;
    // Where the ground is a member of the view (spec/Designate.tla, rule 1: by the count of
    // the monitors the view has not excluded, as every node of the view counts it), a decider's lease holds by the whole view, as the spec's
    // TakeOverEnabled asks: the nodes it decides on count against it too (the ground's vote
    // for it is what lets it decide in a tie), and so do the nodes a joint view's
    // successor excluded (the tie is the view's).
    const bool ground_view = topology_->tie_grace() > 0 && !strict_lease_ &&
                             ground_counts(view, all_voters.size() + (member ? 1 : 0));
    if (!ground_view) voters = voters.minus(without);
    const TimeNs period = topology_->heartbeat_period_ns();
    const TimeNs window = topology_->miss_limit() * period - period / 4;
    // The send times of this node's last heartbeats each voter acknowledged, the oldest first.
    const auto acknowledged = [&](const NodeSet& of, std::array<TimeNs, kMaxNodes>& acked) {
        int count = 0;
        of.for_each([&](NodeId voter) {
            TimeNs at = monitor_.acked_at(voter);
            // A voter that follows a newer epoch acknowledges no Master of an older one.
            if (master && monitor_.acked_epoch(voter) > election_.epoch()) at = HeartbeatMonitor::kNever;
            acked[static_cast<std::size_t>(count++)] = at;
        });
        std::sort(acked.begin(), acked.begin() + count);
        return count;
    };
    // When the k-th voter (1-based, in acked's order) may hold this node failed.
    const auto stale_at = [&](const std::array<TimeNs, kMaxNodes>& acked, int k) {
        const TimeNs at = acked[static_cast<std::size_t>(k - 1)];
        return at == HeartbeatMonitor::kNever ? HeartbeatMonitor::kNever : at + window;
    };
    std::array<TimeNs, kMaxNodes> acked;  // the first `count` entries only
    const int count = acknowledged(voters, acked);
    TimeNs expiry = kForever;
    if (count > 0) {
        // The lease ends when `needed` voters may declare: at the needed-th oldest
        // acknowledgement plus miss_limit periods, less a margin for this node's own loop.
        // A Master handed the view over holds it only while every voter acknowledges it,
        // until its first switch completes: a voter that has not adopted the view yet still
        // goes by the one that excluded this node, in which it may be the last monitor,
        // able to take over alone (keel-sim found it: an Observer deaf to both Masters
        // missed the hand-over and deposed the old one while the new one drove). Where the
        // ground is a member (spec/Designate.tla, rule 1) it is one voter more, which this
        // count leaves out: it counts by rule 2, below.
        const int members = count + (member ? 1 : 0);
        const int needed = strict_lease_ ? 1
                                         : exclusion_quorum(members + (ground_view ? 1 : 0),
                                                            count + (ground_view ? 1 : 0));
        if (needed <= count) expiry = stale_at(acked, needed);
    }
    // Rule 2 (spec/Designate.tla): in a view with the ground a member, a node is in a tie
    // once one vote more than its stale voters would exclude it; the ground counts with it
    // for tie_grace periods of the tie, then against it, unless the ground's vote is for it
    // (in a joint view, for it or for its Master). Every member of the view counts here,
    // those a later view excluded too: the tie is the view's, and a take-over on the
    // ground's vote leaves it joint for that reason (rule 4).
    if (ground_view && !cluster_only_ && count > 0) {
        // needed >= 2 where the ground is a member (an even count of members, two at least).
        const int needed = exclusion_quorum(count + (member ? 1 : 0) + 1, count + 1);
        const TimeNs tie = stale_at(acked, needed - 1);
        // The vote counts only in a view the ground is a member of by the view's own count
        // (one that shrank to an even number by the nodes that gave their own word here
        // has the ground count against its nodes, never for them).
        const bool voting = view_has_ground(view);
        const bool for_master = voting && joint && switch_.view().master != self_ &&
                                vote_for(switch_.view().master);
        expiry = std::min(expiry, ground_against_from(tie, voting, for_master));
    }
    return expiry;
}

TimeNs NodeProtocol::ground_against_from(TimeNs tie, bool for_self, bool for_master) const {
    const TimeNs grace = topology_->tie_grace() * topology_->heartbeat_period_ns();
    if (mutant_on(options_.mutant, Mutant::designate_no_grace)) return kForever;
    const TimeNs against = tie == HeartbeatMonitor::kNever ? HeartbeatMonitor::kNever : tie + grace;
    // The vote's windows that count for this node: its own, and its Master's as the
    // Master's heartbeats said it (from the past: the Master held it when it said so).
    const auto covered = [&](TimeNs from, TimeNs until) -> std::optional<TimeNs> {
        if (until <= from) return std::nullopt;
        if (now_ >= from && now_ < until) return std::max(against, until);  // held now
        if (against >= from && against < until) return until;            // the grace ends in it
        return std::nullopt;
    };
    TimeNs result = against;
    if (for_self && designation_.node == self_) {
        if (auto until = covered(designation_.from, designation_.until)) result = std::max(result, *until);
    }
    if (for_master && master_vote_node_ == switch_.view().master) {
        if (auto until = covered(std::numeric_limits<TimeNs>::min(), master_vote_until_)) {
            result = std::max(result, *until);
        }
    }
    return result;
}

bool NodeProtocol::vote_for(NodeId node) const {
    if (topology_->tie_grace() <= 0 || node == kNoNode) return false;
    if (node == self_) {
        return designation_.node == self_ && now_ >= designation_.from && now_ < designation_.until;
    }
    return master_vote_node_ == node && now_ < master_vote_until_;
}

bool NodeProtocol::lease_fresh() const {
    const TimeNs expiry = lease_expiry_ns();
    if (expiry == kForever) return true;
    if (expiry <= now_) return false;
    // A period of the lease left at least: time for the next acknowledgements, which a
    // voter sends every period (and in its reply to each heartbeat). Whatever lease a
    // cluster keeps in steady state (an acknowledgement up to miss_limit - 1.25 periods
    // old, the round trip), it boots on.
    return expiry - now_ >= topology_->heartbeat_period_ns();
}

int NodeProtocol::exclusion_quorum(int members, int voters) const {
    // The rule before majority quorums: two declarations, one when one voter is left.
    if (mutant_on(options_.mutant, Mutant::quorum_before_fix)) {
        return voters >= 2 ? 2 : 1;
    }
    return quorum_needed(members, voters);
}

TimeNs NodeProtocol::next_tick_ns() const {
    const TimeNs boundary = monitor_.next_boundary_ns();
    const bool watching = (is_master() && resign_ == Resign::none) ||
                          (!switch_.holding() &&
                           !(switch_.active().empty() && switch_.restoring().empty()));
    if (!watching) return boundary;
    const TimeNs expiry = lease_expiry_ns();
    return expiry > now_ && expiry < boundary ? expiry : boundary;
}

void NodeProtocol::enforce_lease() {
    bool holds = holds_lease();
    if (topology_->tie_grace() > 0) {
        consider_stand_down(!holds && lease_ends_in_tie());
        if (stood_down_ && !holds_vote()) holds = false;
    }
    if (boot_pending_) {
        // Fenced meanwhile (a Command of a newer Master made this node a Worker, or
        // excluded it): there is nothing to boot. Nor when it asked to be excluded
        // meanwhile: its word lets its successor take over without a vote, so it must not
        // start commanding (keel-sim found a resign before the boot switch, then two
        // running Masters for 2.2 s).
        if (election_.role() != Role::Master || switch_.excluded() || switch_.view().master != self_ ||
            resign_ != Resign::none) {
            boot_pending_ = false;
            strict_lease_ = false;
            return;
        }
        // It starts commanding on fresh acknowledgements only: a period of its lease left
        // at least (lease_fresh), time for the next acknowledgements.
        // A lease that merely holds may rest on acknowledgements of its first heartbeats,
        // about to lapse: a slow board (keel-node under qemu-aarch64, whose DDS warms up
        // for a second) started its boot switch 29 ms before its lease lapsed, resigned,
        // and handed the cluster to the next Observer (docs/cross-build.md).
        if (!holds || !lease_fresh()) {
            // Handed a view it cannot get every voter's acknowledgement for: it gives the
            // view up (its own word), and the first Observer of the view takes over.
            const TimeNs patience =
                2 * topology_->miss_limit() * topology_->heartbeat_period_ns();
            if (strict_lease_ && now_ - boot_pending_since_ > patience) {
                boot_pending_ = false;
                strict_lease_ = false;
                ++stats_.hand_overs_given_up;
                resign(now_);
            }
            return;
        }
        boot_pending_ = false;
        const View& view = switch_.view();
        manager_.boot_as_master(view);
        switch_.boot_as_master();
        start_switch(manager_.boot_switch(out_));
        return;
    }
    if (is_master()) {
        if (holds && switch_.holding()) {
            // An Observer that held its tasks, then took over.
            if (!switch_.active().empty()) ++stats_.lease_releases;
            switch_.release(out_);
        }
        if (holds || resign_ != Resign::none) return;
        ++stats_.lease_step_downs;
        if (out_.tracing()) {
            out_.trace("switch", "LeaseLapsed",
                       JsonObject().field("n", topology_->node_name(self_)).str(), "{}");
        }
        resign(now_);
        return;
    }
    // Tasks running, or about to (a checkpoint on its way: a paused node reads its queue).
    const bool has_tasks = !switch_.active().empty() || !switch_.restoring().empty();
    // A node that asked to be excluded stops its tasks at once: the Master moves them as
    // soon as it reads the request, maybe before its Command reaches this node.
    if (resign_ == Resign::asked) {
        if (!switch_.holding() && has_tasks) {
            ++stats_.lease_holds;
            switch_.hold(out_);
        }
        return;
    }
    // Without a lease the node holds even with nothing to run yet: what a Command
    // activates meanwhile starts only with the lease (no start-stop-start at boot).
    if (!holds && !switch_.holding()) {
        if (has_tasks) ++stats_.lease_holds;
        switch_.hold(out_);
    } else if (holds && switch_.holding()) {
        if (has_tasks) ++stats_.lease_releases;
        switch_.release(out_);
    }
}

std::vector<Action> NodeProtocol::take_ready() {
    std::vector<Action> ready;
    ready.swap(out_.actions());
    return ready;
}

void NodeProtocol::take_ready(std::vector<Action>& into) {
    into.clear();
    into.swap(out_.actions());
}

PersistentState NodeProtocol::persistent_state() const {
    PersistentState state;
    state.epoch = election_.epoch();
    state.view = switch_.view();
    state.incarnation = monitor_.incarnation();
    state.boot = monitor_.boot();
    state.held_out = held_out_;
    state.paused = switch_.paused();
    if (store_) state.checkpoints = store_->records();
    return state;
}

void NodeProtocol::step(const Message& message, TimeNs now) {
    assert(now >= now_);
    now_ = now;
    // A node that flies another mission image (its heartbeats say so) reads ids by another
    // mission: it takes no part here, and is declared for its silence as any. Before the
    // bounds below: its ids are its mission's, which is no refusal (an honest node of
    // another image is no value fault).
    if (const NodeId from = sender_of(message);
        options_.image != 0 && from != self_ && from < topology_->node_count()) {
        if (const auto* heartbeat = std::get_if<Heartbeat>(&message); heartbeat != nullptr && heartbeat->image != 0) {
            foreign_image_[from] = heartbeat->image != options_.image ? heartbeat->image : 0;
        }
        if (foreign_image_[from] != 0) {
            ++stats_.foreign_image;
            return;
        }
    }
    // Fault model 3: no id from the wire reaches a state machine unless the mission has it.
    if (!mutant_on(options_.mutant, Mutant::no_receiver_checks)) {
        if (auto problem = out_of_mission(message, *topology_)) {
            refuse(stats_.malformed[message.index()], message, *problem);
            return;
        }
    }
    const std::size_t start = out_.actions().size();
    step_down_if_stalled();
    enforce_lease();
    handle(message);
    enforce_lease();
    deliver_internal(start);
}

void NodeProtocol::tick(TimeNs now) {
    assert(now >= now_);
    now_ = now;
    const std::size_t start = out_.actions().size();
    note_epoch();
    enforce_lease();
    if (now < monitor_.next_boundary_ns()) {
        deliver_internal(start);
        return;
    }
    step_down_if_stalled();
    advance_resign();
    monitor_.set_waiting(restarted_ && !commanded_);
    note_vote_left();
    const NodeSet declared =
        monitor_.period_boundary(now, election_.epoch(), left_cluster(), out_);
    declared.for_each([&](NodeId node) { handle_declared(node); });
    if (is_master()) {
        // Evidence may have grown without a new message (a voter was excluded, leaving the
        // Master the last monitor): what this Master holds failed is considered again.
        monitor_.failed().minus(manager_.driving().failed).for_each([&](NodeId node) {
            consider_exclusion(node);
        });
    }
    reports_before_.swap(reports_now_);
    std::fill(reports_now_.begin(), reports_now_.end(), NodeSet{});
    note_declarations();
    step_down_if_cut_off();
    consider_readmission();
    repeat_hand_over();
    consider_warm_boot();
    // A node cut off from everyone suspected everyone. When it hears again, the first
    // heartbeats may come from anyone: it does not take over for two periods, in which the
    // Master it suspects is heard (the suspicion is withdrawn on its heartbeat) or fences
    // it; a Master that really died stays suspected and is succeeded two periods later.
    if (monitor_.silent_periods() >= topology_->miss_limit()) {
        isolated_ = true;
    } else if (isolated_ && monitor_.silent_periods() == 0) {
        isolated_ = false;
        rejoin_hold_ = 2;
    } else if (rejoin_hold_ > 0) {
        --rejoin_hold_;
    }
    // A newer epoch whose owner this Master declared failed, and which stayed unheard for
    // miss_limit periods since: the newer Master is gone, and the nodes that followed it
    // reject everything older, so this Master moves past it.
    if (newer_epoch_ != 0) {
        const TimeNs window = topology_->miss_limit() * topology_->heartbeat_period_ns();
        const NodeId owner = topology_->owner(newer_epoch_);
        if (!is_master() || newer_epoch_ <= election_.epoch() || last_heard_[owner] >= newer_epoch_since_) {
            newer_epoch_ = 0;  // stepped down, overtaken, or the owner is alive: its fencing decides
        } else if (now - newer_epoch_since_ >= window) {
            if (topology_->next_epoch(self_, newer_epoch_) > max_adoptable_epoch(*topology_)) {
                // No epoch a node would adopt is left above it (the width): every other
                // node would refuse this Master's Commands as proof. It stays where it is.
                ++stats_.take_overs_refused;
            } else {
                const Epoch claimed = election_.reclaim(newer_epoch_, out_);
                start_switch(manager_.reclaim(claimed, out_));
            }
            newer_epoch_ = 0;
        }
    }
    declare_master_left();
    time_pass_over();
    // What this node hears changes (a partition heals): the succession is re-examined.
    if (!switch_.excluded() && resign_ == Resign::none &&
        election_.may_take_over(switch_.view(), may_act(), diverged())) {
        take_over();
    }
    if (restarted_ && !commanded_) announce_restart();
    // A node that asked to be excluded repeats it until a view excluding it arrives.
    if (resign_ == Resign::asked && !switch_.excluded() && switch_.view().master != self_) {
        announce_own_exclusion();
    }
    // Observers repeat what they declared until the Master's view shows it: a lost
    // ErrorNotification must not leave a failure unhandled.
    if (election_.role() == Role::Observer && !switch_.excluded() && resign_ != Resign::flushing &&
        resign_ != Resign::done) {
        const View& view = switch_.view();
        monitor_.failed().minus(view.failed).for_each([&](NodeId node) { report_declared(node); });
    }
    exclude_held_out();
    switch_.tick(election_.epoch(), out_);
    start_queued_phase();
    enforce_lease();
    deliver_internal(start);
}

void NodeProtocol::task_stepped(TaskId task, std::vector<std::uint8_t> state, TimeNs now) {
    assert(now >= now_);
    now_ = now;
    const std::size_t start = out_.actions().size();
    // The step ran before this node learned of it: it is recorded first, and the lease is
    // judged after (a lease that lapsed meanwhile holds the task from now on; trace
    // validation takes no step of a node after its Hold line).
    switch_.task_stepped(task, std::move(state), election_.epoch(), out_);
    enforce_lease();
    deliver_internal(start);
}

std::string NodeProtocol::request_recovery(ConfigId target, TimeNs now) {
    assert(now >= now_);
    now_ = now;
    const std::size_t start = out_.actions().size();
    enforce_lease();
    std::string why;
    if (!is_master()) {
        why = "this node is not the Master";
    } else if (switch_.master_stage() != MasterStage::Idle) {
        why = "a switch is under way; send the command again once it completes";
    } else if (auto next = manager_.ground_recovery(target, &why, out_)) {
        start_switch(*next);
    }
    if (!why.empty() && out_.tracing()) {
        out_.trace("switch", "RefuseGroundCommand",
                   JsonObject()
                       .field("m", topology_->node_name(self_))
                       .field("c", target == kSafeConfig || static_cast<int>(target) >= topology_->config_count()
                                       ? std::string("?")
                                       : topology_->config_name(target))
                       .field("why", why)
                       .str(),
                   "{}");
    }
    deliver_internal(start);
    return why;
}

void NodeProtocol::request_phase(PhaseId phase, TimeNs now) {
    assert(now >= now_);
    now_ = now;
    const std::size_t start = out_.actions().size();
    handle(PhaseRequest{kNoNode, phase});
    deliver_internal(start);
}

bool NodeProtocol::ground_exclusion_reaches_safe(const View& view, NodeId node) const {
    // `node` first (the edge a Master's exclusion takes), then, in id order, a pending
    // real failure (declared by this node's monitor, not excluded yet: a node that resigned
    // says so in its heartbeats) and the nodes held out already that the view has not
    // excluded (an earlier exclude under way): judged together (spec/Ground.tla,
    // GroundWalkOk). An acting Master leaves itself out: it is never excluded by its own
    // switch.
    std::vector<NodeId> path{node};
    NodeSet failed = view.failed;
    failed.insert(node);
    (monitor_.failed() | held_out_).minus(failed).for_each([&](NodeId x) {
        if (x == self_ && is_master()) return;
        path.push_back(x);
        failed.insert(x);
    });
    NodeSet alone = view.failed;
    alone.insert(node);
    if (view.is_online() || topology_->phase(topology_->phase_of(view)).placement != mission::PlacementMode::graph) {
        // The Master's answer where the phase places online (online.hpp): the graph's walk,
        // then the placer, for the same failures.
        if (failure_target(*topology_, view, path, failed, kNoNode).is_safe()) return true;
        return failure_target(*topology_, view, {node}, alone, node == view.master ? kNoNode : view.master)
            .is_safe();
    }
    if (topology_->walk(view.config, path, failed).config == kSafeConfig) return true;
    // The edge for `node` alone, as the Master's switch takes it: safe mode, or (for a
    // node other than the Master, which steps down for its successor) a configuration of
    // another Master, which the Master's switch turns into safe mode.
    const ConfigId next = topology_->walk(view.config, {node}, alone).config;
    return next == kSafeConfig || (node != view.master && topology_->config(next).master != view.master);
}

std::string NodeProtocol::ground_exclude(NodeId node, TimeNs now) {
    assert(now >= now_);
    assert(node < topology_->node_count());
    now_ = now;
    const std::size_t start = out_.actions().size();
    const View& view = switch_.view();
    if (!view.failed.contains(node) && view.config != kSafeConfig &&
        ground_exclusion_reaches_safe(view, node)) {
        return "the decision graph's edges for " + topology_->node_name(node) +
               " and the nodes failed or held out already that the view has not excluded, from " +
               topology_->config_name(view.config) +
               ", lead to safe mode: the ground takes no node out beyond the mission's tolerance";
    }
    held_out_.insert(node);
    if (out_.tracing()) {
        out_.trace("switch", "GroundExclude", JsonObject().field("f", topology_->node_name(node)).str(),
                   switch_.vars_json());
    }
    if (node == self_ && is_master()) {
        // The acting Master's view is the one the cluster switches from: it steps down.
        resign(now);
        return {};
    }
    // Any other node is excluded by the acting Master's switch, after the Master's own
    // walk from its view (a node's own view may be behind the Master's).
    exclude_held_out();
    deliver_internal(start);
    return {};
}

void NodeProtocol::exclude_held_out() {
    // As consider_readmission: an idle Master that holds its lease, no phase change queued.
    // Not in safe mode (beyond the tolerance already: the ground's hold waits for a
    // recovery, spec/Ground.tla).
    if (!is_master() || resign_ != Resign::none || queued_phase_ ||
        switch_.master_stage() != MasterStage::Idle || !holds_lease()) {
        return;
    }
    const View& view = manager_.driving();
    if (view.is_safe()) return;
    std::optional<NodeId> next;
    bool withheld = false;
    held_out_.minus(view.failed).for_each([&](NodeId held) {
        if (held == self_ || next) return;
        if (ground_exclusion_reaches_safe(view, held)) {
            withheld = true;
        } else {
            next = held;
        }
    });
    if (!next) {
        if (withheld) ++stats_.ground_exclusions_withheld;
        return;
    }
    if (auto switched = manager_.exclude(*next, Evidence::ground_hold(), out_)) start_switch(*switched);
}

std::string NodeProtocol::ground_readmit(NodeId node, TimeNs now) {
    assert(now >= now_);
    assert(node < topology_->node_count());
    now_ = now;
    if (!held_out_.contains(node)) return topology_->node_name(node) + " is not held out by the ground";
    held_out_.erase(node);
    if (out_.tracing()) {
        out_.trace("switch", "GroundReadmit", JsonObject().field("f", topology_->node_name(node)).str(),
                   switch_.vars_json());
    }
    return {};
}

std::string NodeProtocol::ground_pause(TaskId task, TimeNs now) {
    assert(now >= now_);
    assert(task < topology_->task_count());
    now_ = now;
    const std::string& name = topology_->task(task).name;
    if (topology_->task(task).essential) return name + " is essential: it always runs, and is never paused";
    if (!switch_.pause(task, out_)) return name + " is paused already";
    return {};
}

std::string NodeProtocol::ground_resume(TaskId task, TimeNs now) {
    assert(now >= now_);
    assert(task < topology_->task_count());
    now_ = now;
    if (!switch_.resume(task, out_)) return topology_->task(task).name + " is not paused";
    return {};
}

void NodeProtocol::resign(TimeNs now) {
    assert(now >= now_);
    now_ = now;
    if (resign_ != Resign::none || switch_.excluded()) return;
    const std::size_t start = out_.actions().size();
    if (!is_master()) {
        resign_ = Resign::asked;
        if (out_.tracing()) {
            out_.trace("switch", "AskExclusion",
                       JsonObject().field("n", topology_->node_name(self_)).str(), switch_.vars_json());
        }
        announce_own_exclusion();
        enforce_lease();  // its tasks stop now
        deliver_internal(start);
        return;
    }
    // The Master steps down: no more decisions, nothing runs here, final checkpoints out.
    resign_ = Resign::flushing;
    resign_deadline_ns_ = now + topology_->miss_limit() * topology_->heartbeat_period_ns();
    manager_.step_down();
    joining_ = NodeSet{};
    pending_.clear();
    strict_lease_ = false;
    queued_phase_.reset();
    switch_.resign(out_);
    update_watch();
    advance_resign();
    deliver_internal(start);
}

void NodeProtocol::advance_resign() {
    if (resign_ != Resign::flushing) return;
    const bool flushed = switch_.unflushed().empty();
    if (!flushed && now_ < resign_deadline_ns_) return;
    if (!flushed) switch_.abandon_flushes();
    resign_ = Resign::done;
    if (out_.tracing()) {
        out_.trace("switch", "Resigned",
                   JsonObject().field("n", topology_->node_name(self_)).field("flushed", flushed).str(),
                   switch_.vars_json());
    }
}

void NodeProtocol::refuse(std::uint64_t& counter, const Message& message, const std::string& why) {
    refuse(counter, kind_name(message), sender_of(message), why);
}

void NodeProtocol::refuse(std::uint64_t& counter, std::string_view kind, NodeId from, const std::string& why) {
    ++counter;
    const std::string sender = static_cast<int>(from) < topology_->node_count() ? topology_->node_name(from)
                                                                               : "node " + std::to_string(from);
    last_refusal_ = std::string(kind) + " from " + sender + ": " + why;
    // Rules 1 to 3 on the trace: a refusal (malformed, unauthorized, no Master's, another
    // view under one id) is a line, which trace validation rejects: every node of a
    // validated run is honest, so a refusal there is a check wrong about an honest message
    // (keel-sim's NoHonestRefusalInv, on keel-node's traces too). An epoch ahead and an
    // exclusion not backed yet are no refusals: an honest switch may meet them, as a node
    // that restarted meets a hand-over meant for its boot before.
    if (out_.tracing() && &counter != &stats_.ahead_dropped && &counter != &stats_.commands_unbacked &&
        &counter != &stats_.hand_overs_stale) {
        out_.trace("switch", "Refused",
                   JsonObject()
                       .field("n", topology_->node_name(self_))
                       .field("kind", std::string(kind))
                       .field("from", sender)
                       .field("why", why)
                       .str(),
                   switch_.vars_json());
    }
}

void NodeProtocol::handle(const Message& message) {
    // Any message proves its sender alive, stale or not: it ends the sender's start-up
    // grace (heartbeats do so in receive_heartbeat). A node that dies right after the boot
    // switch, before its first heartbeat, is then declared after miss_limit periods.
    if (!std::holds_alternative<Heartbeat>(message)) monitor_.heard_from(sender_of(message));
    if (sender_of(message) < topology_->node_count()) last_message_[sender_of(message)] = now_;
    // The one place where stale epochs are rejected (raft's Step).
    if (has_epoch(message) && election_.is_stale(epoch_of(message))) {
        ++stats_.stale_rejected;
        return;
    }
    // No epoch more than a lap of the succession above this node's (fault model 3): only
    // a Command may bring one (command_problem says when), and nothing else of an epoch
    // this node has not adopted is acted on.
    note_epoch();
    const bool checks = !mutant_on(options_.mutant, Mutant::no_receiver_checks);
    if (checks && has_epoch(message) && !std::holds_alternative<Command>(message) &&
        epoch_of(message) > adoptable_epoch()) {
        ++stats_.ahead_dropped;  // an honest node far ahead sends it too: no refusal
        return;
    }
    const Epoch epoch = election_.epoch();
    std::visit(
        Overloaded{
            [&](const Heartbeat& heartbeat) {
                // A heartbeat of a boot whose sender has booted again since (overtaken on
                // the way): that process is gone, nothing it said counts.
                if (monitor_.retired_boot(heartbeat)) {
                    ++stats_.retired_boot_heartbeats;
                    return;
                }
                // A heartbeat of this node's Master that says `excluded` from an epoch below
                // the one that Master's Command opened here was sent before that Command
                // (overtaken on the way): a warm-booting Master that knew itself excluded
                // before the power cycle says so until it commands. It is no word of that
                // Master's now, and read as one it deposes the Master at once (keel-sim
                // --ground-designates, earth-observation tie_grace seed 3653: two running
                // Masters for 6 ms). Dropped unread. Only with tie_grace so far, where it was found; a
                // mission without it keeps the rule it was validated under.
                if (topology_->tie_grace() > 0 && heartbeat.excluded && heartbeat.from == switch_.view().master &&
                    heartbeat.from != self_ && heartbeat.epoch < switch_.view().epoch &&
                    !switch_.view().failed.contains(heartbeat.from)) {
                    ++stats_.stale_rejected;
                    return;
                }
                monitor_.set_excluded(left_cluster());  // what its reply says
                monitor_.set_waiting(restarted_ && !commanded_);
                if (heartbeat.from < topology_->node_count()) {
                    // Waiting, or out of the cluster by its own knowledge (fenced, excluded):
                    // either way it is no Master and claims no epoch (consider_warm_boot).
                    const bool idle = heartbeat.waiting ||
                                      (heartbeat.excluded && !mutant_on(options_.mutant, Mutant::warm_boot_waiting_only));
                    heard_waiting_[heartbeat.from] = idle;
                    if (idle) waiting_epoch_[heartbeat.from] = heartbeat.epoch;
                }
                note_vote_left();  // what its reply says
                const NodeId restarted = monitor_.receive_heartbeat(heartbeat, epoch, now_, out_);
                note_master_left(heartbeat);
                note_master_vote(heartbeat);
                // A restart or a self-declared exclusion is the node's own word: no more
                // evidence is needed. (Also for a node this Master had declared and was
                // waiting for evidence on: the monitor no longer watches it, but it marks the
                // declaration permanent.)
                if (restarted != kNoNode) {
                    if (is_master()) {
                        if (auto next = manager_.exclude(restarted, Evidence::own_word(), out_)) {
                            start_switch(*next);
                        }
                    } else {
                        handle_declared(restarted);
                    }
                } else if (is_master() && heartbeat.from < topology_->node_count() &&
                           monitor_.failed().contains(heartbeat.from) &&
                           !monitor_.forgettable(heartbeat.from) &&
                           !manager_.driving().failed.contains(heartbeat.from)) {
                    if (auto next = manager_.exclude(heartbeat.from, Evidence::own_word(), out_)) {
                        start_switch(*next);
                    }
                }
                // A monitor hears a node it declared and the cluster has not excluded: the
                // declaration was wrong and is withdrawn (an Observer's suspicion, or the
                // Master's declaration that lacked a second monitor's evidence).
                if (restarted == kNoNode && !heartbeat.excluded &&
                    heartbeat.from < topology_->node_count() &&
                    (is_master() || election_.suspects().contains(heartbeat.from)) &&
                    monitor_.forgettable(heartbeat.from) &&
                    !switch_.view().failed.contains(heartbeat.from) &&
                    !(is_master() && manager_.driving().failed.contains(heartbeat.from))) {
                    election_.clear_suspect(heartbeat.from);
                    monitor_.forget(heartbeat.from, out_);
                    update_watch();
                }
                // Alive as a possible fencer: not excluded, and not known to have restarted
                // since (a restarted Master is a Worker and fences no one).
                // (A waiting or excluded node takes no part in a succession: none recorded.)
                if (heartbeat.from < topology_->node_count()) {
                    latest_epoch_[heartbeat.from] = heartbeat.waiting || heartbeat.excluded ? 0 : heartbeat.epoch;
                    note_master_heard(heartbeat);
                }
                if (heartbeat.from < topology_->node_count() &&
                    static_cast<std::int64_t>(heartbeat.epoch) > heard_epoch_[heartbeat.from]) {
                    heard_epoch_[heartbeat.from] = heartbeat.epoch;
                    heard_epoch_at_[heartbeat.from] = now_;
                }
                if (heartbeat.from < topology_->node_count() && !heartbeat.excluded &&
                    !(monitor_.failed().contains(heartbeat.from) && !monitor_.forgettable(heartbeat.from))) {
                    last_heard_[heartbeat.from] = now_;
                }
                // An epoch beyond a lap of the succession above this Master's is no epoch a
                // take-over opens (fault model 3): the heartbeat counts as heard, its epoch
                // is not used. Counted as ahead, not refused: a heartbeat says the highest
                // epoch its sender adopted, and an honest node may have followed a Command
                // this Master has not seen (keel-sim --liar, prototype3 seed 2227: PN3
                // followed the liar PN1's epoch 7 just as PN2 took over epoch 2).
                if (checks && is_master() && heartbeat.epoch > adoptable_epoch()) ++stats_.ahead_dropped;
                // A newer epoch whose Master this one has declared failed: noted here, moved
                // past in tick() once its owner stayed unheard (see newer_epoch_). Or one of
                // this Master's own that it never opened: a hand-over made in its name by a
                // Master it had already replaced, which only a value-faulty one sends (keel-sim
                // --liar, earth-observation seed 25282: PN4 followed PN1's hand-over of epoch 6
                // to PN2, Master of epoch 2, and prepared for none of PN2's switches).
                if (is_master() && heartbeat.epoch > election_.epoch() &&
                    heartbeat.epoch > newer_epoch_ &&
                    (!checks || heartbeat.epoch <= adoptable_epoch()) &&
                    (manager_.driving().failed.contains(topology_->owner(heartbeat.epoch)) ||
                     (checks && topology_->owner(heartbeat.epoch) == self_))) {
                    newer_epoch_ = heartbeat.epoch;
                    newer_epoch_since_ = now_;
                }
                // Fencing: a node the Master excluded is still talking; tell it so that
                // it stops whatever it still runs. Once it says it knows (it adopted a view
                // of this epoch that excludes it), it is on its way back (reintegration).
                if (is_master() && manager_.driving().failed.contains(heartbeat.from)) {
                    if (heartbeat.excluded && heartbeat.epoch >= election_.epoch()) {
                        // A streak of heartbeats no more than two periods apart (one lost,
                        // or delayed across a boundary, does not break it).
                        const TimeNs gap = 2 * topology_->heartbeat_period_ns();
                        if (now_ - rejoin_last_[heartbeat.from] > gap) rejoin_since_[heartbeat.from] = now_;
                        rejoin_last_[heartbeat.from] = now_;
                    }
                    out_.send(heartbeat.from, Command{self_, manager_.driving(), pending_});
                }
            },
            [&](const Command& command) { handle_command(command); },
            [&](const ActivateCommand& activate) {
                // Only the Master of the view the Activate is for (authority table).
                const View& view = switch_.view();
                if (checks && activate.epoch == view.epoch && activate.seq == view.seq &&
                    activate.from != view.master) {
                    refuse(stats_.unauthorized[message.index()], message,
                           "only " + topology_->node_name(view.master) + ", the view's Master, activates it");
                    return;
                }
                switch_.receive_activate(activate, epoch, out_);
            },
            [&](const Ack& ack) {
                note_divergence(ack);
                switch_.receive_prepared(ack, out_);
                if (switch_.receive_ack(ack, out_)) {
                    ++stats_.switches_completed;
                    strict_lease_ = false;  // every node has adopted this Master's epoch
                    joining_ = NodeSet{};  // every node has adopted the readmission
                    pending_.clear();      // and the view: no node goes by an older one
                    keep_tie_view();       // but the one a decision on the ground's vote left joint
                    start_queued_phase();
                }
            },
            [&](const ErrorNotification& notification) {
                // Only monitors (processing nodes) declare others; any node may ask for its
                // own exclusion (authority table).
                if (checks && notification.failed_node != notification.from &&
                    !topology_->processing_nodes().contains(notification.from)) {
                    refuse(stats_.unauthorized[message.index()], message,
                           "only a processing node declares another node failed");
                    return;
                }
                // A node this Master's view holds failed (a partition that healed) repeats
                // what it declared while it was cut off: those are not evidence, and acting
                // on them excludes nodes that are alive.
                if (switch_.view().failed.contains(notification.from)) return;
                if (!is_master()) {
                    // A report: the backing of an exclusion a Command may add (rule 5),
                    // and an Observer's report on a monitor ahead in the succession,
                    // evidence for a take-over (fault model 2). A node asking for its own
                    // exclusion backs it, and is no evidence for a take-over.
                    note_report(notification.from, notification.failed_node);
                    if (notification.failed_node == notification.from) return;
                    if (election_.role() == Role::Observer && !switch_.excluded() &&
                        resign_ == Resign::none && election_.may_take_over(switch_.view(), may_act(), diverged())) {
                        take_over();
                    }
                    return;
                }
                if (notification.failed_node == notification.from) {
                    // A node asks to be excluded (resign): its own word is enough.
                    if (auto next = manager_.exclude(notification.from, Evidence::own_word(), out_)) {
                        start_switch(*next);
                    }
                    return;
                }
                note_report(notification.from, notification.failed_node);
                consider_exclusion(notification.failed_node);
            },
            [&](const CheckpointWrite& write) {
                // A state's lineage names the view that opened it: never one of an epoch
                // newer than its writer's (a version from the future would pin the task).
                if (checks && lineage_epoch(write.version.lineage) > write.epoch) {
                    refuse(stats_.unauthorized[message.index()], message,
                           "lineage of epoch " + std::to_string(lineage_epoch(write.version.lineage)) +
                               " is newer than its writer's epoch " + std::to_string(write.epoch));
                    return;
                }
                // Nor of an epoch this Storage node has not adopted yet: no view opened it
                // here. A liar's claim of a newer epoch would otherwise store it, and every
                // honest host restoring it would write from the future (keel-sim --liar,
                // prototype3 seeds 244 and 1544). An honest host ahead
                // (a switch under way) writes again: its flushes repeat until acknowledged.
                if (checks && store_ && lineage_epoch(write.version.lineage) > election_.epoch()) {
                    ++stats_.ahead_dropped;
                    return;
                }
                if (store_) store_->receive_write(write, out_);
            },
            [&](const CheckpointAck& ack) {
                // Only the Storage node acknowledges a flush (authority table): an ack from
                // any other node would clear state nothing holds.
                if (checks && ack.from != topology_->storage_node()) {
                    refuse(stats_.unauthorized[message.index()], message, "only the Storage node acknowledges a checkpoint");
                    return;
                }
                switch_.receive_checkpoint_ack(ack, out_);
                advance_resign();
            },
            [&](const CheckpointRequest& request) {
                if (store_) {
                    store_->receive_request(request, switch_.view(), now_, out_);
                } else {
                    switch_.answer_checkpoint_request(request, now_, out_);
                }
            },
            [&](const CheckpointReply& reply) {
                // A task's state comes only from the Storage node or from a node the mission
                // may place the task on (authority table). Another node's reply still
                // answers its request, as holding nothing: a restore waits for no one.
                // A holder's state of a lineage newer than the request's epoch is of no use
                // to it: its new host's writes would be versions from the future, which the
                // Storage node refuses (a liar's; or the request is stale, overtaken by a
                // newer Master, and an honest holder far ahead answers so too: dropped, not
                // refused). Not the Storage node's: it stores no lineage of an epoch it has
                // not adopted, and after a --cold-start it holds the cluster's kept states,
                // whose lineages may be of any earlier epoch.
                const bool foreign = reply.found && reply.from != topology_->storage_node() &&
                                     !topology_->may_host(reply.task).contains(reply.from);
                const bool future = reply.found && reply.from != topology_->storage_node() &&
                                    lineage_epoch(reply.version.lineage) > reply.epoch;
                if (checks && (foreign || future)) {
                    if (foreign) {
                        refuse(stats_.unauthorized[message.index()], message,
                               "the mission never places " + topology_->task(reply.task).name + " on its sender");
                    } else {
                        ++stats_.ahead_dropped;
                    }
                    CheckpointReply empty = reply;
                    empty.found = false;
                    empty.version = Version{};
                    empty.state.clear();
                    switch_.receive_checkpoint_reply(empty, epoch, out_);
                    return;
                }
                switch_.receive_checkpoint_reply(reply, epoch, out_);
            },
            [&](const PhaseRequest& request) {
                // Phase requests come from the Master's own timeline or from the ground,
                // whose commands every node checks itself (the operator's signature,
                // core/node/ground.hpp) and hands to its own NodeProtocol (request_phase).
                // No node speaks for the ground: one from the wire is nobody's to send.
                if (request.from != kNoNode) {
                    refuse(stats_.unauthorized[message.index()], message,
                           "a phase request comes from the Master's timeline or the ground, never from "
                           "another node");
                    return;
                }
                if (request.phase >= topology_->phase_count()) return;
                // The initial Master waiting for its lease keeps it for after the boot switch.
                if (is_master() || boot_pending_) {
                    queued_phase_ = request.phase;
                    start_queued_phase();
                }
            },
        },
        message);
}

void NodeProtocol::handle_command(const Command& command) {
    // A command comes from the master it names, but for a hand-over: the Master of this
    // node's view gives its next epoch's first view to the node that view names.
    const bool hand_over = command.view.master != command.from &&
                           command.view.master < topology_->node_count() &&
                           command.view.seq == 0 &&
                           topology_->owner(command.view.epoch) == command.view.master &&
                           command.from == switch_.view().master;
    if (command.from >= topology_->node_count() ||
        (command.view.master != command.from && !hand_over) ||
        command.view.config == kNoConfig || command.view.base == kNoConfig) {
        return;  // malformed
    }
    // A hand-over goes only to the nodes its view keeps (NodeProtocol's readmission): one
    // that excludes its receiver fences it in another node's name, which only a
    // value-faulty Master does (keel-sim --liar, prototype3 seed 119042: PN3, fenced so,
    // then refused the named Master's real Commands as proof against it).
    if (hand_over && command.view.failed.contains(self_) &&
        !mutant_on(options_.mutant, Mutant::no_receiver_checks)) {
        refuse(stats_.unauthorized[kCommandIndex], "Command", command.from,
               "a hand-over never excludes its receiver");
        return;
    }
    // A hand-over names the boot of its receiver: one meant for a boot of this node that
    // ended (it restarted within the hand-over's repeats) is not this boot's to take. The
    // other nodes of the view adopt it as sent; the monitors' restart declaration of this
    // node lets the first Observer take over from it (keel-sim --disk-faults
    // master-power-loss, prototype3 seed 3: PN1 lost power just after PN2 handed it the
    // view, took the repeat in its next boot and was Master of epoch 7 for 27 ms beside
    // PN2's epoch 8).
    if (hand_over && command.view.master == self_ && command.boot != monitor_.boot() &&
        !mutant_on(options_.mutant, Mutant::hand_over_any_boot)) {
        refuse(stats_.hand_overs_stale, "Command", command.from,
               "a hand-over to boot " + std::to_string(command.boot) + " of this node, which is in boot " +
                   std::to_string(monitor_.boot()));
        return;
    }
    // A Master that resigned takes part again only by being excluded: its heartbeats say
    // so, and the Master of this Command will exclude it at once. Once excluded, a view
    // that readmits it brings it back.
    if ((resign_ == Resign::flushing || resign_ == Resign::done) &&
        !command.view.failed.contains(self_) && !switch_.excluded()) {
        return;
    }
    if (!switch_.would_adopt(command.view)) {
        switch_.receive_command(command, election_.epoch(), out_);  // duplicate: re-ack
        return;
    }
    // Fault model 3: the receiver checks its Master before it adopts anything.
    Verdict verdict = Verdict::unauthorized;
    std::vector<Backing> backing;
    if (auto problem = command_problem(command, &verdict, &backing)) {
        if (verdict == Verdict::proof) {
            refuse(stats_.commands_refused, "Command", command.from, *problem);
            // An honest Master never sends it: its sender is failed, on this node's word.
            monitor_.declare_wrong(command.from, out_);
            handle_declared(command.from);
        } else if (verdict == Verdict::unbacked) {
            refuse(stats_.commands_unbacked, "Command", command.from, *problem);
        } else if (verdict == Verdict::ahead) {
            refuse(stats_.ahead_dropped, "Command", command.from, *problem);
        } else {
            refuse(stats_.unauthorized[kCommandIndex], "Command", command.from, *problem);
        }
        return;
    }
    const bool was_excluded = switch_.excluded();
    const NodeSet readmitted = switch_.view().failed.minus(command.view.failed);
    commanded_ = true;
    if (!command.view.failed.contains(self_)) vetted_ = command.view;
    // Rule 5 on the trace: what backed each exclusion this node checked, before it adopts
    // the view (TraceConfigSwitch's BackedLine holds each to the lines before it).
    if (out_.tracing() && !backing.empty()) {
        JsonObject by;
        for (const Backing& b : backing) {
            by.raw(topology_->node_name(b.node),
                   std::string("[\"") + b.kind + "\",\"" +
                       (b.by < topology_->node_count() ? topology_->node_name(b.by) : std::string("none")) + "\"]");
        }
        out_.trace("switch", "Backed",
                   JsonObject()
                       .field("n", topology_->node_name(self_))
                       .field("from", topology_->node_name(command.from))
                       .field("epoch", command.view.epoch)
                       .field("seq", command.view.seq)
                       .raw("by", by.str())
                       .str(),
                   switch_.vars_json());
    }
    if (stood_down_ && command.view.epoch > stood_down_epoch_) end_stand_down("command");
    election_.receive_command(command, out_);
    switch_.set_role(election_.role());
    if (command.from != self_) monitor_.forget(command.from, out_);
    switch_.receive_command(command, election_.epoch(), out_);
    if (command.from != self_ && topology_->tie_grace() > 0) adopt_tie_view(command.joint);
    if (election_.role() != Role::Master && manager_.active()) {
        manager_.step_down();
        joining_ = NodeSet{};
        pending_.clear();
        strict_lease_ = false;
        switch_.step_down();
        queued_phase_.reset();
    }
    if (store_) store_->set_view(switch_.view());
    // Reintegration: what was counted and declared of a readmitted node is forgotten; a
    // node readmitted itself forgets what it declared while out, and takes part again.
    readmitted.for_each([&](NodeId node) {
        monitor_.readmit(node, command.view.epoch, out_);
        election_.clear_suspect(node);
        reports_now_[node] = NodeSet{};
        reports_before_[node] = NodeSet{};
    });
    if (was_excluded && !switch_.excluded()) {
        resign_ = Resign::none;
        monitor_.forget_declarations(switch_.view().failed, command.view.epoch, out_);
        election_.suspects().for_each([&](NodeId node) { election_.clear_suspect(node); });
        std::fill(reports_now_.begin(), reports_now_.end(), NodeSet{});
        std::fill(reports_before_.begin(), reports_before_.end(), NodeSet{});
        isolated_ = false;
        rejoin_hold_ = 0;
        cut_off_periods_ = 0;
    }
    // Handed the view over: this node drives it once it holds its lease (enforce_lease).
    if (election_.role() == Role::Master && !manager_.active() && switch_.view().master == self_ &&
        switch_.view().seq == 0) {
        boot_pending_ = true;
        strict_lease_ = true;
        boot_pending_since_ = now_;
    }
    update_watch();
    // A Command read late (a paused node's queue) clears the Election's suspicions, but a
    // node that said it left (resigned, restarted, excluded) stays declared: suspect it
    // again, or no one would ever take over from a Master that resigned meanwhile.
    if (election_.role() == Role::Observer) {
        monitor_.failed().minus(switch_.view().failed).for_each([&](NodeId node) {
            if (!monitor_.forgettable(node) && !election_.suspects().contains(node)) handle_declared(node);
        });
    }
}

bool NodeProtocol::knows_epoch() const {
    return commanded_ || ((mastered_ || election_.role() == Role::Master) &&
                          !mutant_on(options_.mutant, Mutant::unbounded_master_epoch));
}

Epoch NodeProtocol::corroborated_bound(NodeId sender) const {
    // What the cluster's epoch may be, as far as the nodes but `sender` say: each epoch
    // their heartbeats reported since this node booted, a lap above it plus a lap per
    // period since it was heard (an epoch grows no faster), or its own saved one plus a
    // lap per period since boot. A node that heard no one but the sender for miss_limit
    // periods has nothing else to go by: the sender's too. Counting each from when it was
    // heard, not from boot: a node waiting since boot would otherwise count its wait twice
    // (spec/EpochBound.tla).
    const Epoch lap = epoch_lap(*topology_);
    const TimeNs period = topology_->heartbeat_period_ns();
    const auto allowance = [&](std::uint64_t epoch, TimeNs since) {
        return epoch + std::uint64_t{lap} * (1 + static_cast<std::uint64_t>(std::max<TimeNs>(0, now_ - since) / period));
    };
    std::uint64_t bound = allowance(election_.epoch(), booted_ns_);
    bool others = false;
    for (NodeId n = 0; n < topology_->node_count(); ++n) {
        if (n == sender || n == self_ || heard_epoch_[n] < 0) continue;
        others = true;
        bound = std::max(bound, allowance(static_cast<std::uint64_t>(heard_epoch_[n]), heard_epoch_at_[n]));
    }
    const TimeNs listened = now_ - booted_ns_;
    if (!others && sender < topology_->node_count() && heard_epoch_[sender] >= 0 &&
        listened >= topology_->miss_limit() * period) {
        bound = std::max(bound, allowance(static_cast<std::uint64_t>(heard_epoch_[sender]), heard_epoch_at_[sender]));
    }
    return static_cast<Epoch>(std::min<std::uint64_t>(bound, max_adoptable_epoch(*topology_)));
}

void NodeProtocol::note_epoch() {
    // The bound's anchor follows this node's epoch only where that lowers the bound: an
    // epoch it adopts at the bound would otherwise raise the bound a lap at once, and a
    // run of Commands, each a lap above the last, would take it anywhere within a period
    // (spec/EpochBound.tla, mutant EpochBoundPerCommand). An honest epoch grows by a lap
    // at most per take-over, each periods apart: the anchor follows it. The first epoch a
    // node knows (its first Command since it booted, or one it opened) anchors it anew.
    const Epoch epoch = election_.epoch();
    const bool known = knows_epoch();
    if (known && !anchor_known_) {
        anchor_known_ = true;
        anchor_epoch_ = epoch;
        anchor_at_ = now_;
    } else if (epoch != noted_epoch_ &&
               (is_master() || std::uint64_t{epoch} + epoch_lap(*topology_) <= std::uint64_t{adoptable_epoch()})) {
        // An epoch this node opened (a take-over, a reclaim, a warm boot; or a hand-over
        // naming it) anchors the bound there, as EpochBound.tla's opening does: else its
        // followers' messages of its own epoch would read as ahead until the bound caught up.
        anchor_epoch_ = epoch;
        anchor_at_ = now_;
    }
    if (!known) {
        anchor_epoch_ = epoch;  // a saved epoch: no bound until the node knows its epoch
        anchor_at_ = now_;
    }
    noted_epoch_ = epoch;
}

Epoch NodeProtocol::adoptable_epoch() const {
    // A node that booted and has adopted no Command since knows nothing of the cluster's
    // epoch: it may have been down for any time (or booted late), and it follows the first
    // Command it is sent (a late boot, a restarted node's fencing). A node that opened an
    // epoch itself (the initial Master's boot switch, a take-over) knows it as well as one
    // commanded: else one heartbeat of a liar's could move its epoch to the width
    // (keel-sim --liar, prototype3 seed 12: a Master of epoch 2 reclaimed past 13,425,727).
    if (!knows_epoch()) return max_adoptable_epoch(*topology_);
    if (!anchor_known_) {
        // Knows its epoch since its last step (a take-over in this tick): anchored there.
        const std::uint64_t bound = std::uint64_t{election_.epoch()} + epoch_lap(*topology_);
        return static_cast<Epoch>(std::min<std::uint64_t>(bound, max_adoptable_epoch(*topology_)));
    }
    const std::uint64_t periods =
        static_cast<std::uint64_t>(std::max<TimeNs>(0, now_ - anchor_at_) / topology_->heartbeat_period_ns());
    const std::uint64_t bound = std::uint64_t{anchor_epoch_} + std::uint64_t{epoch_lap(*topology_)} * (1 + periods);
    return static_cast<Epoch>(std::min<std::uint64_t>(bound, max_adoptable_epoch(*topology_)));
}

std::optional<std::string> NodeProtocol::command_problem(const Command& command, Verdict* verdict,
                                                         std::vector<Backing>* backing) const {
    *verdict = Verdict::unauthorized;
    if (command.from == self_) return std::nullopt;  // its own: a node trusts itself
    if (mutant_on(options_.mutant, Mutant::no_receiver_checks)) return std::nullopt;
    const View& target = command.view;
    const View& view = switch_.view();
    const Epoch lap = epoch_lap(*topology_);
    // The epoch's width: no node adopts one within a lap of kMaxEpoch, so no take-over
    // ever opens one beyond it.
    if (target.epoch > max_adoptable_epoch(*topology_)) {
        *verdict = Verdict::proof;
        return "epoch " + std::to_string(target.epoch) + " is within a lap of the largest epoch " +
               std::to_string(kMaxEpoch) + ": no Master opens it";
    }
    // An epoch grows by at most a lap of the succession per take-over, readmission or
    // reclaim, and each of those takes periods: a node adopts an epoch at most a lap above
    // its own, plus a lap per heartbeat period since it adopted its own (a node that was
    // cut off or restarted from an old state catches up at that pace). So one node, even
    // the Master, moves the epoch no faster than a lap a period, never in one message.
    // A node that has adopted no Command since it booted follows the first it is sent, but
    // not one that no other node's word supports: within a lap above an epoch the other
    // nodes' heartbeats report, plus a lap per period since it was heard (corroborated_bound). Else a
    // value-faulty Master's first Command, of an epoch far above, sent to a node booting,
    // leaves it in an epoch no correct Master ever reaches (keel-sim --liar, prototype3
    // seed 12942: ST1 followed PN1's epoch 4,405,000 while PN3 followed its epoch 1; PN2
    // took over epoch 2, and ST1 never prepared for it).
    if (!knows_epoch() && !mutant_on(options_.mutant, Mutant::unbounded_master_epoch)) {
        const Epoch corroborated = corroborated_bound(command.from);
        if (target.epoch > corroborated) {
            *verdict = Verdict::ahead;
            return "epoch " + std::to_string(target.epoch) + " is beyond " + std::to_string(corroborated) +
                   ", a lap (" + std::to_string(lap) + ") plus a lap per period above the epochs " +
                   "the other nodes report";
        }
    }
    if (target.epoch > adoptable_epoch()) {
        *verdict = Verdict::ahead;
        return "epoch " + std::to_string(target.epoch) + " is beyond " + std::to_string(adoptable_epoch()) +
               ", a lap of the succession (" + std::to_string(lap) + ") per period above this node's " +
               std::to_string(election_.epoch());
    }
    // (Mutant no-online-check: a view that carries an online configuration unchecked.)
    const bool graph = !mutant_on(options_.mutant, Mutant::no_view_check) &&
                       !(mutant_on(options_.mutant, Mutant::no_online_check) && target.online);
    if (auto problem = graph ? view_problem(target, *topology_) : std::nullopt) {
        *verdict = Verdict::proof;
        return problem;
    }
    // The next switch of this node's own view, from the same Master: an edge of the graph.
    // Only of a view that Master commanded itself (seq 1 on), or the image's initial view
    // (epoch 1, seq 0, which no Command writes): the view at seq 0 of a later
    // epoch is a hand-over's, written by the Master before, and a value-faulty one may
    // have sent this node a copy unlike the one its successor holds; the successor's
    // boot switch, true to its own copy, is no proof against it (keel-sim --liar
    // --max-failures 1, prototype3 seed 15049: ST1 refused PN1's boot switch into SAFE,
    // held to the P4 that PN2 handed ST1, while PN1 had been handed SAFE). Its first
    // switch is held to a view the graph places, as one that skips a switch number is.
    if (graph && target.epoch == view.epoch && target.master == view.master && view.seq < kMaxSeq &&
        target.seq == view.seq + 1 && view.epoch != 0 && (view.seq >= 1 || view.epoch == 1)) {
        const bool gives_up = mutant_on(options_.mutant, Mutant::online_gives_up) &&
                              view.config == kOnlineConfig && target.is_safe();
        if (auto problem = gives_up ? std::nullopt : edge_problem(view, target, *topology_)) {
            *verdict = Verdict::proof;
            return problem;
        }
        if (mutant_on(options_.mutant, Mutant::refuse_phase_edges) && !view.is_safe() && !target.is_safe() &&
            topology_->phase_of(view) != topology_->phase_of(target)) {
            *verdict = Verdict::proof;
            return std::string("no phase edge (mutant refuse-phase-edges)");
        }
    }
    // Rule 5: every exclusion the view adds to those this node checked is backed here, or
    // another member that checked them follows the view (its Prepared for exactly this
    // view). A view that excludes this node itself is followed unchecked (it only stops
    // what this node runs), and what it excludes besides stays unchecked (vetted_).
    if (mutant_on(options_.mutant, Mutant::unbacked_exclusions) || target.failed.contains(self_)) {
        return std::nullopt;
    }
    NodeSet added = target.failed.minus(vetted_.failed);
    added.erase(self_);
    std::optional<NodeId> unbacked;
    std::vector<Backing> found;
    added.for_each([&](NodeId node) {
        if (unbacked) return;
        if (auto by = backing_of(node, command.from, target)) {
            found.push_back(*by);
        } else {
            unbacked = node;
        }
    });
    if (unbacked) {
        const auto voucher = switch_.voucher(target, command.from);
        if (!voucher) {
            *verdict = Verdict::unbacked;
            return "it excludes " + topology_->node_name(*unbacked) + ", which no node but " +
                   topology_->node_name(command.from) + " has declared failed to this node";
        }
        // Another member checked the view: its Prepared vouches for every exclusion.
        found.clear();
        added.for_each([&](NodeId node) { found.push_back({node, "vouched", *voucher}); });
    }
    if (backing != nullptr) *backing = std::move(found);
    return std::nullopt;
}

std::optional<NodeProtocol::Backing> NodeProtocol::backing_of(NodeId node, NodeId sender,
                                                              const View& target) const {
    // Declared by this node's own monitor (on its own evidence, or the node's own word).
    if (monitor_.declared().contains(node)) return Backing{node, "reported", self_};
    if (silent_here(node)) return Backing{node, "silent", kNoNode};
    NodeSet declarers = reports_now_[node] | reports_before_[node];
    declarers.erase(sender);
    if (!declarers.empty()) {
        NodeId first = kNoNode;
        declarers.for_each([&](NodeId d) {
            if (first == kNoNode) first = d;
        });
        // A node asking for its own exclusion is its own word; another's, a declaration.
        return Backing{node, first == node ? "word" : "reported", first};
    }
    if (exclusion_backed(node, sender, target)) return Backing{node, "last", kNoNode};
    return std::nullopt;
}

bool NodeProtocol::silent_here(NodeId node) const {
    // Silent here for as long as a monitor takes to declare it: a node this node hears
    // every period (any node, on a processing node; a monitor of its view, elsewhere: of
    // the last view it checked while it is out of the cluster, not of the view that
    // excluded it, which may name a Worker a monitor).
    const View& view = switch_.view().failed.contains(self_) ? vetted_ : switch_.view();
    const bool heard_each_period = topology_->processing_nodes().contains(self_) ||
                                   topology_->monitors(view).contains(node);
    const TimeNs window = topology_->miss_limit() * topology_->heartbeat_period_ns();
    return heard_each_period && now_ - std::max(last_message_[node], booted_ns_) >= window;
}

bool NodeProtocol::declared_to_me(NodeId node, NodeId sender) const {
    if (monitor_.declared().contains(node)) return true;
    if (silent_here(node)) return true;
    NodeSet declarers = reports_now_[node] | reports_before_[node];
    declarers.erase(sender);
    return !declarers.empty();
}

bool NodeProtocol::exclusion_backed(NodeId node, NodeId sender, const View& target) const {
    if (declared_to_me(node, sender)) return true;
    // The sender may be the last monitor (its own declaration is then all an exclusion
    // needs, fault model 2): of this node's view's monitors, none but the sender and `node`
    // is left once the view's exclusions and the target's backed ones are taken out.
    const View& view = switch_.view().failed.contains(self_) ? vetted_ : switch_.view();
    NodeSet others = topology_->monitors(view).minus(view.failed);
    others.erase(sender);
    others.erase(node);
    (others & target.failed).for_each([&](NodeId other) {
        if (declared_to_me(other, sender)) others.erase(other);
    });
    return others.empty();
}

void NodeProtocol::announce_restart() {
    // A restarted node lost its volatile state: it says so (its own word, which backs its
    // exclusion where a Command adding it is checked, rule 5) to the nodes that do not
    // hear its heartbeats, the Storage and interface nodes, until a Command reaches it. No
    // processing node needs it (each sees the incarnation grow), and none must take it for
    // a resignation: one delayed past this node's readmission would exclude it again while
    // it runs its tasks.
    topology_->all_nodes().minus(topology_->processing_nodes()).for_each([&](NodeId node) {
        if (node != self_) out_.send(node, ErrorNotification{self_, election_.epoch(), self_});
    });
}

void NodeProtocol::announce_own_exclusion() {
    topology_->all_nodes().minus(switch_.view().failed).for_each([&](NodeId node) {
        if (node != self_) out_.send(node, ErrorNotification{self_, election_.epoch(), self_});
    });
}

void NodeProtocol::handle_declared(NodeId node) {
    if (node == self_ || node >= topology_->node_count()) return;
    if (is_master()) {
        consider_exclusion(node);
        return;
    }
    if (election_.role() != Role::Observer || switch_.excluded() || resign_ == Resign::flushing ||
        resign_ == Resign::done) {
        return;
    }
    const View& view = switch_.view();
    // A node that asked to be excluded still reports what it sees, but never takes over.
    if (election_.suspect(node, view, may_act(), out_, diverged()) && resign_ == Resign::none) {
        take_over();
    } else {
        report_declared(node);
    }
}

void NodeProtocol::report_declared(NodeId node) {
    // Only a node that holds its lease reports (spec/Quorum.tla, rule 4): one whose lease
    // lapsed may be the cut-off side, whose declarations are of the nodes it cannot hear,
    // not of nodes that failed.
    // Where the ground counts (spec/Designate.tla), a node stopped by the ground's count
    // alone still reports: its lease holds by the cluster's acknowledgements (the spec's
    // ClusterHolds), and its declarations are what a designee's vote completes.
    const bool cluster_holds = topology_->tie_grace() > 0 && lease_ends_in_tie();
    if (!no_joint_views() && !holds_lease() && !cluster_holds) return;
    const View& view = switch_.view();
    // To the Master, which decides on exclusions, and to every other node: the Observers
    // among the processing nodes decide on a take-over when a monitor is declared (views
    // may differ while a switch is under way or after a late boot, so any may be one), and
    // every node checks that an exclusion a Command adds is backed (rule 5).
    topology_->all_nodes().for_each([&](NodeId other) {
        if (other != self_ && other != node && (other == view.master || !view.failed.contains(other))) {
            out_.send(other, ErrorNotification{self_, election_.epoch(), node});
        }
    });
}

void NodeProtocol::step_down_if_stalled() {
    if (!is_master() || resign_ != Resign::none) return;
    // The Master's lease: its period boundaries come on time. Its heartbeats stop when its
    // loop stalls (paused, starved), and the Observers declare it after miss_limit periods
    // without one; so a Master whose boundary is more than miss_limit - 1 periods overdue
    // (its last heartbeat more than miss_limit periods old) may already have been
    // replaced, and it stops before it acts on anything it received meanwhile (a
    // checkpoint reply, a report, a phase request). A shorter lease made every Master of a
    // heavily loaded 20 ms cluster step down in turn (bench-detector).
    const TimeNs period = topology_->heartbeat_period_ns();
    const TimeNs expiry = monitor_.next_boundary_ns() + std::max(0, topology_->miss_limit() - 1) * period;
    if (now_ <= expiry) return;
    ++stats_.stall_step_downs;
    resign(now_);
}

void NodeProtocol::step_down_if_cut_off() {
    if (!is_master() || resign_ != Resign::none) {
        cut_off_periods_ = 0;
        return;
    }
    // A period in which this Master heard no other node at all counts; at miss_limit - 1
    // such periods in a row it is cut off: deaf, starved or alone on its side of a
    // partition (then the other side takes over after miss_limit periods, and this Master
    // must have stopped by then), or every other node is down (far beyond the tolerance).
    // Only stepping down is safe in both. Not during its own start-up grace before it
    // has heard every other processing node: the few it heard first may pause or restart
    // while the rest have not booted yet.
    const TimeNs grace_ns = topology_->startup_grace_periods() * topology_->heartbeat_period_ns();
    NodeSet peers = topology_->processing_nodes();
    peers.erase(self_);
    const bool started = monitor_.heard_once().includes(peers) || now_ - booted_ns_ >= grace_ns;
    NodeSet heard_once = monitor_.heard_once();
    heard_once.erase(self_);
    if (heard_once.empty() || !monitor_.heard_last_period().empty() || !started) {
        cut_off_periods_ = 0;
        return;
    }
    ++cut_off_periods_;
    if (cut_off_periods_ < std::max(1, topology_->miss_limit() - 1)) return;
    ++stats_.cut_off_step_downs;
    cut_off_periods_ = 0;
    resign(now_);
}

void NodeProtocol::consider_warm_boot() {
    // A whole-cluster power cycle (spec/MasterElection.tla, WarmBoot): every processing
    // node booted from its saved state and none has been commanded since, so none is
    // Master and none will claim an epoch (a restarted node never does: a restarted former
    // Master must not resume). When this node, the first of the succession (the initial
    // Master: one node, whatever the saved views say), has heard every processing node
    // say it waits, miss_limit periods in a row, and has heard every other node too (or
    // its start-up grace is over: a Storage or interface node that does not come back is
    // then declared as any), it claims the first epoch it owns above every epoch those
    // processing nodes saved and drives, with no node failed, the initial configuration
    // of its saved view's phase (of the mission's first phase when that one's master is
    // another node); the others follow its Command as any, and checkpointed tasks resume
    // from the Storage node. A processing node heard that does not wait (commanded, or
    // booted without saved state) stops it: a Master may exist. So does a processing node
    // that never comes back (docs/fault-model.md). Storage and interface nodes are never
    // Master: whether they wait does not matter (they may have stayed up).
    //
    // A processing node that knows itself excluded counts as waiting, and this node may be
    // one: it runs nothing, claims no epoch and waits for a Master to readmit it. Without
    // it a value-faulty Master that fenced every other processing node and then restarted
    // (a reboot clears the upset) would leave none to readmit anyone (keel-sim --liar,
    // prototype3 seed 1900: PN1 fenced PN2 and PN3, restarted, and waited with them).
    // A node the ground holds out never warm-boots: no Master it would be may readmit it.
    const NodeId first = topology_->priority().front();
    const bool fenced = switch_.excluded() && !mutant_on(options_.mutant, Mutant::warm_boot_waiting_only);
    const bool idle = (restarted_ && !commanded_) || fenced;
    if (self_ != first || !idle || held_out_.contains(self_) || resign_ != Resign::none || boot_pending_ ||
        is_master() || mutant_on(options_.mutant, Mutant::no_warm_boot)) {
        warm_periods_ = 0;
        return;
    }
    NodeSet processing = topology_->processing_nodes();
    processing.erase(self_);
    NodeSet others = topology_->all_nodes();
    others.erase(self_);
    const NodeSet& heard = monitor_.heard_last_period();
    bool all_waiting = true;
    processing.for_each([&](NodeId node) {
        if (!heard_waiting_[node]) all_waiting = false;
    });
    const TimeNs grace_ns = topology_->startup_grace_periods() * topology_->heartbeat_period_ns();
    if (!all_waiting || !heard.includes(processing) ||
        (!heard.includes(others) && now_ - booted_ns_ < grace_ns)) {
        warm_periods_ = 0;
        return;
    }
    if (++warm_periods_ < topology_->miss_limit()) return;
    // Above every epoch the processing nodes saved (each says its own while it waits).
    Epoch above = election_.epoch();
    processing.for_each([&](NodeId node) { above = std::max(above, waiting_epoch_[node]); });
    if (topology_->next_epoch(self_, above) > max_adoptable_epoch(*topology_)) {
        // No epoch a node would adopt is left above them (the width of fault model 3's
        // bound): only --cold-start brings this cluster back.
        warm_periods_ = 0;
        ++stats_.warm_boots_refused;
        return;
    }
    ConfigId target = topology_->recovery_target(topology_->phase_of(switch_.view()), NodeSet{});
    if (target == kSafeConfig || topology_->config(target).master != self_) {
        target = topology_->initial_view().config;
    }
    if (topology_->config(target).master != self_) return;  // Topology::build makes it so
    ++stats_.warm_boots;
    warm_periods_ = 0;
    commanded_ = true;  // it commands from now on: it no longer waits
    pending_.clear();
    const Epoch epoch = election_.warm_boot(above, out_);
    switch_.set_role(election_.role());
    start_switch(manager_.warm_boot(epoch, target, out_));
    update_watch();
}

void NodeProtocol::note_report(NodeId reporter, NodeId node) {
    assert(reporter < topology_->node_count() && node < topology_->node_count());
    // A report not current until now starts its streak (rule 4: how long it has stood).
    const bool current = (reports_now_[node] | reports_before_[node]).contains(reporter);
    reports_now_[node].insert(reporter);
    if (!report_since_.empty() && (!current || report_since_[node][reporter] < 0)) {
        report_since_[node][reporter] = now_;
    }
}

bool NodeProtocol::evidence_suffices(NodeId node, const View& driving) const {
    if (!evidence_suffices_in(node, driving)) return false;
    // Joint views (spec/Quorum.tla): a Master whose switch is under way decides only with
    // evidence in every view some node may still go by.
    if (!is_master() || no_joint_views()) return true;
    for (const View& pending : pending_) {
        if (!pending.failed.contains(node) && !evidence_suffices_in(node, pending)) return false;
    }
    return true;
}

bool NodeProtocol::evidence_suffices_in(NodeId node, const View& view) const {
    const Evidence evidence = evidence_in(node, view);
    if (evidence.own) return true;
    NodeSet voters = evidence.members;
    voters.erase(node);
    // Rule 1 (spec/Designate.tla): where the ground is a member (ground_counts), it is one
    // voter more.
    const bool ground = ground_counts(view, evidence.members.size());
    const int needed = mutant_on(options_.mutant, Mutant::single_report_exclusion)
                           ? 1
                           : exclusion_quorum(evidence.members.size() + (ground ? 1 : 0),
                                              voters.size() + (ground ? 1 : 0));
    if (evidence.declared.size() >= needed) return true;
    return vote_completes(node, view, evidence, needed);
}

bool NodeProtocol::vote_completes(NodeId node, const View& view, const Evidence& evidence, int needed) const {
    return vote_counts_against(node, view) && stood_declarations(node, evidence.declared) + 1 >= needed;
}

bool NodeProtocol::view_has_ground(const View& view) const {
    return ground_member(topology_->monitors(view).minus(view.failed).size());
}

bool NodeProtocol::ground_counts(const View& view, int members) const {
    // The view's own count (the spec's Members), or the members this node counts once the
    // nodes that gave their own word here are left out (a resigned Master, a restarted
    // node): two sides of a cut may each shrink an odd view to an even count by what each
    // alone heard, and the ground, a member there too, keeps either from deciding alone.
    return view_has_ground(view) || ground_member(members);
}

bool NodeProtocol::vote_needed(NodeId node, const View& view) const {
    if (topology_->tie_grace() <= 0) return false;
    const Evidence evidence = evidence_in(node, view);
    if (evidence.own) return false;
    NodeSet voters = evidence.members;
    voters.erase(node);
    const bool ground = ground_counts(view, evidence.members.size());
    const int needed = exclusion_quorum(evidence.members.size() + (ground ? 1 : 0), voters.size() + (ground ? 1 : 0));
    return evidence.declared.size() < needed && vote_completes(node, view, evidence, needed);
}

bool NodeProtocol::vote_counts_against(NodeId node, const View& view) const {
    // Rule 4: this node holds the vote, and holds its lease with it (a decider whose
    // lease lapsed decides nothing); the vote is against the nodes it cannot hear only:
    // its own declaration of `node` has stood tie_grace periods, and only in a view the
    // ground is a member of (an even number of monitors the view has not excluded: a tie
    // is possible there, and the ground's standing acknowledgement stopped the other side;
    // in a view with an odd number a majority decides, and the vote never counts).
    if (!view_has_ground(view)) return false;
    const TimeNs stood = topology_->tie_grace() * topology_->heartbeat_period_ns();
    return node != self_ && holds_vote() && holds_lease() && monitor_.declared().contains(node) &&
           declared_at_[node] >= 0 && now_ - declared_at_[node] >= stood;
}

int NodeProtocol::stood_declarations(NodeId node, const NodeSet& declared) const {
    // Each declaration the vote completes has stood tie_grace periods: by then the node
    // declared has been in a tie that long (its voters on this side stopped acknowledging
    // it before they declared it), and has stopped by rule 2 unless the vote is for it.
    const TimeNs stood = topology_->tie_grace() * topology_->heartbeat_period_ns();
    int count = 0;
    declared.for_each([&](NodeId by) {
        const TimeNs since = by == self_ ? declared_at_[node] : report_since_[node][by];
        if (since >= 0 && now_ - since >= stood) ++count;
    });
    return count;
}

NodeSet NodeProtocol::members_of(const View& view) const {
    NodeSet permanent;
    monitor_.failed().for_each([&](NodeId other) {
        if (!monitor_.forgettable(other)) permanent.insert(other);
    });
    // A member passed over for going by another view (diverged()) is no member either: a
    // Worker in its view, it declares no one to this node.
    NodeSet members = topology_->monitors(view).minus(view.failed).minus(permanent).minus(diverged());
    members.insert(self_);
    return members;
}

Evidence NodeProtocol::evidence_in(NodeId node, const View& view) const {
    // A node's own word (it restarted, or says it is excluded) needs no vote.
    if (monitor_.failed().contains(node) && !monitor_.forgettable(node)) return Evidence::own_word();
    // The members: the monitors of the view, but a node the view excluded or this node
    // holds failed for good (it said it left). The voters: the members but `node`. This
    // node's own current declaration and each voter's current report count once each; a
    // majority of the members is needed (exclusion_quorum). Reports of nodes that are no
    // members of the view do not count: a quorum of another view need not share a member
    // with this one's.
    const NodeSet members = members_of(view);
    NodeSet voters = members;
    voters.erase(node);
    const NodeSet reporters = reports_now_[node] | reports_before_[node];
    Evidence evidence;
    evidence.members = members;
    evidence.declared = reporters & voters;
    if (monitor_.failed().contains(node)) evidence.declared.insert(self_);
    return evidence;
}

bool NodeProtocol::awaiting_evidence(NodeId node) const {
    return is_master() && node < topology_->node_count() && monitor_.failed().contains(node) &&
           !manager_.driving().failed.contains(node) && !evidence_suffices(node, manager_.driving());
}

bool NodeProtocol::awaiting_takeover_evidence() const {
    return election_.role() == Role::Observer && !switch_.excluded() && resign_ == Resign::none &&
           election_.ahead_all_suspected(switch_.view(), diverged()) && hears_others() && !takeover_evidence();
}

bool NodeProtocol::awaiting_takeover_lease() const {
    return election_.role() == Role::Observer && !switch_.excluded() && resign_ == Resign::none &&
           election_.ahead_all_suspected(switch_.view(), diverged()) && hears_others() && takeover_evidence() &&
           !may_act();
}

void NodeProtocol::note_divergence(const Ack& ack) {
    const View& view = switch_.view();
    // Not at seq 0: a hand-over's id is not one writer's (two Masters of different epochs
    // may hand the same successor the same next epoch of its own), so two honest copies
    // may differ there; the successor's boot switch (seq 1) gives the view one writer.
    if (ack.kind != AckKind::Prepared || ack.from == self_ || ack.from >= topology_->node_count() ||
        ack.epoch != view.epoch || ack.seq != view.seq || view.seq == 0 || view.failed.contains(ack.from) ||
        ack.view == view_digest(view)) {
        return;
    }
    if (diverged_epoch_ != view.epoch || diverged_seq_ != view.seq) {
        diverged_ = NodeSet{};
        diverged_epoch_ = view.epoch;
        diverged_seq_ = view.seq;
        pass_over_since_ = -1;  // the wait starts again for this view
    }
    if (diverged_.contains(ack.from)) return;
    diverged_.insert(ack.from);
    refuse(stats_.prepared_diverged, "Prepared", ack.from,
           "another view under this node's view's id (epoch " + std::to_string(view.epoch) + ", switch " +
               std::to_string(view.seq) + "): passed over in its succession");
}

NodeSet NodeProtocol::diverged_members() const {
    const View& view = switch_.view();
    NodeSet members;
    if (diverged_epoch_ == view.epoch && diverged_seq_ == view.seq) members = diverged_;
    // A member whose heartbeats say an epoch below this view's never took the view: it
    // missed the Command or hand-over that made it, and the Master that would repeat it is
    // gone (keel-sim --liar --loss 5%, prototype3 seed 826: PN3 handed PN1 epoch 7, PN2
    // missed it, PN1 asked to be excluded; PN3, an Observer behind PN2 in epoch 7's
    // succession, waited for ever for PN2, a Worker in its own epoch 6). It goes by an
    // older view, another succession, and is passed over as one that prepared another.
    // Only while it is heard and hears this node (it acknowledges this node's heartbeats,
    // as a voter of the take-over's lease must): a member that crashed before the view
    // reached it says an older epoch too, and one that is deaf could never acknowledge the
    // take-over; each is succeeded on evidence, as ever.
    //
    // So is a member whose Prepared names a switch of this view's epoch newer than this
    // view, which this node never received: the Master sent it, the copy to this node was
    // lost (or a value-faulty Master sent it to some members only), and the Master died
    // before repeating it. The member goes by the newer view, in which it may be a Worker
    // waiting for this node (spec/DivergedView.tla, MCDivergedViewLost; the rule before,
    // which compared only this view's id, left this node waiting for ever: mutant
    // DivergedSameIdOnly). At any seq of this view, 0 too: a newer switch of an epoch has
    // one writer, the epoch's Master.
    //
    // And so is a member whose Prepared of this very view never reached this node, at seq
    // >= 2 (never_prepared): the switch reached this node but not the member, whose Master
    // died before repeating it, or a lying Master sent the member another switch of the
    // epoch (spec/DivergedView.tla, NeverPrepared). A member that took the view and waits
    // with it repeats its Prepared every period, and one past its Prepared answers this
    // node's repeated own, so one silent for the 2 miss_limit periods of the wait never
    // took the view. Were the guess wrong (every Prepared of it lost), the member, an
    // Observer ahead in the same view, takes over first, during the wait: at most two
    // take-overs, in two epochs. Not at seq 1: the member may then be in the epoch's
    // first view (seq 0), the initial view of a node that booted late, where it is an
    // Observer that takes over in its own time (keel-sim earth-observation seed 7050: PN2,
    // booted after PN1's boot switch and PN1's crash, passed over by PN3 at seq 1, and the
    // cluster went to safe mode where PN2 would have taken it to C2).
    //
    // Only while the member is heard and hears this node,
    // as above: one that excluded this node in its newer view acknowledges it no more. And
    // only once the member no longer hears that Master (its acknowledgements of the
    // Master's heartbeats stopped moving for miss_limit periods): while it does, the
    // Master is alive, this node merely cannot hear it, and the member, a monitor in its
    // view or not, must count (keel-sim prototype3 seed 12313: PN3, deaf to PN1, missed
    // PN1's boot switch that PN2 took, and without this guard passed PN2 over and took
    // over alone beside a live Master).
    const TimeNs window = topology_->miss_limit() * topology_->heartbeat_period_ns();
    for (const NodeId observer : topology_->observers(view)) {
        if (observer == self_ || view.failed.contains(observer) || silent_here(observer) ||
            monitor_.acked_at(observer) == HeartbeatMonitor::kNever || now_ - monitor_.acked_at(observer) >= window) {
            continue;
        }
        const bool behind = latest_epoch_[observer] != 0 && latest_epoch_[observer] < view.epoch;
        // (A member whose heartbeats say a newer epoch, or none, waiting or excluded, goes
        // by no other switch of this epoch.)
        const bool in_epoch = latest_epoch_[observer] == view.epoch;
        if (behind || (in_epoch && (switch_.prepared_newer_switch(observer) || never_prepared(observer)) &&
                       !hears_master(observer))) {
            members.insert(observer);
        }
    }
    members.erase(view.master);  // the Master itself is succeeded only on evidence
    return members;
}

void NodeProtocol::note_master_heard(const Heartbeat& heartbeat) {
    const NodeId master = switch_.view().master;
    const Epoch epoch = switch_.view().epoch;
    MasterHeard& heard = master_heard_[heartbeat.from];
    // About this view's Master in this view's epoch: a Master that restarted and leads a
    // later epoch again is heard afresh.
    if (heard.master != master || heard.epoch != epoch) heard = MasterHeard{master, epoch, 0, 0, -1, false};
    if (master == kNoNode || heartbeat.from == master) return;
    for (const HeartbeatAck& ack : heartbeat.acks) {
        if (ack.node != master) continue;
        if (heard.changed_at >= 0 && ack.incarnation > heard.incarnation) heard.restarted = true;
        if (ack.incarnation != heard.incarnation || ack.seq != heard.seq) {
            heard.incarnation = ack.incarnation;
            heard.seq = ack.seq;
            heard.changed_at = now_;
        }
        return;
    }
}

bool NodeProtocol::never_prepared(NodeId node) const {
    const View& view = switch_.view();
    return view.seq >= 2 && switch_.commanded() && !switch_.prepared_this_view(node);
}

bool NodeProtocol::hears_master(NodeId node) const {
    const MasterHeard& heard = master_heard_[node];
    return heard.master == switch_.view().master && heard.epoch == switch_.view().epoch &&
           heard.changed_at >= 0 && !heard.restarted &&
           now_ - heard.changed_at < topology_->miss_limit() * topology_->heartbeat_period_ns();
}

void NodeProtocol::time_pass_over() {
    // Passing over waits while a member ahead that goes by another view could still take
    // over in it (as a hand-over is given up): 2 miss_limit periods from the first tick at which only such members
    // stand between this node and a take-over. A member that is an Observer in its view
    // takes over meanwhile, and its Command ends the divergence; one that is a Worker
    // there never does, and is passed over then. Two take-overs at once are safe (each
    // opens an epoch of its own, and the lease ends the older) but cost a failover.
    const View& view = switch_.view();
    const NodeSet members = diverged_members();
    const bool waiting = !members.empty() && election_.ahead_all_suspected(view, members) &&
                         !election_.ahead_all_suspected(view);
    if (!waiting || pass_over_epoch_ != view.epoch || pass_over_seq_ != view.seq) {
        pass_over_since_ = -1;  // the wait is for one view
        pass_over_epoch_ = view.epoch;
        pass_over_seq_ = view.seq;
    }
    if (waiting && pass_over_since_ < 0) pass_over_since_ = now_;
}

NodeSet NodeProtocol::diverged() const {
    // A value-faulty Master's Command may reach members changed (keel-sim --liar,
    // prototype3 seed 30979: PN1 readmitted PN3 into S1, where PN2 is the first
    // Observer, but PN2's copy said safe mode from P3, where PN2 is a Worker; PN1 then
    // restarted, and PN3 waited for ever for PN2 to take over). A member whose Prepared
    // names another view under this view's id goes by another succession: this node
    // passes it over (it needs no evidence against it, and does not exclude it). Only
    // a Master that issued two views under one id, or the sender's own lie, makes one:
    // DDS binds each Prepared to its sender, so a lying member can have only itself
    // passed over; a lying Master can have any member passed over (PN2 above is honest),
    // which costs at most a take-over by a node behind it, in an epoch of its own.
    const View& view = switch_.view();
    if (pass_over_since_ < 0 || pass_over_epoch_ != view.epoch || pass_over_seq_ != view.seq ||
        now_ - pass_over_since_ < 2 * topology_->miss_limit() * topology_->heartbeat_period_ns()) {
        return NodeSet{};  // (a wait timed for another view counts for none)
    }
    return diverged_members();
}

bool NodeProtocol::takeover_evidence() const {
    // Every node ahead of this Observer in the succession that the view has not excluded:
    // two monitors' evidence, as the Master needs for an exclusion (spec/Exclusion.tla).
    const View& view = switch_.view();
    if (!view.failed.contains(view.master) && !evidence_suffices(view.master, view)) return false;
    const NodeSet passed = diverged();
    for (NodeId observer : topology_->observers(view)) {
        if (observer == self_) return true;
        if (!view.failed.contains(observer) && !passed.contains(observer) && !evidence_suffices(observer, view)) {
            return false;
        }
    }
    return true;
}

// A decider whose own lease lapsed decides nothing (spec/Lease.tla), but the nodes it
// decides on do not count against it: the last Observer, alone with a dead Master, whose
// only voter is that Master, still takes over.
bool NodeProtocol::may_act() const {
    if (!hears_others() || !takeover_evidence()) return false;
    // A node whose own loop stalled (its boundary overdue by more than half a period)
    // reads what queued up first: it decides at its boundary, not from its stale queue
    // (it would take over and at once step down as a stalled Master).
    if (now_ > monitor_.next_boundary_ns() + topology_->heartbeat_period_ns() / 2) return false;
    // A node that booted moments ago and has adopted no Command since knows nothing of the
    // cluster's current view: it listens for miss_limit periods before it decides, time
    // for a Master of a newer epoch to fence or command it (keel-sim: a late-booted
    // Observer took over from its initial view on the old Master's word 19 ms after boot,
    // beside the Master of a newer epoch).
    if (!commanded_ && now_ - booted_ns_ < topology_->miss_limit() * topology_->heartbeat_period_ns()) {
        return false;
    }
    const View& view = switch_.view();
    NodeSet ahead;
    ahead.insert(view.master);
    for (NodeId observer : topology_->observers(view)) {
        if (observer == self_) break;
        ahead.insert(observer);
    }
    // A node that keeps a tie view (rule 4) decides only with its lease there too, the
    // ground's vote for it included (spec/Designate.tla's TakeOverEnabled: its LeaseBy).
    if (tie_view_ && now_ >= lease_expiry_ns(*tie_view_, NodeSet{}, true)) return false;
    return now_ < lease_expiry_ns(ahead);
}

void NodeProtocol::consider_exclusion(NodeId node) {
    assert(is_master());
    if (node == self_ || manager_.driving().failed.contains(node)) return;
    if (!evidence_suffices(node, manager_.driving())) {
        ++stats_.exclusions_withheld;
        return;
    }
    Evidence evidence = evidence_in(node, manager_.driving());
    if (topology_->tie_grace() > 0) {
        evidence.gm = view_has_ground(manager_.driving());
        evidence.vote = vote_needed(node, manager_.driving());
        if (evidence.vote && !tie_view_) tie_view_ = manager_.driving();
    }
    if (auto next = manager_.exclude(node, evidence, out_)) {
        start_switch(*next);
    }
}

bool NodeProtocol::hears_others() const {
    if (rejoin_hold_ > 0) return false;
    // Some other node's heartbeat arrived in this monitor's last whole period. Not "within
    // miss_limit periods": a node cut off declares the Master after miss_limit silent
    // periods, and by then it may still have heard, less than miss_limit periods ago, a
    // node whose last heartbeat landed later in its period (a wall-clock window counts a
    // heartbeat at the very end of a period as recent, too).
    return monitor_.silent_periods() == 0;
}

void NodeProtocol::take_over() {
    // A take-over opens an epoch every other node adopts: none within a lap of kMaxEpoch,
    // which they refuse as proof (spec/EpochBound.tla, TopLapInv; mutant
    // EpochBoundTopLapOpens). Such a cluster is left to --cold-start, as its warm boot is.
    if (topology_->next_epoch(self_, election_.epoch()) > max_adoptable_epoch(*topology_)) {
        ++stats_.take_overs_refused;
        return;
    }
    const View& view = switch_.view();
    // The members passed over (diverged()): each trace line of the take-over names them,
    // the election's with the epoch each last said, which trace validation holds below
    // the taker's.
    const NodeSet passed = diverged();
    // Joint views (spec/Quorum.tla, rule 3a): the nodes of the view taken over may still
    // go by the views its Master had pending; start_switch adds the view itself.
    pending_ = no_joint_views() ? std::vector<View>{} : switch_.joint();
    // A voter that follows an epoch above the one this take-over opens, whose owner is one
    // of the nodes it replaces, acknowledges no Master of that epoch: the lease would lapse
    // at once. The new Master moves past it now, as a Master that learned of such an epoch
    // does after miss_limit periods (newer_epoch_), within the bound of a lap a period
    // (keel-sim --liar, prototype3 seed 49016: PN3 followed PN1's epoch 7 from a copy PN1
    // changed; PN2 took over epoch 5, stepped down at once, and was never succeeded: its
    // heartbeats of epoch 5 were too old for PN3 to hear). The nodes it replaces: the
    // view's Master and the Observers ahead of this node, each excluded by the view, by
    // evidence, or passed over. Not a node merely suspected, nor one behind: the epoch of
    // a Master this node does not replace (one it missed) is that Master's. A node that
    // knows no epoch (no Command since it booted) has no bound to move by, and does not.
    Epoch above = 0;
    if (knows_epoch()) {
        NodeSet replaced;
        const auto replaces = [&](NodeId node) {
            if (view.failed.contains(node) || passed.contains(node) ||
                (election_.suspects().contains(node) && evidence_suffices(node, view))) {
                replaced.insert(node);
            }
        };
        replaces(view.master);
        for (NodeId observer : topology_->observers(view)) {
            if (observer == self_) break;
            replaces(observer);
        }
        topology_->monitors(view).minus(view.failed).minus(replaced).for_each([&](NodeId voter) {
            const Epoch acked = monitor_.acked_epoch(voter);
            if (voter != self_ && acked > above && replaced.contains(topology_->owner(acked))) above = acked;
        });
        // The view's Master left it for a newer epoch (declare_master_left): this take-over
        // opens one above, which that Master follows.
        if (left_declared_ && left_view_epoch_ == view.epoch && left_view_seq_ == view.seq &&
            left_epoch_ > above) {
            above = left_epoch_;
        }
        // Beyond the bound it is no epoch this node may adopt, nor move past; nor one
        // whose next epoch of this node's is beyond the width.
        if (above > adoptable_epoch() ||
            topology_->next_epoch(self_, above) > max_adoptable_epoch(*topology_)) {
            above = 0;
        }
    }
    // Why each member was passed over (diverged_members), for the trace lines: another
    // view under this view's id (named by no list: no trace spec maps that rule), a newer
    // switch of this view's epoch (`newer`), an older epoch (its epoch heard says so), or
    // no Prepared of this view (`unprepared`).
    std::vector<std::pair<NodeId, Epoch>> heard;
    NodeSet newer;
    NodeSet unprepared;
    const NodeSet other_copy =
        diverged_epoch_ == view.epoch && diverged_seq_ == view.seq ? diverged_ : NodeSet{};
    passed.for_each([&](NodeId node) {
        heard.emplace_back(node, latest_epoch_[node]);
        const bool behind = latest_epoch_[node] != 0 && latest_epoch_[node] < view.epoch;
        if (!other_copy.contains(node) && !behind) {
            if (switch_.prepared_newer_switch(node)) {
                newer.insert(node);
            } else if (never_prepared(node)) {
                unprepared.insert(node);
            }
        }
        ++stats_.passed_over;
    });
    Epoch epoch = election_.become_master(view, out_, heard, newer, unprepared);
    if (above > epoch) epoch = election_.reclaim(above, out_);
    switch_.set_role(election_.role());
    mastered_ = true;
    // Only the suspicions with evidence are excluded at once; the others stay declared and
    // are decided as this Master's own, on the next tick (consider_exclusion).
    NodeSet excluded;
    TakeOverEvidence evidence;
    evidence.members = members_of(view);
    evidence.passed = passed;
    evidence.newer = newer;
    evidence.unprepared = unprepared;
    election_.suspects().for_each([&](NodeId node) {
        if (!evidence_suffices(node, view)) return;
        excluded.insert(node);
        const Evidence why = evidence_in(node, view);
        if (!why.own) evidence.declared.emplace_back(node, why.declared);
        if (!view.failed.contains(node) && vote_needed(node, view)) evidence.voted.insert(node);
    });
    if (topology_->tie_grace() > 0) evidence.gm = view_has_ground(view);
    // A take-over the ground's vote may have counted in (rule 4) leaves the view it took
    // over from joint for as long as the tie lasts.
    if (!evidence.voted.empty()) tie_view_ = view;
    const View target = manager_.take_over(view, epoch, excluded, evidence, out_);
    start_switch(target);
}

void NodeProtocol::start_switch(const View& target) {
    const View before = switch_.driving() ? switch_.master_view() : switch_.view();
    const NodeSet excluded_before = before.failed;
    // Joint views: until this switch completes, a node may still go by the view before it.
    if (std::none_of(pending_.begin(), pending_.end(), [&](const View& view) {
            return view.epoch == before.epoch && view.seq == before.seq;
        })) {
        pending_.push_back(before);
    }
    keep_tie_view();
    ++stats_.switches_started;
    switch_.start_switch(target, out_, pending_);
    // Fencing at once: a node this switch newly excludes is not among the Command's
    // recipients, yet it may be alive (a false suspicion, a node that asked to be
    // excluded) and still run what moves away now. One Command tells it to stop, rather
    // than waiting for its next heartbeat to reach this Master.
    target.failed.minus(excluded_before).for_each([&](NodeId node) {
        if (node != self_) out_.send(node, Command{self_, target, pending_});
    });
}

void NodeProtocol::consider_readmission() {
    if (mutant_on(options_.mutant, Mutant::no_readmission)) return;
    if (!is_master() || resign_ != Resign::none || queued_phase_ ||
        switch_.master_stage() != MasterStage::Idle || !holds_lease()) {
        return;
    }
    const View& driving = manager_.driving();
    const TimeNs period = topology_->heartbeat_period_ns();
    const TimeNs needed = kRejoinPeriodsPerMissLimit * topology_->miss_limit() * period;
    for (int index = 0; index < topology_->node_count(); ++index) {
        const auto node = static_cast<NodeId>(index);
        // A node this Master caught sending what no honest node sends (fault model 3)
        // comes back only once it restarted.
        // Nor does a node the ground holds out, until the ground lets it back.
        if (!driving.failed.contains(node) || monitor_.wrong().contains(node) || held_out_.contains(node) ||
            now_ - rejoin_last_[node] > 2 * period ||
            rejoin_last_[node] - rejoin_since_[node] < needed) {
            continue;
        }
        const Target target = recovery_target(*topology_, driving, node);
        // Beyond the tolerance the smaller failed set may still be safe mode: the node
        // stays out (it is readmitted when another one comes back, or by the ground).
        if (target.is_safe()) continue;
        rejoin_since_[node] = rejoin_last_[node] = 0;
        // A readmission opens an epoch (this Master's next, or the next of the Master it
        // hands the view to): none beyond the width of fault model 3's bound, which every
        // other node refuses as proof (spec/EpochBound.tla, ReadmitBy; mutant
        // EpochBoundReadmitOpens). The node stays out; its next streak is counted afresh.
        const NodeId readmitter = master_of(*topology_, target);
        if (topology_->next_epoch(readmitter, driving.epoch) > max_adoptable_epoch(*topology_)) {
            ++stats_.readmissions_refused;
            continue;
        }
        ++stats_.readmissions;
        if (readmitter == self_) {
            // A readmission opens an epoch: what the node said before it adopted the view
            // (`excluded`) is then told apart from what it says after.
            const View next = manager_.readmit(node, target, out_);
            election_.open_epoch(next.epoch, out_);
            // As a voter on this Master's lease the readmitted node starts afresh: it
            // counts from zero, and only once the view that readmits it, sent now, arrived.
            monitor_.assume_acked(node, now_, election_.epoch());
            joining_.insert(node);
            start_switch(next);
            return;
        }
        ++stats_.hand_overs;
        const View handed = manager_.hand_over(node, target, out_);
        handed_over_epoch_ = handed.epoch;
        handed_over_boot_ = monitor_.boot_of(node);
        const Command command = hand_over_command(handed, pending_);
        topology_->all_nodes().minus(handed.failed).for_each([&](NodeId to) {
            if (to != self_) out_.send(to, command);
        });
        handle_command(command);
        return;
    }
}

void NodeProtocol::repeat_hand_over() {
    if (handed_over_epoch_ == 0) return;
    const View& view = switch_.view();
    // Until the new Master commands (its first switch moves the view past seq 0).
    if (view.epoch != handed_over_epoch_ || view.seq != 0 || view.master == self_) {
        handed_over_epoch_ = 0;
        return;
    }
    out_.send(view.master, hand_over_command(view, switch_.joint()));
}

Command NodeProtocol::hand_over_command(const View& handed, std::vector<View> joint) const {
    // It names the boot it was handed to: a receiver that restarted since refuses it (and
    // is seen to restart, a failure like any other).
    Command command{self_, handed, std::move(joint)};
    command.boot = handed_over_boot_;
    return command;
}

void NodeProtocol::note_master_left(const Heartbeat& heartbeat) {
    // A node whose view's Master says, in its heartbeats, that it follows a newer epoch
    // (the highest it adopted) knows that Master left the view: an honest node that adopts
    // a newer epoch steps down from an older one, and never drives it again. The Master of
    // that epoch commands this node too, within a period or two (its Commands are
    // repeated), unless it failed or lied: a value-faulty Master readmitted a node into
    // its epoch alone, then handed the others an older epoch naming that node Master,
    // which that node never takes (keel-sim --liar, earth-observation seed 13921: PN1
    // followed PN2's epoch 14, PN3, PN4 and IF1 waited in epoch 9 for PN1, and no one
    // ever commanded again once PN2 restarted). Since when the Master of this view has
    // said so, without a break, within the adoptable bound (a lie of its own beyond it
    // moves nothing).
    const View& view = switch_.view();
    if (left_view_epoch_ != view.epoch || left_view_seq_ != view.seq) {
        left_view_epoch_ = view.epoch;
        left_view_seq_ = view.seq;
        left_since_ = -1;
        left_epoch_ = 0;
        left_declared_ = false;
    }
    if (heartbeat.from != view.master || view.master == self_ || heartbeat.from >= topology_->node_count() ||
        heartbeat.reply) {
        return;
    }
    // Or it says an epoch below the view's: it never took the view it was handed (a
    // value-faulty Master handed the others a view naming it, and went on as its Master;
    // spec/ElectionLiar.tla, rule 2). An honest new Master takes a hand-over within a
    // period or two (hand-overs are repeated), well within the patience below.
    const bool ahead = heartbeat.epoch > view.epoch && heartbeat.epoch <= adoptable_epoch();
    const bool behind = heartbeat.epoch < view.epoch;
    const bool left = (ahead || behind) && !heartbeat.excluded && !heartbeat.waiting;
    if (!left) {
        left_since_ = -1;
        return;
    }
    if (left_since_ < 0) left_since_ = now_;
    left_epoch_ = std::max(left_epoch_, heartbeat.epoch);
}

void NodeProtocol::declare_master_left() {
    // After 3 miss_limit periods (longer than a hand-over's new Master waits for its
    // voters before it gives the view up) an Observer declares the Master on its own word
    // (reason "left"): the first Observer takes over, in an epoch above the one the Master
    // follows, and the Master follows it (fenced, then readmitted).
    const View& view = switch_.view();
    if (left_since_ < 0 || left_declared_ || left_view_epoch_ != view.epoch || left_view_seq_ != view.seq ||
        election_.role() != Role::Observer || switch_.excluded() || resign_ != Resign::none ||
        mutant_on(options_.mutant, Mutant::no_master_left)) {
        return;
    }
    const TimeNs patience = 3 * topology_->miss_limit() * topology_->heartbeat_period_ns();
    if (now_ - left_since_ < patience || monitor_.failed().contains(view.master)) return;
    left_declared_ = true;
    ++stats_.masters_left;
    monitor_.declare_left(view.master, out_);
    if (monitor_.failed().contains(view.master)) handle_declared(view.master);
}

void NodeProtocol::start_queued_phase() {
    if (!queued_phase_ || !is_master() || switch_.master_stage() != MasterStage::Idle) return;
    const PhaseId phase = *queued_phase_;
    queued_phase_.reset();
    if (auto next = manager_.on_phase(phase, out_)) start_switch(*next);
}

void NodeProtocol::update_watch() {
    const View& view = switch_.view();
    NodeSet failed = view.failed;
    if (manager_.active()) failed = failed | manager_.driving().failed;
    monitor_.adopt_failed(failed);
    const bool monitoring = !switch_.excluded() && resign_ != Resign::flushing &&
                            resign_ != Resign::done && (election_.role() == Role::Master ||
                                                     election_.role() == Role::Observer);
    NodeSet watched = topology_->all_nodes().minus(failed);
    watched.erase(self_);
    monitor_.set_watch(monitoring, watched);
}

void NodeProtocol::deliver_internal(std::size_t from_index) {
    auto& actions = out_.actions();
    int deliveries = 0;
    for (std::size_t i = from_index; i < actions.size();) {
        auto* send = std::get_if<act::Send>(&actions[i]);
        if (send == nullptr || send->to != self_) {
            ++i;
            continue;
        }
        Message message = std::move(send->message);
        actions.erase(actions.begin() + static_cast<std::ptrdiff_t>(i));
        ++deliveries;
        assert(deliveries <= kMaxInternalDeliveries);
        if (deliveries > kMaxInternalDeliveries) break;
        handle(message);
    }
}

// spec/Designate.tla in the runtime (docs/operations.md, `designate`).

std::string NodeProtocol::ground_designate(NodeId node, int wait_periods, int span_periods, std::uint32_t echo,
                                           TimeNs now) {
    assert(now >= now_);
    now_ = now;
    if (topology_->tie_grace() <= 0) {
        return "the mission sets no heartbeat.tie_grace: the ground is no voter of its leases, and a designation "
               "could not be safe (spec/Designate.tla)";
    }
    if (node >= topology_->node_count()) return "no such node";
    if (!topology_->monitors(switch_.view()).contains(node) || switch_.view().failed.contains(node)) {
        return topology_->node_name(node) + " is no monitor of the view this node goes by (epoch " +
               std::to_string(switch_.view().epoch) + ", " + topology_->config_name(switch_.view().config) +
               "): only a monitor decides";
    }
    if (wait_periods < 0 || span_periods <= wait_periods) {
        return "the span (" + std::to_string(span_periods) + " periods) must end after the wait (" +
               std::to_string(wait_periods) + ")";
    }
    const TimeNs period = topology_->heartbeat_period_ns();
    Designation designation;
    designation.node = node;
    designation.from = mutant_on(options_.mutant, Mutant::designate_at_once) ? now : now + wait_periods * period;
    designation.until = designation.from;  // another node's vote: none for this one
    if (node == self_) {
        const auto sent = monitor_.sent_at(echo);
        if (!sent) {
            return "heartbeat " + std::to_string(echo) + " is not one of this boot's last heartbeats (the latest is " +
                   std::to_string(monitor_.seq()) +
                   "): the span counts from the designee's heartbeat the ground saw last, and this node cannot "
                   "tell when that one was sent";
        }
        designation.until = *sent + span_periods * period;
    }
    const std::size_t start = out_.actions().size();
    designation_ = designation;
    designation_echo_ = echo;
    if (out_.tracing()) {
        out_.trace("switch", "GroundDesignate",
                   JsonObject()
                       .field("n", topology_->node_name(self_))
                       .field("d", topology_->node_name(node))
                       .field("wait", wait_periods)
                       .field("span", span_periods)
                       .field("echo", static_cast<std::uint64_t>(echo))
                       .str(),
                   "{}");
    }
    enforce_lease();
    deliver_internal(start);
    return "";
}

void NodeProtocol::note_vote_left() {
    if (topology_->tie_grace() <= 0) return;
    std::uint32_t left = 0;
    if (holds_vote()) {
        const TimeNs ms = (designation_.until - now_) / 1'000'000;
        left = static_cast<std::uint32_t>(std::clamp<TimeNs>(ms, 0, std::numeric_limits<std::uint32_t>::max()));
    }
    monitor_.set_vote_left_ms(left);
}

void NodeProtocol::note_master_vote(const Heartbeat& heartbeat) {
    if (topology_->tie_grace() <= 0 || heartbeat.from != switch_.view().master || heartbeat.from == self_) return;
    if (heartbeat.vote_left_ms == 0) {
        master_vote_node_ = kNoNode;  // the Master holds no vote now
        master_vote_until_ = 0;
        return;
    }
    // Counted from this node's own heartbeat that the Master acknowledged: sent before the
    // Master said how much was left, so the end reckoned here never follows the Master's.
    for (const HeartbeatAck& ack : heartbeat.acks) {
        if (ack.node != self_ || ack.incarnation != monitor_.incarnation()) continue;
        if (const auto sent = monitor_.sent_at(ack.seq)) {
            const TimeNs until = *sent + static_cast<TimeNs>(heartbeat.vote_left_ms) * 1'000'000;
            if (master_vote_node_ != heartbeat.from || until > master_vote_until_) {
                master_vote_node_ = heartbeat.from;
                master_vote_until_ = until;
            }
        }
        break;
    }
}

void NodeProtocol::note_declarations() {
    if (topology_->tie_grace() <= 0) return;
    for (NodeId node = 0; node < topology_->node_count(); ++node) {
        if (monitor_.declared().contains(node)) {
            if (declared_at_[node] < 0) declared_at_[node] = now_;
        } else {
            declared_at_[node] = -1;
        }
        // A report missing from both generations was withdrawn: its streak starts again.
        auto& since = report_since_[node];
        const NodeSet current = reports_now_[node] | reports_before_[node];
        for (NodeId by = 0; by < topology_->node_count(); ++by) {
            if (since[by] >= 0 && !current.contains(by)) since[by] = -1;
        }
    }
}

bool NodeProtocol::lease_ends_in_tie() const {
    // The lease by the cluster's acknowledgements alone holds: what ends it is the ground.
    cluster_only_ = true;
    const TimeNs expiry = lease_expiry_ns();
    cluster_only_ = false;
    return now_ < expiry;
}

void NodeProtocol::consider_stand_down(bool lapsed_in_tie) {
    // A Master whose lease lapses resigns (its own word, Lease.tla): only a designation
    // makes it a Master again, by a take-over of another node.
    if (!stood_down_) {
        if (!lapsed_in_tie || is_master() || boot_pending_ || switch_.excluded()) return;
        stood_down_ = true;
        stood_down_epoch_ = election_.epoch();
        if (out_.tracing()) {
            out_.trace("switch", "StandDown",
                       JsonObject().field("n", topology_->node_name(self_)).field("epoch", election_.epoch()).str(),
                       "{}");
        }
        return;
    }
    if (tie_over()) end_stand_down("heard");
}

void NodeProtocol::end_stand_down(const char* why) {
    stood_down_ = false;
    if (out_.tracing()) {
        out_.trace("switch", "StandUp",
                   JsonObject().field("n", topology_->node_name(self_)).field("why", why).str(), "{}");
    }
}

bool NodeProtocol::tie_over() const {
    // Every voter of every view this node goes by acknowledges it, and none goes by a newer
    // epoch: the tie is over, and no take-over this node does not know of excluded it (a
    // take-over's Master acknowledges no node it excluded).
    const TimeNs period = topology_->heartbeat_period_ns();
    const TimeNs window = topology_->miss_limit() * period - period / 4;
    const auto acknowledged_by_all = [&](const View& view) {
        bool all = true;
        topology_->monitors(view).minus(view.failed).for_each([&](NodeId voter) {
            if (voter == self_ || (monitor_.failed().contains(voter) && !monitor_.forgettable(voter))) return;
            const TimeNs at = monitor_.acked_at(voter);
            if (at == HeartbeatMonitor::kNever || at + window <= now_ || latest_epoch_[voter] > election_.epoch()) {
                all = false;
            }
        });
        return all;
    };
    if (!acknowledged_by_all(switch_.view())) return false;
    return std::all_of(switch_.joint().begin(), switch_.joint().end(), acknowledged_by_all);
}

bool NodeProtocol::in_tie(const View& view) const {
    // Rule 2's InTie: the ground a member of the view, and one vote more than this node's
    // stale voters there would exclude it.
    if (topology_->tie_grace() <= 0 || !ground_member(topology_->monitors(view).minus(view.failed).size())) {
        return false;
    }
    NodeSet voters = topology_->monitors(view).minus(view.failed);
    monitor_.failed().for_each([&](NodeId node) {
        if (!monitor_.forgettable(node)) voters.erase(node);
    });
    const bool member = voters.contains(self_);
    voters.erase(self_);
    const int count = voters.size();
    if (count == 0) return false;
    const TimeNs period = topology_->heartbeat_period_ns();
    const TimeNs window = topology_->miss_limit() * period - period / 4;
    int stale = 0;
    voters.for_each([&](NodeId voter) {
        const TimeNs at = monitor_.acked_at(voter);
        if (at == HeartbeatMonitor::kNever || at + window <= now_) ++stale;
    });
    return stale + 1 >= exclusion_quorum(count + (member ? 1 : 0) + 1, count + 1);
}

void NodeProtocol::adopt_tie_view(const std::vector<View>& joint) {
    // A node that follows a view keeps, of the joint views its Command carried, the one it
    // is in a tie in (rule 4: the view a decision on the ground's vote left joint; in an
    // ordinary joint view no node of the deciding side is in a tie).
    tie_view_.reset();
    for (const View& view : joint) {
        if (in_tie(view)) {
            tie_view_ = view;
            return;
        }
    }
}

void NodeProtocol::keep_tie_view() {
    if (!tie_view_) return;
    // The tie is over once this node is in a tie there no more (its voters acknowledge it
    // again, or said they left: the nodes this lineage excluded, fenced).
    if (!in_tie(*tie_view_)) {
        tie_view_.reset();
        return;
    }
    if (std::none_of(pending_.begin(), pending_.end(), [&](const View& view) {
            return view.epoch == tie_view_->epoch && view.seq == tie_view_->seq;
        })) {
        pending_.insert(pending_.begin(), *tie_view_);
    }
}

}  // namespace keel::fsm
