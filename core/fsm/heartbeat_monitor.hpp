// HeartbeatMonitor: failure detection by missed heartbeats (spec/Heartbeat.tla, fsm
// "heartbeat").
//
// Every node sends one Heartbeat per heartbeat period to every processing node (the
// possible monitors: whoever the current view makes Master or Observer). A monitoring node
// counts, for each watched node, the consecutive periods in which no heartbeat arrived
// (`missed`) and declares the node failed when the count reaches the mission's miss limit
// (DeclareFailed). A heartbeat whose `incarnation` grew also declares the node failed: it
// restarted and lost its volatile state. So does the first heartbeat heard from a node
// when its incarnation is above 1 (it restarted before this node first heard it), and a
// heartbeat of a new boot (`boot`, a number each boot draws at random) whatever its
// incarnation: a node whose saved incarnation went back (a lost write, a restored file,
// --cold-start in a live cluster) restarted all the same. A heartbeat of a boot this monitor
// saw end is stale (it was overtaken by the next boot's) and is dropped unheard
// (retired_boot()).
//
// Start-up grace: real processes do not start at the same instant. A node this monitor has
// never heard since this node booted (`heardOnce` in the trace vars: every node one of
// whose heartbeats reached this node since its boot, whether or not it was monitoring
// then) is declared only after Topology::startup_grace_periods() missed periods instead
// of miss_limit; once heard, the normal miss_limit counting applies. "Since this node
// booted" means: a monitor that starts watching later (set_watch, e.g. an Observer that
// takes over, or a Worker a new view makes Observer) keeps what it heard before, so a
// node it has heard is counted with miss_limit; a node restarted with PersistentState
// starts with heardOnce empty (it cannot know who is up yet). A node proved alive by a
// Command (forget) counts as heard.
//
// Ordering contract (the caller, NodeProtocol, honours it; a direct user must too):
//  1. Call period_boundary(now) exactly once per period, at the node's period boundaries
//     (phase_start + k * period, see next_boundary_ns()), with non-decreasing `now`. It runs
//     the spec's Tick for the period that ends (updating `missed` from `heard` and
//     declaring), then SendHeartbeat for the period that begins.
//  2. Call receive_heartbeat() for every heartbeat that arrives, in arrival order, between
//     boundaries. Heartbeats are never stale: they count whatever their epoch.
//  3. Call set_watch() whenever the node's view changes. Starting to monitor skips the
//     first (partial) period so a fresh monitor does not count a period it did not see.
// Self-suspicion (fault model 2, spec/Exclusion.tla rule 1): a period in which this monitor
// heard no other node's heartbeat (watched or not), or whose boundary it reached more than
// half a period late, is not counted against anyone: a deaf or CPU-starved monitor
// suspects itself before it suspects others. Its Tick trace line then carries `suspect`
// (with `late` and `silent`); the nodes it heard restart their counts from zero, and no
// other count changes.
// Declarations are permanent except through forget(), which the node calls when a node it
// declared proves alive (it commanded this node, or was heard again before the Master
// excluded it).
// Acknowledgements (fault model 2's lease, spec/Lease.tla): heartbeats are numbered
// (`seq`), and a processing node's heartbeat acknowledges the last heartbeat it heard
// from each node it watches and has not declared (a monitor's goes to every node, and a
// monitor also replies to each heartbeat at once). A node keeps, for
// each sender, the send time of its own latest heartbeat that sender acknowledged
// (acked_at): the sender heard it then or later, so it cannot declare this node before
// acked_at + miss_limit periods. NodeProtocol derives the lease from these times.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>

#include "core/fsm/actions.hpp"
#include "core/fsm/mutants.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

class HeartbeatMonitor {
public:
    // `boot`: this boot's random identifier, sent in every heartbeat.
    HeartbeatMonitor(const Topology& topology, NodeId self, std::uint32_t incarnation,
                     TimeNs phase_start_ns, Mutant mutant, std::uint32_t boot = 0);

    TimeNs next_boundary_ns() const { return next_boundary_ns_; }

    // Whether this node monitors, and whom: every node but itself and the view's failed.
    void set_watch(bool monitoring, NodeSet watched);
    // Adds nodes the cluster excluded to the declared set (they are no longer watched).
    void adopt_failed(NodeSet failed);
    // Forgets a declaration (the node proved it is alive, which counts as heard in the
    // period under way); counting restarts from zero. The withdrawal is traced (Withdraw):
    // a declaration withdrawn is no evidence any more.
    // Declarations for a restart or a self-reported exclusion are never forgotten: being
    // heard again proves nothing there.
    void forget(NodeId node, Outbox& out);
    bool forgettable(NodeId node) const { return failed_.contains(node) && !permanent_.contains(node); }
    // Reintegration (spec/Rejoin.tla, rule 4): the cluster readmitted `node` in a view of
    // `epoch` (a readmission always opens an epoch). Whatever this monitor counted and
    // declared of it is forgotten (a permanent declaration too), and counting restarts
    // from zero. `excluded` in its heartbeats is its word again only from that epoch on:
    // before, it had not adopted the view that readmits it. Traced as heartbeat.Readmit.
    void readmit(NodeId node, Epoch epoch, Outbox& out);
    // This node was readmitted: what it declared while it was out of the cluster (cut
    // off, it may have declared everyone) is no evidence. Every declaration but `keep`
    // (the cluster's exclusions) is dropped, and every count restarts from zero. Traced as
    // heartbeat.Rejoin.
    void forget_declarations(NodeSet keep, Epoch epoch, Outbox& out);
    // The Master readmits `node` at `now`: the node counts this Master's missed periods
    // from zero once the view reaches it, so it cannot declare this Master before `now`
    // plus miss_limit periods, as if it had acknowledged a heartbeat sent now.
    void assume_acked(NodeId node, TimeNs now, Epoch epoch);
    // Whether this node knows itself out of the cluster, as its replies say it between
    // its heartbeats (its heartbeats say what period_boundary is told).
    void set_excluded(bool excluded) { excluded_ = excluded; }
    // Whether this node booted from its saved state and no Command has reached it since
    // (its heartbeats say `waiting`).
    void set_waiting(bool waiting) { waiting_ = waiting; }
    // The boot before this one (saved with the node's state; 0: none), in every heartbeat.
    void set_previous_boot(std::uint32_t boot) { previous_boot_ = boot; }
    // The mission image this node flies (Heartbeat::image), in every heartbeat.
    void set_image(std::uint64_t image) { image_ = image; }
    // What this node's heartbeats say of the ground's vote for it (Heartbeat::vote_left_ms).
    void set_vote_left_ms(std::uint32_t ms) { vote_left_ms_ = ms; }
    // The number of this node's latest heartbeat (0: none sent yet).
    std::uint32_t seq() const { return seq_; }
    // The send time of this boot's heartbeat `seq`, while it is among the last kSentKept.
    std::optional<TimeNs> sent_at(std::uint32_t seq) const {
        const std::uint32_t slot = seq % kSentKept;
        if (seq == 0 || sent_seq_[slot] != seq) return std::nullopt;
        return sent_at_[slot];
    }

    // Another message (a Command, an ack, a checkpoint...) arrived from `node`: it is alive,
    // which ends its start-up grace. The first time, its count of missed periods restarts
    // from zero too (it has been counted against the grace, not against miss_limit). Not a
    // heartbeat: `heard` is unchanged.
    void heard_from(NodeId node);
    // Fault model 3: `node` sent what no honest node sends (a Command this node refused as
    // no Master's: admission.hpp). It is declared failed for good, as a restart is: being
    // heard again proves nothing, and the declaration is its own word against it (no vote
    // needed). Traced as DeclareFailed with reason "wrong".
    // A Master does not readmit such a node before it restarted (wrong(): cleared by a
    // restart seen in its heartbeats, or by a readmission the cluster made).
    void declare_wrong(NodeId node, Outbox& out);
    // The view's Master, watched and not declared, left the view on its own word: its
    // heartbeats say it follows a newer epoch, and none of that epoch's Commands reached
    // this node (NodeProtocol decides when). Declared for good, as a restart is; traced as
    // DeclareFailed with reason "left".
    void declare_left(NodeId node, Outbox& out);
    const NodeSet& wrong() const { return wrong_; }
    // Whether `heartbeat` comes from a boot of its sender this monitor heard end (a later
    // boot's heartbeat came first): stale, its caller drops it unread.
    bool retired_boot(const Heartbeat& heartbeat) const;
    // ReceiveHeartbeat. Returns the node when the heartbeat shows it restarted or knows
    // itself excluded and this call declared it failed, else kNoNode. A heartbeat of a
    // retired boot changes nothing.
    NodeId receive_heartbeat(const Heartbeat& heartbeat, Epoch epoch, TimeNs now, Outbox& out);
    // Retires `boot` of `node` (a boot that ended) unless it is the one heard now or
    // already retired.
    void retire_boot(NodeId node, std::uint32_t boot);
    // Only the acknowledgements of a heartbeat (receive_heartbeat takes them too; taking
    // them twice changes nothing).
    void take_acks(const Heartbeat& heartbeat);
    // Tick then SendHeartbeat (see the contract). Returns the nodes declared failed.
    // `excluded`: this node knows the cluster excluded it (its heartbeats say so).
    NodeSet period_boundary(TimeNs now, Epoch epoch, bool excluded, Outbox& out);

    // Whether any other node's heartbeat arrived after `since` (watched or not).
    bool heard_any_since(TimeNs since) const { return last_heard_any_ns_ >= since; }
    // Whole periods of this monitor, up to the last boundary, in which no other node's
    // heartbeat arrived (watched or not): the same unit the declarations are counted in.
    int silent_periods() const { return silent_periods_; }
    // Periods this monitor did not count because it suspected itself (heard none of the
    // nodes it watches, or ran late): a reliability counter.
    std::uint64_t self_suspected_periods() const { return self_suspected_periods_; }
    bool monitoring() const { return monitoring_; }
    const NodeSet& failed() const { return failed_; }
    // The part of failed() this node has evidence for itself: its own declarations and
    // the nodes whose heartbeats said they restarted or know themselves excluded, not the
    // exclusions it adopted from a view (fault model 3: a view may lie, rule 5).
    const NodeSet& declared() const { return declared_; }
    const NodeSet& heard() const { return heard_; }
    // Every node whose heartbeat arrived in the period that ended at the last boundary,
    // watched or not.
    const NodeSet& heard_last_period() const { return heard_last_period_; }
    const NodeSet& watched() const { return watched_; }
    int missed(NodeId node) const { return static_cast<int>(missed_[node]); }
    // Nodes heard at least once since this node booted (see the start-up grace above).
    const NodeSet& heard_once() const { return heard_once_; }
    // Missed periods that declare `node`: miss_limit once heard, the grace before.
    int declare_after(NodeId node) const {
        return heard_once_.contains(node) ? declare_at_ : grace_at_;
    }
    std::uint32_t incarnation() const { return incarnation_; }
    std::uint32_t boot() const { return boot_; }
    // The boot of `node` heard last (0: never heard, or its embedder draws none).
    std::uint32_t boot_of(NodeId node) const { return node < kMaxNodes ? boots_[node] : 0; }
    int declare_at() const { return declare_at_; }
    // The send time of this node's latest heartbeat (of this incarnation) that `node`
    // acknowledged, and the epoch of the heartbeat that carried the acknowledgement;
    // kNever before any.
    static constexpr TimeNs kNever = std::numeric_limits<TimeNs>::min();
    TimeNs acked_at(NodeId node) const { return acked_at_[node]; }
    Epoch acked_epoch(NodeId node) const { return acked_epoch_[node]; }

private:
    std::string vars_json() const;
    void declare(NodeId node, act::FailureReason reason, Outbox& out);

    const Topology* topology_;
    NodeId self_;
    std::uint32_t incarnation_;
    std::uint32_t boot_;  // this boot's identifier, in every heartbeat it sends
    TimeNs period_ns_;
    TimeNs next_boundary_ns_;
    int declare_at_;  // missed periods that make a declaration (the mission's miss limit)
    int grace_at_;    // the same for a node never heard (Topology::startup_grace_periods)
    bool monitoring_ = false;
    bool skip_next_tick_ = false;
    bool self_suspicion_ = true;  // off only in the no_self_suspicion mutant
    std::uint64_t self_suspected_periods_ = 0;
    NodeSet watched_;
    NodeSet heard_;
    NodeSet failed_;
    NodeSet declared_;  // see declared()
    NodeSet wrong_;  // declared by declare_wrong, not restarted since
    NodeSet heard_once_;
    NodeSet heard_all_;          // every sender heard in the period under way
    NodeSet heard_last_period_;  // the same for the period that ended
    NodeSet permanent_;  // declared for a restart or a self-reported exclusion
    std::array<Epoch, kMaxNodes> readmit_epoch_{};  // see readmit
    // 1 + the periods since a readmission the node has not been heard to adopt (0: none).
    std::array<int, kMaxNodes> unadopted_for_{};
    static constexpr int kUnadoptedPeriods = 3;  // in miss_limit periods (see receive)
    std::array<std::uint32_t, kMaxNodes> missed_{};
    std::array<std::uint32_t, kMaxNodes> incarnations_{};  // 0: never heard
    // Each node's boot heard with that incarnation, and the boots heard before it (the
    // last kRetiredBoots: a ring, retired_next_ counts the boots ever retired).
    static constexpr std::uint32_t kRetiredBoots = 4;
    bool boots_ignored_ = false;  // the ignore_boot mutant
    std::array<std::uint32_t, kMaxNodes> boots_{};
    std::array<std::array<std::uint32_t, kRetiredBoots>, kMaxNodes> retired_{};
    std::array<std::uint32_t, kMaxNodes> retired_next_{};
    TimeNs last_heard_any_ns_ = 0;
    // Acknowledgements: this node's heartbeats sent (seq -> send time, the last
    // kSentKept), the last heartbeat heard from each node, what each node acknowledged.
    static constexpr std::uint32_t kSentKept = 32;
    std::uint32_t seq_ = 0;
    bool excluded_ = false;  // what this node's last heartbeat said
    bool waiting_ = false;   // see set_waiting
    std::uint32_t previous_boot_ = 0;  // see set_previous_boot
    std::uint64_t image_ = 0;          // see set_image
    std::uint32_t vote_left_ms_ = 0;   // see set_vote_left_ms
    std::array<std::uint32_t, kSentKept> sent_seq_{};
    std::array<TimeNs, kSentKept> sent_at_{};
    std::array<std::uint32_t, kMaxNodes> heard_seq_{};
    std::array<TimeNs, kMaxNodes> acked_at_;
    std::array<Epoch, kMaxNodes> acked_epoch_{};
    bool heard_any_this_period_ = false;
    int silent_periods_ = 0;
};

}  // namespace keel::fsm
