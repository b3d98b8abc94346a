// The mission model's lookups, the loader's errors, and the normalised JSON form.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <variant>

#include "core/mission/mission.hpp"
#include "core/mission/yaml_source.hpp"

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

// --------------------------------------------------------------------------------------
// JSON, printed the way Python's json.dumps prints (ASCII only, floats as repr()).

namespace {

class JsonWriter {
public:
    std::string out;

    void string(const std::string& text) {
        out += '"';
        std::size_t i = 0;
        while (i < text.size()) {
            const auto byte = static_cast<unsigned char>(text[i]);
            if (byte < 0x80) {
                switch (byte) {
                    case '"':
                        out += "\\\"";
                        break;
                    case '\\':
                        out += "\\\\";
                        break;
                    case '\n':
                        out += "\\n";
                        break;
                    case '\r':
                        out += "\\r";
                        break;
                    case '\t':
                        out += "\\t";
                        break;
                    case '\b':
                        out += "\\b";
                        break;
                    case '\f':
                        out += "\\f";
                        break;
                    default:
                        if (byte < 0x20) {
                            escape(byte);
                        } else {
                            out += static_cast<char>(byte);
                        }
                }
                ++i;
                continue;
            }
            // Loaded text is valid UTF-8 (the loader checks it).
            std::size_t length = byte < 0xE0 ? 2 : byte < 0xF0 ? 3 : 4;
            char32_t cp = byte & (length == 2 ? 0x1Fu : length == 3 ? 0x0Fu : 0x07u);
            for (std::size_t k = 1; k < length && i + k < text.size(); ++k) {
                cp = (cp << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3Fu);
            }
            if (cp >= 0x10000) {
                const char32_t v = cp - 0x10000;
                escape(0xD800 + (v >> 10));
                escape(0xDC00 + (v & 0x3FF));
            } else {
                escape(cp);
            }
            i += length;
        }
        out += '"';
    }

    void integer(std::int64_t value) { out += std::to_string(value); }

    void number(double value) {
        if (std::isnan(value)) {
            out += "NaN";
        } else if (std::isinf(value)) {
            out += value > 0 ? "Infinity" : "-Infinity";
        } else {
            out += detail::python_float_repr(value);
        }
    }

    void null() { out += "null"; }
    void boolean(bool value) { out += value ? "true" : "false"; }

    void optional_integer(const std::optional<std::int64_t>& value) {
        if (value) {
            integer(*value);
        } else {
            null();
        }
    }
    void optional_number(const std::optional<double>& value) {
        if (value) {
            number(*value);
        } else {
            null();
        }
    }

    void strings(const std::vector<std::string>& values) {
        out += '[';
        for (std::size_t i = 0; i < values.size(); ++i) {
            if (i > 0) out += ", ";
            string(values[i]);
        }
        out += ']';
    }

    void key(const char* name) {
        string(name);
        out += ": ";
    }

    // {"a": "x", "b": "y", "c": "z"}: one edge of the decision graph or the phase map.
    void string_triple(const char* k1, const std::string& v1, const char* k2,
                       const std::string& v2, const char* k3, const std::string& v3) {
        out += '{';
        key(k1);
        string(v1);
        out += ", ";
        key(k2);
        string(v2);
        out += ", ";
        key(k3);
        string(v3);
        out += '}';
    }

private:
    void escape(char32_t unit) {
        char buffer[16];
        std::snprintf(buffer, sizeof buffer, "\\u%04x", static_cast<unsigned>(unit));
        out += buffer;
    }
};

void write_resources(JsonWriter& w, const Resources& r) {
    w.out += '{';
    w.key("cpu");
    w.optional_integer(r.cpu);
    w.out += ", ";
    w.key("mem_mb");
    w.optional_integer(r.mem_mb);
    w.out += '}';
}

void write_params(JsonWriter& w, const Params& params) {
    w.out += '{';
    for (std::size_t i = 0; i < params.size(); ++i) {
        if (i > 0) w.out += ", ";
        w.string(params[i].first);
        w.out += ": ";
        std::visit(
            [&](const auto& value) {
                using T = std::decay_t<decltype(value)>;
                if constexpr (std::is_same_v<T, std::string>) {
                    w.string(value);
                } else if constexpr (std::is_same_v<T, std::int64_t>) {
                    w.integer(value);
                } else if constexpr (std::is_same_v<T, double>) {
                    w.number(value);
                } else {
                    w.boolean(value);
                }
            },
            params[i].second);
    }
    w.out += '}';
}

}  // namespace

std::string to_json(const Mission& mission) {
    JsonWriter w;
    w.out += "{\n  ";
    w.key("mission");
    w.string(mission.name);
    w.out += ",\n  ";
    w.key("schema");
    w.integer(1);
    w.out += ",\n  ";
    w.key("heartbeat");
    w.out += '{';
    w.key("period_ms");
    w.integer(mission.heartbeat.period_ms);
    w.out += ", ";
    w.key("miss_limit");
    w.integer(mission.heartbeat.miss_limit);
    w.out += ", ";
    w.key("startup_grace_ms");
    w.integer(mission.heartbeat.startup_grace_ms);
    w.out += "},\n  ";
    w.key("tolerance");
    w.out += '{';
    w.key("node_failures");
    w.integer(mission.tolerance.node_failures);
    w.out += ", ";
    w.key("nodes");
    w.strings(mission.tolerance.nodes);
    w.out += "},\n  ";

    w.key("nodes");
    w.out += '[';
    for (std::size_t i = 0; i < mission.nodes.size(); ++i) {
        const Node& n = mission.nodes[i];
        w.out += i > 0 ? ",\n    {" : "\n    {";
        w.key("name");
        w.string(n.name);
        w.out += ", ";
        w.key("kind");
        w.string(n.kind == NodeKind::processing ? "processing" : "interface");
        w.out += ", ";
        w.key("role");
        if (n.role == NodeRole::none) {
            w.null();
        } else {
            w.string(n.role == NodeRole::storage ? "storage" : "interface");
        }
        w.out += ", ";
        w.key("capabilities");
        w.strings(n.capabilities);
        w.out += ", ";
        w.key("capacity");
        write_resources(w, n.capacity);
        w.out += '}';
    }
    w.out += "],\n  ";

    w.key("tasks");
    w.out += '[';
    for (std::size_t i = 0; i < mission.tasks.size(); ++i) {
        const Task& t = mission.tasks[i];
        w.out += i > 0 ? ",\n    {" : "\n    {";
        w.key("name");
        w.string(t.name);
        w.out += ", ";
        w.key("port");
        w.integer(t.port);
        w.out += ", ";
        w.key("component");
        w.string(t.component);
        w.out += ", ";
        w.key("requires");
        w.strings(t.requires_capabilities);
        w.out += ", ";
        w.key("load");
        write_resources(w, t.load);
        w.out += ", ";
        w.key("essential");
        w.boolean(t.essential);
        w.out += ", ";
        w.key("checkpoint");
        w.boolean(t.checkpoint);
        w.out += ", ";
        w.key("inputs");
        w.strings(t.inputs);
        w.out += ", ";
        w.key("period_ms");
        w.optional_integer(t.period_ms);
        w.out += ", ";
        w.key("health");
        if (t.health) {
            w.out += '{';
            w.key("min");
            w.optional_number(t.health->min);
            w.out += ", ";
            w.key("max");
            w.optional_number(t.health->max);
            w.out += ", ";
            w.key("deadline_ms");
            w.optional_integer(t.health->deadline_ms);
            w.out += '}';
        } else {
            w.null();
        }
        w.out += ", ";
        w.key("params");
        write_params(w, t.params);
        w.out += '}';
    }
    w.out += "],\n  ";

    w.key("phases");
    w.out += '[';
    for (std::size_t i = 0; i < mission.phases.size(); ++i) {
        const Phase& p = mission.phases[i];
        w.out += i > 0 ? ",\n    {" : "\n    {";
        w.key("name");
        w.string(p.name);
        w.out += ", ";
        w.key("tasks");
        w.strings(p.tasks);
        w.out += ", ";
        w.key("initial");
        w.string(p.initial);
        w.out += ",\n     ";
        w.key("configurations");
        w.out += '[';
        for (std::size_t c = 0; c < p.configurations.size(); ++c) {
            const Configuration& config = p.configurations[c];
            w.out += c > 0 ? ",\n       {" : "\n       {";
            w.key("name");
            w.string(config.name);
            w.out += ", ";
            w.key("master");
            w.string(config.master);
            w.out += ", ";
            w.key("observers");
            w.strings(config.observers);
            w.out += ", ";
            w.key("tasks");
            w.out += '[';
            for (std::size_t t = 0; t < config.placement.size(); ++t) {
                if (t > 0) w.out += ", ";
                w.out += '[';
                w.string(config.placement[t].first);
                w.out += ", ";
                w.string(config.placement[t].second);
                w.out += ']';
            }
            w.out += "]}";
        }
        w.out += "],\n     ";
        auto write_edges = [&w](const char* key, const std::vector<FailureEdge>& edges) {
            w.key(key);
            w.out += '[';
            for (std::size_t e = 0; e < edges.size(); ++e) {
                w.out += e > 0 ? ",\n       " : "\n       ";
                w.string_triple("config", edges[e].config, "node", edges[e].node, "next",
                                edges[e].next);
            }
            w.out += "],\n     ";
        };
        write_edges("on_failure", p.on_failure);
        // Absent when empty, as keel-verify load prints it.
        if (!p.on_recovery.empty()) write_edges("on_recovery", p.on_recovery);
        w.key("on_phase");
        w.out += '[';
        for (std::size_t e = 0; e < p.on_phase.size(); ++e) {
            const PhaseEdge& edge = p.on_phase[e];
            w.out += e > 0 ? ",\n       " : "\n       ";
            w.string_triple("phase", edge.phase, "from", edge.from, "to", edge.to);
        }
        w.out += "],\n     ";
        w.key("params");
        w.out += '{';
        for (std::size_t t = 0; t < p.params.size(); ++t) {
            if (t > 0) w.out += ", ";
            w.string(p.params[t].first);
            w.out += ": ";
            write_params(w, p.params[t].second);
        }
        w.out += "}}";
    }
    w.out += "]\n}";
    return w.out;
}

}  // namespace keel::mission
