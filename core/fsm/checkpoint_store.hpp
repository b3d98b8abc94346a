// CheckpointStore: the Storage node's logic (the paper's checkpointing service; the
// `stored` variable of spec/ConfigSwitch.tla).
//
// It keeps the latest checkpoint per task, and versions only grow, lineage first (types.hpp,
// Version): a write whose version is not above the stored one changes nothing (a late, reordered or duplicated write
// cannot roll a task back). It refuses writes from nodes the cluster has excluded, so a
// node falsely declared failed — still running a task that has moved — cannot overwrite
// the state its successor resumes from. It refuses a write of a task that is not
// checkpointed, from a node the mission never places the task on (Topology::may_host), or
// with a state above the task's max_state_bytes: no honest node sends one (a node never
// sends a state above the bound), and it is counted (refused_writes). Final writes (the flush after a deactivation) are
// acknowledged, with the version now stored, so the writer knows it may ack Prepared.
//
// A node the mission may place a task on, but that does not host it, can still write a
// version far above the host's (fault model 3: a value fault, {lineage, 2^62}); by the
// rule above it would pin the task, every later honest write superseded. So the host's
// word wins over a foreign one: a periodic write (not a final one) from the task's host in
// the Storage node's current view, sent in that view's epoch, replaces a stored state whose
// writer hosts the task in neither that view nor the one before it, or is unknown (a
// record read back from disk) (`overridden`). An honest cluster never takes this branch:
// a running host started from the newest state there was, so its periodic writes are
// newer than any other node's (keel-sim's NoHonestRefusalInv holds the counter to 0; no
// spec models this rule: docs/fault-model.md, "Not covered"). A final write is left out:
// it flushes a hand-off, which may be older than one another node made since (after the
// Storage node's readmission both are flushed). The host of the view before is the one
// that handed the task over; its late writes may still arrive.
//
// Requests are answered within a RequestBudget (request_budget.hpp): a reply carries a
// whole state for a request of a few bytes.
//
// Ordering contract: call set_view() with the Storage node's view whenever it changes,
// before handling further writes; handle writes and requests in
// arrival order. The store is the Storage node's durable state: the caller persists each
// StoreCheckpoint action and passes the records back after a restart.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/fsm/actions.hpp"
#include "core/fsm/request_budget.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

struct StoredCheckpoint {
    TaskId task = 0;
    Version version;
    std::vector<std::uint8_t> state;
    friend bool operator==(const StoredCheckpoint&, const StoredCheckpoint&) = default;
};

class CheckpointStore {
public:
    CheckpointStore(const Topology& topology, NodeId self);

    // The Storage node's view: who is excluded, who hosts each task (and hosted it in the
    // view before).
    void set_view(const View& view);
    // Records of tasks this mission does not checkpoint, or above its max_state_bytes, are
    // left out.
    void restore(const std::vector<StoredCheckpoint>& records);

    // Returns true when the write became the latest checkpoint of its task.
    bool receive_write(const CheckpointWrite& write, Outbox& out);
    // `view`: the Storage node's own view; `now`: the time of receipt.
    void receive_request(const CheckpointRequest& request, const View& view, TimeNs now,
                         Outbox& out);

    std::optional<Version> latest_version(TaskId task) const;
    // Writes of a task that is not checkpointed, from a node the mission never places the
    // task on, or with a state above the task's max_state_bytes.
    std::uint64_t refused_writes() const { return refused_writes_; }
    // Stored states of a writer that hosted the task in neither of the Storage node's last
    // two views, replaced by the host's older write (see above): a value fault seen.
    std::uint64_t overridden() const { return overridden_; }
    // Requests refused and left unanswered (request_budget.hpp).
    const RequestBudget& request_budget() const { return budget_; }
    std::vector<StoredCheckpoint> records() const;
    // A restarted Storage node's trace: one Recovered line per checkpointed task with the
    // version it read back from its disk (0: none), which trace validation holds to every
    // StoreCheckpoint line before it (a line that stood for a write the disk lost is
    // caught there: core/node/driver.hpp, rule 2).
    void trace_recovered(Outbox& out) const;

private:
    std::string stored_json(TaskId task) const;
    bool host_wins(const CheckpointWrite& write) const;

    const Topology* topology_;
    NodeId self_;
    NodeSet excluded_;
    std::optional<View> view_;
    std::optional<View> previous_view_;
    // Per task of the mission (Topology::task_count entries).
    std::vector<bool> present_;
    std::vector<Version> version_;
    std::vector<std::vector<std::uint8_t>> state_;
    std::vector<NodeId> writer_;  // of the stored state; kNoNode when read back from disk
    std::uint64_t refused_writes_ = 0;
    std::uint64_t overridden_ = 0;
    RequestBudget budget_;
};

}  // namespace keel::fsm
