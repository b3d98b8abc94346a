// Election: Master/Observer succession with epochs (spec/MasterElection.tla, fsm
// "election").
//
// Epoch e can only be claimed by Topology::owner(e), so no two nodes are ever Master of
// the same epoch. A node obeys the Master of the highest epoch it has seen: every message
// that carries an older epoch is rejected by is_stale(), which NodeProtocol::step calls in
// exactly one place, before any role-specific handling (raft's Step). An Observer that has
// declared failed the view's Master and every Observer ahead of itself becomes Master
// (BecomeMaster) in its next owned epoch; the Command of the switch it then starts is the
// announcement.
//
// Ordering contract:
//  1. Call is_stale(epoch_of(message)) for every message that has an epoch, and drop the
//     message when it returns true. Nothing else in Keel compares epochs for staleness.
//  2. Call receive_command() for every Command that passed (1), before the switch handles
//     it, so the role and the leader are current when tasks move.
//  3. Call suspect() for every node the failure detector declares (or an
//     ErrorNotification reports); when it returns true, call become_master() at once and
//     start the switch it implies. It returns true only while the caller says the node
//     may act (it hears another node, and holds two monitors' evidence on the nodes ahead
//     of it). Since both change, the caller also asks may_take_over() once per period and
//     on every report.
//  5. Call clear_suspect() when a suspected node is heard again (a heartbeat): an
//     Observer's suspicion is an opinion, not an exclusion, until the Master acts on it.
//  4. A Master that hears of an epoch above its own (heartbeats carry the sender's epoch)
//     whose owner it has declared failed calls reclaim(): the newer Master is gone, and
//     the nodes that followed it reject everything older, so this Master must move past.
// `epoch` survives a restart (the caller persists it); role, leader and suspects do not.
#pragma once

#include <utility>
#include <vector>

#include "core/fsm/actions.hpp"
#include "core/fsm/mutants.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

class Election {
public:
    // A node booting with `view` (the initial view, or the persisted one after a restart:
    // then `restarted` is true and the node starts as a Worker, as the spec's Restart).
    Election(const Topology& topology, NodeId self, const View& view, Epoch epoch,
             bool restarted, Mutant mutant);

    Role role() const { return role_; }
    Epoch epoch() const { return epoch_; }
    NodeId leader() const { return leader_; }
    NodeSet suspects() const { return suspects_; }
    Epoch last_command() const { return last_command_; }

    // The one stale-epoch check (see the contract).
    bool is_stale(Epoch message_epoch) const;

    // ReceiveCommand: adopt the command's epoch and sender as leader and take the role the
    // view gives this node (Worker when the view excludes it). A Master of a lower epoch
    // steps down here.
    void receive_command(const Command& command, Outbox& out);
    // Suspect(n, m). Returns true when this node must now BecomeMaster.
    // `may_act`: NodeProtocol's judgement that this node may act on its suspicions: it
    // heard another node in its last period (a node cut off from everyone does not take
    // over) and, fault model 2, it holds the evidence of two monitors on every node ahead
    // of it in the succession (spec/Exclusion.tla).
    // `passed`: Observers ahead of this one that go by another view under this view's id
    // (NodeProtocol::diverged): no take-over waits for them.
    bool suspect(NodeId node, const View& view, bool may_act, Outbox& out, NodeSet passed = NodeSet{});
    // Whether this node, an Observer of `view`, must now BecomeMaster.
    bool may_take_over(const View& view, bool may_act, NodeSet passed = NodeSet{}) const;
    // Whether every node ahead of this Observer in the succession of `view` is suspected,
    // excluded or passed over.
    bool ahead_all_suspected(const View& view, NodeSet passed = NodeSet{}) const;
    void clear_suspect(NodeId node) { suspects_.erase(node); }
    // The Master readmits a node in a new epoch of its own (ReconfigurationManager::readmit).
    void open_epoch(Epoch epoch, Outbox& out);
    // BecomeMaster: claims the next owned epoch; returns it. `passed`: the members it
    // passed over (ahead_all_suspected's), each with the epoch its heartbeats last said,
    // logged on the trace line (trace validation holds each below the taker's epoch, but
    // those in `newer`, whose Prepared named a newer switch of the taker's view's epoch,
    // and in `unprepared`, whose Prepared of the taker's view never reached it).
    Epoch become_master(const View& view, Outbox& out,
                        const std::vector<std::pair<NodeId, Epoch>>& passed = {}, NodeSet newer = {},
                        NodeSet unprepared = {});
    // BecomeMaster again, by a Master that learned of a newer epoch `seen` whose owner it
    // has declared failed: claims its next owned epoch above `seen`; returns it.
    Epoch reclaim(Epoch seen, Outbox& out);
    // WarmBoot (spec/MasterElection.tla): a restarted node that every other node heard
    // waiting for a Command (a whole-cluster power cycle) claims its first owned epoch
    // above `above`, the highest epoch any of them holds; returns it.
    Epoch warm_boot(Epoch above, Outbox& out);

private:
    std::string vars_json() const;

    const Topology* topology_;
    NodeId self_;
    Mutant mutant_;
    Role role_;
    Epoch epoch_;
    NodeId leader_;
    NodeSet suspects_;
    Epoch last_command_ = 0;
};

}  // namespace keel::fsm
