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
// A reply carries a whole state for a request of a few bytes, so requests are bounded too:
// only a node the mission may place the task on asks for it (others are refused, and
// counted with the writes), and per asking node and task the store answers a request of a
// switch it has adopted and that node has not asked about before at once, anything else
// (a retransmission, a node resuming a task it held, a switch the store has not adopted)
// from a budget of 4 replies refilled one per half heartbeat period (limited_requests). An
// honest node asks once per switch, once when it resumes a held task, and once a period
// while it waits, well inside the budget; an insider's flood of requests gets two replies a
// period per task it may host, after the first 4.
//
// Ordering contract: call set_excluded() with the view's failed set whenever the Storage
// node's view changes, before handling further writes; handle writes and requests in
// arrival order. The store is the Storage node's durable state: the caller persists each
// StoreCheckpoint action and passes the records back after a restart.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/fsm/actions.hpp"
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

    void set_excluded(NodeSet failed) { excluded_ = failed; }
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
    // Requests from a node the mission never places the task on.
    std::uint64_t refused_requests() const { return refused_requests_; }
    // Requests left unanswered by the bound above (the requester asks again).
    std::uint64_t limited_requests() const { return limited_requests_; }
    std::vector<StoredCheckpoint> records() const;

private:
    std::string stored_json(TaskId task) const;

    const Topology* topology_;
    NodeId self_;
    NodeSet excluded_;
    // Per task of the mission (Topology::task_count entries).
    std::vector<bool> present_;
    std::vector<Version> version_;
    std::vector<std::vector<std::uint8_t>> state_;
    std::uint64_t refused_writes_ = 0;
    std::uint64_t refused_requests_ = 0;
    std::uint64_t limited_requests_ = 0;
    // Replies beyond the first of a switch, at once, per asking node and task.
    static constexpr TimeNs kRequestBurst = 4;
    // Per asking node and task (node * task_count + task): the last switch answered as its
    // first, and when the budget of other replies is full again.
    struct Answered {
        bool any = false;
        Epoch epoch = 0;
        Seq seq = 0;
        TimeNs due = 0;
    };
    std::vector<Answered> answered_;
};

}  // namespace keel::fsm
