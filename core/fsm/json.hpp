// A small JSON object writer for trace events and reports: keys in insertion order, no
// allocation beyond the output string, strings escaped.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "core/fsm/topology.hpp"
#include "core/mission/json_string.hpp"

namespace keel::fsm {

class JsonObject {
public:
    JsonObject& field(std::string_view key, std::int64_t value);
    JsonObject& field(std::string_view key, std::uint64_t value);
    JsonObject& field(std::string_view key, int value) { return field(key, std::int64_t{value}); }
    JsonObject& field(std::string_view key, unsigned value) { return field(key, std::uint64_t{value}); }
    JsonObject& field(std::string_view key, double value);
    JsonObject& field(std::string_view key, bool value);
    JsonObject& field(std::string_view key, std::string_view value);
    JsonObject& field(std::string_view key, const char* value) { return field(key, std::string_view(value)); }
    // `json` must already be a JSON value.
    JsonObject& raw(std::string_view key, std::string_view json);
    // A task state's version: "version" (its count) and, for a lineage other than the
    // initial one, "lineage" ([epoch, seq]).
    JsonObject& version(Version version);
    std::string str() const { return body_ + "}"; }

private:
    void key(std::string_view name);
    std::string body_ = "{";
    bool first_ = true;
};

// The one JSON string writer (core/mission/json_string.hpp).
using mission::append_json_string;
// ["PN1","PN2"] in id order.
std::string json_nodes(const Topology& topology, NodeSet nodes);
std::string json_tasks(const Topology& topology, TaskSet tasks);
std::string json_node(const Topology& topology, NodeId node);  // "PN1" or null
std::string json_lineage(std::uint64_t lineage);  // [epoch,seq]
// "12", or "12 (lineage 3.2)" for a lineage other than the initial one.
std::string version_text(Version version);

}  // namespace keel::fsm
