#include "core/node/subscriptions.hpp"

#include <algorithm>

namespace keel::node {

Subscriptions::Subscriptions(const keel::mission::Mission& mission, const fsm::Topology& topology)
    : topology_(&topology),
      consumers_(static_cast<std::size_t>(topology.task_count())),
      ports_(static_cast<std::size_t>(topology.task_count()), 0),
      destinations_(static_cast<std::size_t>(topology.task_count())) {
    for (std::size_t consumer = 0; consumer < mission.tasks.size(); ++consumer) {
        ports_[consumer] = mission.tasks[consumer].port;
        for (const std::string& input : mission.tasks[consumer].inputs) {
            if (auto producer = topology.task_id(input)) {
                consumers_[*producer].push_back(static_cast<fsm::TaskId>(consumer));
            }
        }
    }
}

bool Subscriptions::update(const fsm::View& view) {
    bool changed = false;
    for (std::size_t producer = 0; producer < consumers_.size(); ++producer) {
        std::vector<fsm::NodeId> nodes;
        for (const fsm::TaskId consumer : consumers_[producer]) {
            const fsm::NodeId host = topology_->host(view, consumer);
            if (host != fsm::kNoNode) nodes.push_back(host);
        }
        std::sort(nodes.begin(), nodes.end());
        nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
        if (nodes != destinations_[producer]) {
            destinations_[producer] = std::move(nodes);
            changed = true;
        }
    }
    return changed;
}

std::string Subscriptions::describe() const {
    std::string text;
    for (std::size_t producer = 0; producer < consumers_.size(); ++producer) {
        if (consumers_[producer].empty()) continue;
        if (!text.empty()) text += "; ";
        text += topology_->task(static_cast<fsm::TaskId>(producer)).name + "(" +
                std::to_string(ports_[producer]) + ") ->";
        if (destinations_[producer].empty()) text += " none";
        for (const fsm::NodeId node : destinations_[producer]) text += " " + topology_->node_name(node);
    }
    return text.empty() ? "no subscriptions" : text;
}

}  // namespace keel::node
