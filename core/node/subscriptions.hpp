// Subscriptions: where each task's outputs must go in the current view — the interface
// node's subscription lists, kept by every node so that a producer addresses its samples to
// the nodes hosting its consumers (logical address + port, as in the paper).
//
// Rebuilt from the view on every reconfiguration (update()); a lookup is one vector index.
#pragma once

#include <string>
#include <vector>

#include "core/fsm/topology.hpp"

namespace keel::node {

class Subscriptions {
public:
    explicit Subscriptions(const keel::mission::Mission& mission, const fsm::Topology& topology);

    // Recomputes the lists for `view`. Returns true when any list changed.
    bool update(const fsm::View& view);

    // The nodes hosting a consumer of `producer` in the current view, in id order.
    const std::vector<fsm::NodeId>& destinations(fsm::TaskId producer) const {
        return destinations_.at(producer);
    }
    // "taskA(100) -> PN3; taskB(101) -> none", for logs.
    std::string describe() const;

private:
    const fsm::Topology* topology_;
    std::vector<std::vector<fsm::TaskId>> consumers_;  // per producer
    std::vector<std::int64_t> ports_;
    std::vector<std::vector<fsm::NodeId>> destinations_;
};

}  // namespace keel::node
