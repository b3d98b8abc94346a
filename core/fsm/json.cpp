#include "core/fsm/json.hpp"

#include <cmath>
#include <cstdio>

namespace keel::fsm {

JsonObject& JsonObject::version(Version version) {
    field("version", version.count);
    if (version.lineage != 0) raw("lineage", json_lineage(version.lineage));
    return *this;
}

std::string version_text(Version version) {
    std::string text = std::to_string(version.count);
    if (version.lineage != 0) {
        text += " (lineage " + std::to_string(lineage_epoch(version.lineage)) + "." +
                std::to_string(lineage_seq(version.lineage)) + ")";
    }
    return text;
}

std::string json_lineage(std::uint64_t lineage) {
    return "[" + std::to_string(lineage_epoch(lineage)) + "," + std::to_string(lineage_seq(lineage)) +
           "]";
}

void JsonObject::key(std::string_view name) {
    if (!first_) body_.push_back(',');
    first_ = false;
    append_json_string(body_, name);
    body_.push_back(':');
}

JsonObject& JsonObject::field(std::string_view name, std::int64_t value) {
    key(name);
    body_ += std::to_string(value);
    return *this;
}

JsonObject& JsonObject::field(std::string_view name, std::uint64_t value) {
    key(name);
    body_ += std::to_string(value);
    return *this;
}

JsonObject& JsonObject::field(std::string_view name, double value) {
    key(name);
    if (!std::isfinite(value)) {
        body_ += "null";
    } else {
        char buffer[64];
        std::snprintf(buffer, sizeof buffer, "%.6g", value);
        body_ += buffer;
    }
    return *this;
}

JsonObject& JsonObject::field(std::string_view name, bool value) {
    key(name);
    body_ += value ? "true" : "false";
    return *this;
}

JsonObject& JsonObject::field(std::string_view name, std::string_view value) {
    key(name);
    append_json_string(body_, value);
    return *this;
}

JsonObject& JsonObject::raw(std::string_view name, std::string_view json) {
    key(name);
    body_ += json;
    return *this;
}

std::string json_nodes(const Topology& topology, NodeSet nodes) {
    std::string out = "[";
    bool first = true;
    nodes.for_each([&](NodeId id) {
        if (!first) out.push_back(',');
        first = false;
        append_json_string(out, id < topology.node_count() ? topology.node_name(id) : "?");
    });
    out.push_back(']');
    return out;
}

std::string json_tasks(const Topology& topology, TaskSet tasks) {
    std::string out = "[";
    bool first = true;
    tasks.for_each([&](TaskId id) {
        if (!first) out.push_back(',');
        first = false;
        append_json_string(out, id < topology.task_count() ? topology.task(id).name : "?");
    });
    out.push_back(']');
    return out;
}

std::string json_node(const Topology& topology, NodeId node) {
    if (node == kNoNode || node >= topology.node_count()) return "null";
    std::string out;
    append_json_string(out, topology.node_name(node));
    return out;
}

}  // namespace keel::fsm
