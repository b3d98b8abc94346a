// The mission model's lookups and the loader's errors.
#include <algorithm>
#include <string>

#include "core/mission/mission.hpp"

namespace keel::mission {

bool Node::has_capability(const std::string& capability) const {
    return std::find(capabilities.begin(), capabilities.end(), capability) != capabilities.end();
}

const std::string* Configuration::node_of(const std::string& task) const {
    for (const auto& [placed, node] : placement) {
        if (placed == task) return &node;
    }
    return nullptr;
}

const Configuration* Phase::configuration(const std::string& wanted) const {
    for (const Configuration& c : configurations) {
        if (c.name == wanted) return &c;
    }
    return nullptr;
}

const FailureEdge* Phase::failure_edge(const std::string& config, const std::string& node) const {
    for (const FailureEdge& edge : on_failure) {
        if (edge.config == config && edge.node == node) return &edge;
    }
    return nullptr;
}

const FailureEdge* Phase::recovery_edge(const std::string& config, const std::string& node) const {
    for (const FailureEdge& edge : on_recovery) {
        if (edge.config == config && edge.node == node) return &edge;
    }
    return nullptr;
}

const PhaseEdge* Phase::phase_edge(const std::string& target_phase,
                                   const std::string& config) const {
    for (const PhaseEdge& edge : on_phase) {
        if (edge.phase == target_phase && edge.from == config) return &edge;
    }
    return nullptr;
}

const Node* Mission::node(const std::string& wanted) const {
    for (const Node& n : nodes) {
        if (n.name == wanted) return &n;
    }
    return nullptr;
}

const Task* Mission::task(const std::string& wanted) const {
    for (const Task& t : tasks) {
        if (t.name == wanted) return &t;
    }
    return nullptr;
}

const Phase* Mission::phase(const std::string& wanted) const {
    for (const Phase& p : phases) {
        if (p.name == wanted) return &p;
    }
    return nullptr;
}

const Configuration* Mission::configuration(const std::string& wanted) const {
    for (const Phase& p : phases) {
        if (const Configuration* c = p.configuration(wanted)) return c;
    }
    return nullptr;
}

int Mission::address_of(const std::string& node) const {
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        if (nodes[i].name == node) return static_cast<int>(i);
    }
    return -1;
}

std::vector<std::string> Mission::processing_nodes() const {
    std::vector<std::string> out;
    for (const Node& n : nodes) {
        if (n.is_processing()) out.push_back(n.name);
    }
    return out;
}

std::vector<std::string> Mission::storage_nodes() const {
    std::vector<std::string> out;
    for (const Node& n : nodes) {
        if (n.is_storage()) out.push_back(n.name);
    }
    return out;
}

std::string LoadError::to_string() const {
    return file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": " + rule + ": " +
           message;
}

bool LoadError::is_input_error() const {
    return rule != "unknown-reference" && rule != "port-conflict";
}

int LoadResult::exit_code() const {
    if (ok()) return 0;
    for (const LoadError& e : errors) {
        if (e.is_input_error()) return 2;
    }
    return 1;
}

}  // namespace keel::mission
