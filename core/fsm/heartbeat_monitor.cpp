#include "core/fsm/heartbeat_monitor.hpp"

#include <algorithm>
#include <cassert>

#include "core/fsm/json.hpp"

namespace keel::fsm {

HeartbeatMonitor::HeartbeatMonitor(const Topology& topology, NodeId self,
                                   std::uint32_t incarnation, TimeNs phase_start_ns,
                                   Mutant mutant, std::uint32_t boot)
    : topology_(&topology),
      self_(self),
      incarnation_(incarnation),
      boot_(boot),
      period_ns_(topology.heartbeat_period_ns()),
      next_boundary_ns_(phase_start_ns),
      declare_at_(topology.miss_limit()),
      grace_at_(std::max(topology.startup_grace_periods(), topology.miss_limit())) {
    assert(period_ns_ > 0);
    assert(self < topology.node_count());
    if (mutant_on(mutant, Mutant::declare_on_first_miss)) declare_at_ = 1;
    if (mutant_on(mutant, Mutant::late_declare)) declare_at_ = 2 * topology.miss_limit();
    if (mutant_on(mutant, Mutant::no_startup_grace)) grace_at_ = declare_at_;
    if (mutant_on(mutant, Mutant::no_self_suspicion)) self_suspicion_ = false;
    if (mutant_on(mutant, Mutant::ignore_boot)) boots_ignored_ = true;
    acked_at_.fill(kNever);
}

void HeartbeatMonitor::set_watch(bool monitoring, NodeSet watched) {
    watched.erase(self_);
    if (monitoring && !monitoring_) {
        // A fresh monitor has seen no heartbeat yet: start every count from zero and do
        // not count the partial period that is under way.
        skip_next_tick_ = true;
        missed_.fill(0);
        heard_ = NodeSet{};
    }
    monitoring_ = monitoring;
    watched_ = watched.minus(failed_);
}

void HeartbeatMonitor::adopt_failed(NodeSet failed) {
    failed_ = failed_ | failed;
    watched_ = watched_.minus(failed_);
}

void HeartbeatMonitor::forget(NodeId node, Outbox& out) {
    if (!forgettable(node)) return;
    failed_.erase(node);
    declared_.erase(node);
    missed_[node] = 0;
    // The message that proved the node alive counts for the period under way.
    heard_.insert(node);
    heard_once_.insert(node);
    if (out.tracing()) {
        out.trace("heartbeat", "Withdraw",
                  JsonObject().field("m", topology_->node_name(self_)).field("n", topology_->node_name(node)).str(),
                  vars_json());
    }
}

void HeartbeatMonitor::readmit(NodeId node, Epoch epoch, Outbox& out) {
    if (node >= topology_->node_count() || node == self_) return;
    failed_.erase(node);
    declared_.erase(node);
    permanent_.erase(node);
    wrong_.erase(node);
    missed_[node] = 0;
    readmit_epoch_[node] = std::max(readmit_epoch_[node], epoch);
    unadopted_for_[node] = 1;
    if (out.tracing()) {
        out.trace("heartbeat", "Readmit",
                  JsonObject()
                      .field("m", topology_->node_name(self_))
                      .field("n", topology_->node_name(node))
                      .field("epoch", epoch)
                      .str(),
                  vars_json());
    }
}

void HeartbeatMonitor::forget_declarations(NodeSet keep, Epoch epoch, Outbox& out) {
    failed_ = failed_ & keep;
    declared_ = declared_ & keep;
    permanent_ = permanent_ & keep;
    missed_.fill(0);
    heard_once_ = NodeSet{};  // every node gets the start-up grace again
    if (out.tracing()) {
        out.trace("heartbeat", "Rejoin",
                  JsonObject()
                      .field("m", topology_->node_name(self_))
                      .field("epoch", epoch)
                      .str(),
                  vars_json());
    }
}

void HeartbeatMonitor::assume_acked(NodeId node, TimeNs now, Epoch epoch) {
    if (node >= topology_->node_count() || now <= acked_at_[node]) return;
    acked_at_[node] = now;
    acked_epoch_[node] = epoch;
}

void HeartbeatMonitor::heard_from(NodeId node) {
    if (node >= topology_->node_count() || node == self_ || heard_once_.contains(node)) return;
    heard_once_.insert(node);
    if (!failed_.contains(node)) missed_[node] = 0;
}

void HeartbeatMonitor::take_acks(const Heartbeat& heartbeat) {
    // What the sender acknowledges of this node: the send time of the heartbeat it heard.
    if (heartbeat.from >= topology_->node_count() || heartbeat.from == self_) return;
    for (const HeartbeatAck& ack : heartbeat.acks) {
        if (ack.node != self_ || ack.incarnation != incarnation_ || ack.seq == 0) continue;
        const std::uint32_t slot = ack.seq % kSentKept;
        if (sent_seq_[slot] != ack.seq) break;  // older than what is kept, or never sent
        if (sent_at_[slot] > acked_at_[heartbeat.from]) {
            acked_at_[heartbeat.from] = sent_at_[slot];
            acked_epoch_[heartbeat.from] = heartbeat.epoch;
        }
        break;
    }
}

void HeartbeatMonitor::retire_boot(NodeId node, std::uint32_t boot) {
    if (node >= topology_->node_count() || boot == boots_[node]) return;
    const auto& retired = retired_[node];
    const auto end = retired.begin() + std::min<std::uint32_t>(retired_next_[node], kRetiredBoots);
    if (std::find(retired.begin(), end, boot) != end) return;
    retired_[node][retired_next_[node] % kRetiredBoots] = boot;
    ++retired_next_[node];
}

bool HeartbeatMonitor::retired_boot(const Heartbeat& heartbeat) const {
    const NodeId from = heartbeat.from;
    if (boots_ignored_ || from >= topology_->node_count() || incarnations_[from] == 0 ||
        heartbeat.boot == boots_[from]) {
        return false;
    }
    const auto& retired = retired_[from];
    const auto end = retired.begin() + std::min<std::uint32_t>(retired_next_[from], kRetiredBoots);
    return std::find(retired.begin(), end, heartbeat.boot) != end;
}

NodeId HeartbeatMonitor::receive_heartbeat(const Heartbeat& heartbeat, Epoch epoch, TimeNs now,
                                           Outbox& out) {
    const NodeId from = heartbeat.from;
    if (from >= topology_->node_count() || from == self_ || retired_boot(heartbeat)) return kNoNode;
    last_heard_any_ns_ = now;
    heard_any_this_period_ = true;
    heard_all_.insert(from);
    heard_once_.insert(from);
    const std::uint32_t known = incarnations_[from];
    // A boot this monitor has not heard: the node restarted, whatever its incarnation says
    // (it may have gone back with a lost or restored state file). Its incarnation is taken
    // as it now is, so that acknowledgements name the one the node sends.
    const bool new_boot = known != 0 && !boots_ignored_ && heartbeat.boot != boots_[from];
    if (known == 0 || new_boot) {
        const std::uint32_t ended = boots_[from];
        boots_[from] = heartbeat.boot;
        if (new_boot) retire_boot(from, ended);
    }
    // The boot before this one has ended, whether or not this monitor heard it: a late
    // heartbeat of it is stale.
    if (!boots_ignored_ && heartbeat.previous_boot != 0) retire_boot(from, heartbeat.previous_boot);
    // Overtaken on the way (a reply sent before the sender's boundary, arriving after its
    // next heartbeat): what it says of the sender is older than what was heard.
    const bool overtaken = !new_boot && heartbeat.incarnation == known && heartbeat.seq < heard_seq_[from];
    incarnations_[from] = new_boot ? heartbeat.incarnation : std::max(known, heartbeat.incarnation);
    if (heartbeat.incarnation > known || new_boot) heard_seq_[from] = 0;
    if (heartbeat.incarnation == incarnations_[from]) heard_seq_[from] = std::max(heard_seq_[from], heartbeat.seq);
    take_acks(heartbeat);
    // A node first heard at an incarnation above 1, or saying it waits for a Command after
    // booting from its saved state, restarted before this node heard it (it booted later,
    // e.g.): it lost its volatile state all the same. Without this, a restarted initial
    // Master waiting for a Command would look alive to an Observer that booted after it,
    // and nobody would ever command the cluster (`waiting`: also when its saved
    // incarnation went back to 0).
    const bool restarted = known != 0 ? heartbeat.incarnation > known || new_boot
                                      : heartbeat.incarnation > 1 || heartbeat.waiting;
    // A restart clears what made it wrong: its volatile state is gone.
    if (restarted) wrong_.erase(from);
    // A readmitted node says `excluded` until it adopts the view that readmits it: in an
    // older epoch, that is stale, until the node has said so for 3 miss_limit periods
    // after the readmission (a Master repeats its Command to a node that has not
    // prepared it, so one that still has not adopted it then never heard it: it is deaf,
    // and out by its own word; keel-sim --loss 5%, prototype3 seed 9386: PN2, readmitted
    // while deaf, stayed out, and PN3 waited for ever behind it for a take-over).
    if (!overtaken && (!heartbeat.excluded || heartbeat.epoch >= readmit_epoch_[from])) {
        unadopted_for_[from] = 0;
    }
    const bool says_excluded =
        heartbeat.excluded && !overtaken &&
        (heartbeat.epoch >= readmit_epoch_[from] ||
         unadopted_for_[from] > kUnadoptedPeriods * declare_at_);
    // Already declared, and now known to have restarted or to be excluded: that
    // declaration can no longer be withdrawn by hearing the node.
    // Traced as a declaration for that reason (the node's own word, which an exclusion of
    // it may rest on: spec/trace/TraceConfigSwitch.tla, `said`).
    if ((restarted || says_excluded) && failed_.contains(from) && !permanent_.contains(from)) {
        permanent_.insert(from);
        declared_.insert(from);  // its own word, heard here
        if (out.tracing()) {
            out.trace("heartbeat", "DeclareFailed",
                      JsonObject()
                          .field("m", topology_->node_name(self_))
                          .field("n", topology_->node_name(from))
                          .field("reason", restarted ? "restarted" : "excluded")
                          .str(),
                      vars_json());
        }
    }
    if (!monitoring_ || !watched_.contains(from)) return kNoNode;
    heard_.insert(from);
    // The immediate acknowledgement (not of a reply: replies are never answered).
    if (!heartbeat.reply && heartbeat.incarnation == incarnations_[from]) {
        out.send(from, Heartbeat{self_, epoch, incarnation_, excluded_, seq_,
                                 {HeartbeatAck{from, incarnations_[from], heard_seq_[from]}}, true, boot_,
                                 waiting_, previous_boot_, image_, vote_left_ms_});
    }
    if (out.tracing()) {
        out.trace("heartbeat", "ReceiveHeartbeat",
                  JsonObject().field("m", topology_->node_name(self_)).field("n", topology_->node_name(from))
                      .field("epoch", epoch).str(),
                  vars_json());
    }
    if (restarted) {
        declare(from, act::FailureReason::restarted, out);
        return from;
    }
    if (says_excluded) {
        declare(from, act::FailureReason::excluded, out);
        return from;
    }
    return kNoNode;
}

NodeSet HeartbeatMonitor::period_boundary(TimeNs now, Epoch epoch, bool excluded, Outbox& out) {
    assert(now >= next_boundary_ns_);
    NodeSet declared;
    for (int& periods : unadopted_for_) {
        if (periods > 0 && periods < 0x7FFF'FFFF) ++periods;
    }
    // Self-suspicion (spec/Exclusion.tla, rule 1): a period in which this monitor heard no
    // other node's heartbeat (watched or not), or whose boundary it reached more than half a period
    // late (its own loop was starved: what arrived meanwhile may still sit unread in its
    // queues), says more about this monitor than about the others. It is not counted.
    const bool late = now - next_boundary_ns_ > period_ns_ / 2;
    const bool silent = heard_all_.empty();
    const bool suspect_self = self_suspicion_ && (late || silent);
    // Tick: the period that ends is counted, unless this monitor started during it.
    if (monitoring_) {
        if (skip_next_tick_) {
            skip_next_tick_ = false;
        } else if (suspect_self) {
            // What it did hear is still evidence of life; only its misses are suspect.
            heard_.for_each([&](NodeId node) { missed_[node] = 0; });
            ++self_suspected_periods_;
            if (out.tracing()) {
                out.trace("heartbeat", "Tick",
                          JsonObject()
                              .field("m", topology_->node_name(self_))
                              .field("suspect", true)
                              .field("late", late)
                              .field("silent", silent)
                              .str(),
                          vars_json());
            }
        } else {
            watched_.for_each([&](NodeId node) {
                if (heard_.contains(node)) {
                    missed_[node] = 0;
                } else if (missed_[node] < 0xFFFF'FFFFu) {
                    ++missed_[node];
                }
            });
            if (out.tracing()) {
                // What rule 1 decides on, so that trace validation can hold the decision
                // to it (a counting Tick must be neither late nor silent).
                out.trace("heartbeat", "Tick",
                          JsonObject()
                              .field("m", topology_->node_name(self_))
                              .field("late", late)
                              .field("silent", silent)
                              .str(),
                          vars_json());
            }
            watched_.for_each([&](NodeId node) {
                if (missed_[node] >= static_cast<std::uint32_t>(declare_after(node))) {
                    declare(node, act::FailureReason::missed, out);
                    declared.insert(node);
                }
            });
        }
    }
    heard_ = NodeSet{};
    heard_last_period_ = heard_all_;
    heard_all_ = NodeSet{};
    silent_periods_ = heard_any_this_period_ ? 0 : silent_periods_ + 1;
    heard_any_this_period_ = false;
    // SendHeartbeat: to every processing node but this one; a monitor's, with its
    // acknowledgements, to every node.
    ++seq_;
    excluded_ = excluded;
    sent_seq_[seq_ % kSentKept] = seq_;
    sent_at_[seq_ % kSentKept] = now;
    Heartbeat heartbeat{self_, epoch, incarnation_, excluded, seq_, {}, false, boot_, waiting_, previous_boot_,
                        image_, vote_left_ms_};
    // Every processing node acknowledges (a Worker may be an Observer in the next view,
    // and its word then counts at once); only a monitor also replies at once.
    if (topology_->processing_nodes().contains(self_) && !excluded) {
        watched_.minus(failed_).for_each([&](NodeId node) {
            if (incarnations_[node] != 0) {
                heartbeat.acks.push_back(HeartbeatAck{node, incarnations_[node], heard_seq_[node]});
            }
        });
    }
    (monitoring_ ? topology_->all_nodes() : topology_->processing_nodes()).for_each([&](NodeId node) {
        if (node != self_) out.send(node, heartbeat);
    });
    if (out.tracing()) {
        out.trace("heartbeat", "SendHeartbeat",
                  JsonObject().field("n", topology_->node_name(self_)).str(), vars_json());
    }
    // Next boundary: skip whole periods the caller may have missed, keeping the phase.
    const TimeNs behind = now - next_boundary_ns_;
    next_boundary_ns_ += (behind / period_ns_ + 1) * period_ns_;
    return declared;
}

void HeartbeatMonitor::declare(NodeId node, act::FailureReason reason, Outbox& out) {
    failed_.insert(node);
    declared_.insert(node);
    if (reason != act::FailureReason::missed) permanent_.insert(node);
    watched_.erase(node);
    out.push(act::DeclareFailed{node, reason});
    if (out.tracing()) {
        out.trace("heartbeat", "DeclareFailed",
                  JsonObject()
                      .field("m", topology_->node_name(self_))
                      .field("n", topology_->node_name(node))
                      .field("reason", reason == act::FailureReason::missed      ? "missed"
                                    : reason == act::FailureReason::restarted ? "restarted"
                                    : reason == act::FailureReason::excluded  ? "excluded"
                                    : reason == act::FailureReason::left      ? "left"
                                                                              : "wrong")
                      .str(),
                  vars_json());
    }
}

void HeartbeatMonitor::declare_left(NodeId node, Outbox& out) {
    if (node == self_ || static_cast<int>(node) >= topology_->node_count() || !watched_.contains(node) ||
        failed_.contains(node)) {
        return;
    }
    declare(node, act::FailureReason::left, out);
}

void HeartbeatMonitor::declare_wrong(NodeId node, Outbox& out) {
    if (node == self_ || static_cast<int>(node) >= topology_->node_count()) return;
    wrong_.insert(node);
    if (failed_.contains(node)) {
        permanent_.insert(node);  // declared for missed heartbeats: now for good
        declared_.insert(node);
        return;
    }
    declare(node, act::FailureReason::wrong, out);
}

std::string HeartbeatMonitor::vars_json() const {
    // Every node but this one: a declared node keeps the count that declared it.
    std::string missed = "{";
    bool first = true;
    topology_->all_nodes().for_each([&](NodeId node) {
        if (node == self_) return;
        if (!first) missed.push_back(',');
        first = false;
        append_json_string(missed, topology_->node_name(node));
        missed.push_back(':');
        missed += std::to_string(missed_[node]);
    });
    missed.push_back('}');
    return JsonObject()
        .raw("heard", json_nodes(*topology_, heard_))
        .raw("missed", missed)
        .raw("failed", json_nodes(*topology_, failed_))
        .raw("heardOnce", json_nodes(*topology_, heard_once_))
        .str();
}

}  // namespace keel::fsm
