// RequestBudget: what a checkpoint request buys from the node that answers it.
//
// A CheckpointRequest is a few bytes and its CheckpointReply a whole state: answered without
// bound, requests make the answering node (the Storage node's CheckpointStore, or a node
// holding a hand-off, ConfigSwitch::answer_checkpoint_request) an amplifier for any node
// that floods them. So:
//  - only a node the mission may place the task on is answered (Topology::may_host): no
//    honest node asks for a task it is never placed on (refused());
//  - per asking node and task, the first request of the answering node's own switch is
//    answered at once (one per switch it adopts);
//  - any other request (a retransmission, a node resuming a task it held, a switch the
//    answering node has not adopted: keys the requester chooses, so they buy nothing) draws
//    on a budget of kBurst replies refilled one per half heartbeat period (GCRA: `due` is
//    when the budget is full again); beyond it, the request is left unanswered (limited()).
// An honest node asks once per switch, once when it resumes a held task and once a period
// while it waits: well inside the budget. To the specs a request left unanswered is a lost
// message, which the requester's retransmission covers.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/fsm/messages.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

class RequestBudget {
public:
    static constexpr TimeNs kBurst = 4;

    explicit RequestBudget(const Topology& topology)
        : topology_(&topology),
          asked_(static_cast<std::size_t>(topology.node_count()) *
                 static_cast<std::size_t>(topology.task_count())) {}

    // True when `request` (task and sender already checked in range) may be answered now, by
    // a node in `view`; false when it is refused or limited (and counted).
    bool admit(const CheckpointRequest& request, const View& view, TimeNs now) {
        if (!topology_->may_host(request.task).contains(request.from)) {
            ++refused_;
            return false;
        }
        Asked& last = asked_[static_cast<std::size_t>(request.from) *
                                 static_cast<std::size_t>(topology_->task_count()) +
                             request.task];
        const bool current = request.epoch == view.epoch && request.seq == view.seq;
        if (current && (!last.any || newer_than(view.epoch, view.seq, last.epoch, last.seq))) {
            last.any = true;
            last.epoch = view.epoch;
            last.seq = view.seq;
            return true;
        }
        const TimeNs interval = topology_->heartbeat_period_ns() / 2;
        if (now < last.due - (kBurst - 1) * interval) {
            ++limited_;
            return false;
        }
        last.due = std::max(last.due, now) + interval;
        return true;
    }

    // Requests from a node the mission never places the task on.
    std::uint64_t refused() const { return refused_; }
    // Requests beyond the budget.
    std::uint64_t limited() const { return limited_; }

private:
    struct Asked {
        bool any = false;  // a first request of a switch was answered
        Epoch epoch = 0;
        Seq seq = 0;
        TimeNs due = 0;
    };
    const Topology* topology_;
    std::vector<Asked> asked_;  // per asking node and task: node * task_count + task
    std::uint64_t refused_ = 0;
    std::uint64_t limited_ = 0;
};

}  // namespace keel::fsm
