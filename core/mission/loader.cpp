// The mission loader: the four steps of config/schema/README.md, in the same order and
// with the same errors as verify/keel_verify/mission.py.
//
//   1. parse       YAML syntax, duplicate keys            (yaml_source.cpp)
//   2. schema      mission.schema.json, checked by hand   (check_schema)
//   3. rules       what the schema cannot say             (check_rules)
//   4. references  names and ports                        (check_references)
//
// Each step reports every error it finds; a step runs only when the steps before it found
// nothing. Messages are worded as the Python reader words them.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "core/mission/image.hpp"
#include "core/mission/mission.hpp"
#include "core/mission/yaml_source.hpp"

namespace keel::mission {
namespace {

using detail::Position;
using detail::Value;
using Type = Value::Type;

class Errors {
public:
    explicit Errors(const std::string& file) : file_(file) {}

    void add(Position position, std::string rule, std::string message) {
        errors_.push_back(
            LoadError{file_, position.line, position.col, std::move(rule), std::move(message)});
    }
    bool empty() const { return errors_.empty(); }
    std::vector<LoadError>& list() { return errors_; }

private:
    const std::string& file_;
    std::vector<LoadError> errors_;
};

// `a.b.0.c`, as `_where` joins a path; "the file" for the root.
std::string where(const std::string& path) { return path.empty() ? "the file" : path; }

std::string child(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
}

std::string child(const std::string& path, std::size_t index) {
    return child(path, std::to_string(index));
}

std::string python_number(const Value& value) {
    return value.type == Type::integer ? std::to_string(value.integer)
                                       : detail::python_float_repr(value.number);
}

// `_describe`: how a message names a value.
std::string describe(const Value& value) {
    switch (value.type) {
        case Type::null:
            return "null";
        case Type::boolean:
            return "a boolean";
        case Type::integer:
            return "the integer " + std::to_string(value.integer);
        case Type::number:
            return "the number " + detail::python_float_repr(value.number);
        case Type::string:
            return "the string '" + value.string + "'";
        case Type::list:
            return "a list";
        case Type::mapping:
            return "a mapping";
    }
    return "a value";
}

// Python's repr() of a str, as jsonschema quotes instances (only ever the empty string
// here, but kept general).
std::string python_repr(const std::string& text) {
    const bool has_single = text.find('\'') != std::string::npos;
    const bool has_double = text.find('"') != std::string::npos;
    const char quote = has_single && !has_double ? '"' : '\'';
    std::string out(1, quote);
    for (char c : text) {
        if (c == quote || c == '\\') {
            out += '\\';
            out += c;
        } else if (c == '\n') {
            out += "\\n";
        } else if (c == '\t') {
            out += "\\t";
        } else if (c == '\r') {
            out += "\\r";
        } else {
            out += c;
        }
    }
    out += quote;
    return out;
}

// `^[A-Za-z][A-Za-z0-9_-]{0,62}$`
bool is_name(std::string_view text) {
    if (text.empty() || text.size() > 63) return false;
    auto letter = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); };
    if (!letter(text[0])) return false;
    return std::all_of(text.begin() + 1, text.end(), [&](char c) {
        return letter(c) || (c >= '0' && c <= '9') || c == '_' || c == '-';
    });
}

// --------------------------------------------------------------------------------------
// Step 2: mission.schema.json, keyword by keyword as jsonschema applies it

enum class JsonType { string, integer, number, boolean, array, object };

bool has_type(const Value& value, JsonType type) {
    switch (type) {
        case JsonType::string:
            return value.type == Type::string;
        case JsonType::integer:
            return value.type == Type::integer;
        case JsonType::number:
            return value.is_number();
        case JsonType::boolean:
            return value.type == Type::boolean;
        case JsonType::array:
            return value.type == Type::list;
        case JsonType::object:
            return value.type == Type::mapping;
    }
    return false;
}

const char* type_words(JsonType type) {
    switch (type) {
        case JsonType::string:
            return "a string";
        case JsonType::integer:
            return "an integer";
        case JsonType::number:
            return "a number";
        case JsonType::boolean:
            return "a boolean (true or false)";
        case JsonType::array:
            return "a list";
        case JsonType::object:
            return "a mapping";
    }
    return "a value";
}

struct Schema {
    std::vector<JsonType> types{};
    std::optional<std::int64_t> minimum{};
    std::optional<std::int64_t> maximum{};
    bool non_empty_string = false;  // minLength: 1
    bool name_pattern = false;      // pattern of $defs/name
    std::vector<std::string> enumeration{};
    bool const_one = false;  // const: 1
    // Objects.
    std::vector<std::pair<std::string, const Schema*>> properties{};
    bool closed = false;                 // additionalProperties: false
    const Schema* additional = nullptr;  // additionalProperties: {schema}
    bool names = false;                  // propertyNames: $defs/name
    std::vector<std::string> required{};
    bool non_empty_object = false;  // minProperties: 1
    // Arrays.
    const Schema* items = nullptr;
};

// mission.schema.json, transcribed. Keep the two in step.
struct MissionSchema {
    Schema name{.types = {JsonType::string}, .name_pattern = true};
    Schema names{.types = {JsonType::array}, .items = &name};
    Schema resources{.types = {JsonType::object},
                     .properties = {{"cpu", &cpu}, {"mem_mb", &mem_mb}},
                     .closed = true};
    Schema cpu{.types = {JsonType::integer}, .minimum = 0, .maximum = 1000000};
    Schema mem_mb{.types = {JsonType::integer}, .minimum = 0, .maximum = 100000000};
    Schema period_ms{.types = {JsonType::integer}, .minimum = 1, .maximum = 600000};
    Schema boolean{.types = {JsonType::boolean}};
    Schema number{.types = {JsonType::number}};

    Schema kind{.enumeration = {"processing", "interface"}};
    Schema role{.enumeration = {"storage", "interface"}};
    Schema node{.types = {JsonType::object},
                .properties = {{"kind", &kind},
                               {"role", &role},
                               {"capabilities", &names},
                               {"capacity", &resources}},
                .closed = true,
                .required = {"kind"}};

    Schema port{.types = {JsonType::integer}, .minimum = 1, .maximum = 65535};
    Schema health{.types = {JsonType::object},
                  .properties = {{"min", &number}, {"max", &number}, {"deadline_ms", &period_ms}},
                  .closed = true};
    Schema param_value{
        .types = {JsonType::string, JsonType::number, JsonType::boolean}};
    Schema params{.types = {JsonType::object}, .additional = &param_value, .names = true};
    Schema task{.types = {JsonType::object},
                .properties = {{"port", &port},
                               {"component", &name},
                               {"requires", &names},
                               {"load", &resources},
                               {"essential", &boolean},
                               {"checkpoint", &boolean},
                               {"inputs", &names},
                               {"period_ms", &period_ms},
                               {"health", &health},
                               {"params", &params}},
                .closed = true,
                .required = {"port"}};

    Schema name_map{.types = {JsonType::object}, .additional = &name, .names = true};
    Schema configuration{.types = {JsonType::object},
                         .properties = {{"master", &name}, {"observers", &names}, {"tasks", &name_map}},
                         .closed = true,
                         .required = {"master", "tasks"}};
    Schema configurations{.types = {JsonType::object},
                          .additional = &configuration,
                          .names = true,
                          .non_empty_object = true};
    Schema edges{.types = {JsonType::object}, .additional = &name_map, .names = true};
    Schema phase_params{.types = {JsonType::object}, .additional = &params, .names = true};
    Schema phase{.types = {JsonType::object},
                 .properties = {{"tasks", &names},
                                {"initial", &name},
                                {"configurations", &configurations},
                                {"on_failure", &edges},
                                {"on_recovery", &edges},
                                {"on_phase", &edges},
                                {"params", &phase_params}},
                 .closed = true,
                 .required = {"initial", "configurations"}};

    Schema mission{.types = {JsonType::string}, .non_empty_string = true};
    Schema schema_version{.const_one = true};
    Schema miss_limit{.types = {JsonType::integer}, .minimum = 1, .maximum = 1000};
    Schema startup_grace_ms{.types = {JsonType::integer}, .minimum = 0, .maximum = 3600000};
    Schema heartbeat{.types = {JsonType::object},
                     .properties = {{"period_ms", &period_ms},
                                    {"miss_limit", &miss_limit},
                                    {"startup_grace_ms", &startup_grace_ms}},
                     .closed = true,
                     .required = {"period_ms", "miss_limit"}};
    Schema node_failures{.types = {JsonType::integer}, .minimum = 0, .maximum = 64};
    Schema tolerance{.types = {JsonType::object},
                     .properties = {{"node_failures", &node_failures}, {"nodes", &names}},
                     .closed = true,
                     .required = {"node_failures"}};
    Schema nodes{.types = {JsonType::object},
                 .additional = &node,
                 .names = true,
                 .non_empty_object = true};
    Schema tasks{.types = {JsonType::object}, .additional = &task, .names = true};
    Schema phases{.types = {JsonType::object},
                  .additional = &phase,
                  .names = true,
                  .non_empty_object = true};
    Schema root{.types = {JsonType::object},
                .properties = {{"mission", &mission},
                               {"schema", &schema_version},
                               {"heartbeat", &heartbeat},
                               {"tolerance", &tolerance},
                               {"nodes", &nodes},
                               {"tasks", &tasks},
                               {"phases", &phases}},
                .closed = true,
                .required = {"mission", "schema", "heartbeat", "tolerance", "nodes", "tasks",
                             "phases"}};
};

const MissionSchema& mission_schema() {
    static const MissionSchema schema;
    return schema;
}

// Exact comparison of a number with an integer bound, as Python compares int and float.
int compare(const Value& value, std::int64_t bound) {
    if (value.type == Type::integer) return value.integer < bound ? -1 : value.integer > bound;
    const double b = static_cast<double>(bound);  // bounds are small: exact
    if (value.number < b) return -1;
    if (value.number > b) return 1;
    return 0;  // equal, or NaN (every comparison false)
}

void check_schema(const Value& value, const Schema& schema, const std::string& path,
                  Errors& errors) {
    if (!schema.types.empty() &&
        std::none_of(schema.types.begin(), schema.types.end(),
                     [&](JsonType type) { return has_type(value, type); })) {
        std::string words;
        for (JsonType type : schema.types) {
            if (!words.empty()) words += " or ";
            words += type_words(type);
        }
        errors.add(value.position, "wrong-type",
                   where(path) + " must be " + words + ", not " + describe(value));
    }
    if (!schema.enumeration.empty()) {
        const bool allowed =
            value.type == Type::string &&
            std::find(schema.enumeration.begin(), schema.enumeration.end(), value.string) !=
                schema.enumeration.end();
        if (!allowed) {
            std::string shown;
            for (const std::string& option : schema.enumeration) {
                if (!shown.empty()) shown += ", ";
                shown += option;
            }
            errors.add(value.position, "bad-value",
                       where(path) + " is " + describe(value) + "; allowed: " + shown);
        }
    }
    if (schema.const_one) {
        const bool one = (value.type == Type::integer && value.integer == 1) ||
                         (value.type == Type::number && value.number == 1.0);
        if (!one) {
            errors.add(value.position, "bad-value",
                       where(path) + " is " + describe(value) + "; allowed: 1");
        }
    }
    if (value.is_number()) {
        if (schema.minimum && compare(value, *schema.minimum) < 0) {
            errors.add(value.position, "out-of-range",
                       where(path) + ": " + python_number(value) + " is less than the minimum of " +
                           std::to_string(*schema.minimum));
        }
        if (schema.maximum && compare(value, *schema.maximum) > 0) {
            errors.add(value.position, "out-of-range",
                       where(path) + ": " + python_number(value) +
                           " is greater than the maximum of " + std::to_string(*schema.maximum));
        }
    }
    if (value.type == Type::string) {
        if (schema.non_empty_string && value.string.empty()) {
            errors.add(value.position, "out-of-range",
                       where(path) + ": " + python_repr(value.string) + " should be non-empty");
        }
        if (schema.name_pattern && !is_name(value.string)) {
            errors.add(value.position, "bad-name",
                       "'" + value.string + "' is not a valid name (" + where(path) + ")");
        }
    }
    if (value.type == Type::mapping) {
        for (std::size_t i = 0; i < value.keys.size(); ++i) {
            const std::string& key = value.keys[i];
            const auto property =
                std::find_if(schema.properties.begin(), schema.properties.end(),
                             [&](const auto& p) { return p.first == key; });
            if (property != schema.properties.end()) {
                check_schema(value.items[i], *property->second, child(path, key), errors);
            } else if (schema.closed) {
                std::vector<std::string> known;
                for (const auto& p : schema.properties) known.push_back(p.first);
                std::sort(known.begin(), known.end());
                std::string shown;
                for (const std::string& k : known) {
                    if (!shown.empty()) shown += ", ";
                    shown += k;
                }
                errors.add(value.key_positions[i], "unknown-key",
                           "unknown key '" + key + "' in " + where(path) + " (known: " + shown +
                               ")");
            } else if (schema.additional != nullptr) {
                check_schema(value.items[i], *schema.additional, child(path, key), errors);
            }
            if (schema.names && !is_name(key)) {
                errors.add(value.key_positions[i], "bad-name",
                           "'" + key + "' is not a valid name in " + where(path));
            }
        }
        for (const std::string& key : schema.required) {
            if (value.get(key) == nullptr) {
                errors.add(value.position, "missing-key",
                           where(path) + " lacks required key '" + key + "'");
            }
        }
        if (schema.non_empty_object && value.keys.empty()) {
            errors.add(value.position, "empty", where(path) + " must not be empty");
        }
    }
    if (value.type == Type::list && schema.items != nullptr) {
        for (std::size_t i = 0; i < value.items.size(); ++i) {
            check_schema(value.items[i], *schema.items, child(path, i), errors);
        }
    }
}

// --------------------------------------------------------------------------------------
// Step 3: the shape rules a schema cannot say. The document has passed the schema, so
// the values below have the types it names.

// A number of the document as a double (health bounds are held as doubles).
double as_double(const Value& value) {
    return value.type == Type::integer ? static_cast<double>(value.integer) : value.number;
}

void check_rules(const Value& root, Errors& errors) {
    const Value& nodes = *root.get("nodes");
    const Value& tasks = *root.get("tasks");
    const Value& phases = *root.get("phases");
    auto reserved = [&](const Value& mapping, std::size_t i, const char* what) {
        if (mapping.keys[i] == kSafe) {
            errors.add(mapping.key_positions[i], "bad-name",
                       std::string("'") + kSafe + "' is reserved and cannot name a " + what);
        }
    };
    for (std::size_t i = 0; i < nodes.keys.size(); ++i) reserved(nodes, i, "node");
    for (std::size_t i = 0; i < tasks.keys.size(); ++i) reserved(tasks, i, "task");
    for (std::size_t i = 0; i < phases.keys.size(); ++i) reserved(phases, i, "phase");
    for (std::size_t i = 0; i < nodes.keys.size(); ++i) {
        const Value& node = nodes.items[i];
        const Value* role = node.get("role");
        if (node.get("kind")->string == "processing" && role != nullptr) {
            errors.add(role->position, "bad-value",
                       "node " + nodes.keys[i] + ": role is only for interface nodes");
        }
    }
    for (std::size_t i = 0; i < tasks.keys.size(); ++i) {
        const Value* health = tasks.items[i].get("health");
        if (health == nullptr) continue;
        const Value* min = health->get("min");
        const Value* max = health->get("max");
        if (min != nullptr && max != nullptr && as_double(*min) > as_double(*max)) {
            errors.add(max->position, "bad-value",
                       "task " + tasks.keys[i] + ": health.max " + python_number(*max) +
                           " is below health.min " + python_number(*min));
        }
    }
    std::map<std::string, std::string> seen;  // configuration -> phase
    for (std::size_t p = 0; p < phases.keys.size(); ++p) {
        const Value& configurations = *phases.items[p].get("configurations");
        for (std::size_t c = 0; c < configurations.keys.size(); ++c) {
            const std::string& name = configurations.keys[c];
            reserved(configurations, c, "configuration");
            const auto [it, inserted] = seen.emplace(name, phases.keys[p]);
            if (!inserted) {
                errors.add(configurations.key_positions[c], "duplicate-name",
                           "configuration " + name + " is already defined in phase " + it->second);
            }
        }
    }
}

// --------------------------------------------------------------------------------------
// Step 4: references and ports

Value make_empty(Type type) {
    Value value;
    value.type = type;
    return value;
}
const Value kEmptyList = make_empty(Type::list);
const Value kEmptyMapping = make_empty(Type::mapping);

const Value& get_or(const Value& mapping, std::string_view key, const Value& fallback) {
    const Value* value = mapping.get(key);
    return value != nullptr ? *value : fallback;
}

bool defines(const Value& mapping, const std::string& name) { return mapping.get(name) != nullptr; }

void check_references(const Value& root, Errors& errors) {
    const Value& nodes = *root.get("nodes");
    const Value& tasks = *root.get("tasks");
    const Value& phases = *root.get("phases");
    std::set<std::string> capabilities;
    for (const Value& node : nodes.items) {
        for (const Value& capability : get_or(node, "capabilities", kEmptyList).items) {
            capabilities.insert(capability.string);
        }
    }
    auto unknown = [&](Position position, std::string message) {
        errors.add(position, "unknown-reference", std::move(message));
    };
    // A name written as a value at `path`.
    auto check_value = [&](const std::string& path, const Value& name, bool defined,
                           const std::string& what) {
        if (!defined) {
            unknown(name.position, path + ": " + what + " '" + name.string + "' is not defined");
        }
    };
    // A name written as a key of `mapping`, which is at `path`.
    auto check_key = [&](const std::string& path, const Value& mapping, std::size_t i,
                         bool defined, const std::string& what) {
        if (!defined) {
            unknown(mapping.key_positions[i],
                    path + ": " + what + " '" + mapping.keys[i] + "' is not defined");
        }
    };

    const Value& tolerance_nodes = get_or(*root.get("tolerance"), "nodes", kEmptyList);
    for (std::size_t i = 0; i < tolerance_nodes.items.size(); ++i) {
        const Value& name = tolerance_nodes.items[i];
        check_value(child("tolerance.nodes", i), name, defines(nodes, name.string), "node");
    }
    for (std::size_t t = 0; t < tasks.keys.size(); ++t) {
        const std::string base = "tasks." + tasks.keys[t];
        const Value& requires_list = get_or(tasks.items[t], "requires", kEmptyList);
        for (std::size_t i = 0; i < requires_list.items.size(); ++i) {
            const Value& capability = requires_list.items[i];
            if (capabilities.count(capability.string) == 0) {
                unknown(capability.position, child(base + ".requires", i) +
                                                 ": no node offers capability '" +
                                                 capability.string + "'");
            }
        }
        const Value& inputs = get_or(tasks.items[t], "inputs", kEmptyList);
        for (std::size_t i = 0; i < inputs.items.size(); ++i) {
            check_value(child(base + ".inputs", i), inputs.items[i],
                        defines(tasks, inputs.items[i].string), "task");
        }
    }
    for (std::size_t p = 0; p < phases.keys.size(); ++p) {
        const std::string& phase_name = phases.keys[p];
        const Value& phase = phases.items[p];
        const std::string base = "phases." + phase_name;
        const std::string of_phase = "configuration of phase " + phase_name;
        const Value& configurations = *phase.get("configurations");
        const Value& phase_tasks = get_or(phase, "tasks", kEmptyList);
        for (std::size_t i = 0; i < phase_tasks.items.size(); ++i) {
            check_value(child(base + ".tasks", i), phase_tasks.items[i],
                        defines(tasks, phase_tasks.items[i].string), "task");
        }
        const Value& initial = *phase.get("initial");
        check_value(base + ".initial", initial, defines(configurations, initial.string), of_phase);
        for (std::size_t c = 0; c < configurations.keys.size(); ++c) {
            const std::string cpath = base + ".configurations." + configurations.keys[c];
            const Value& configuration = configurations.items[c];
            const Value& master = *configuration.get("master");
            check_value(cpath + ".master", master, defines(nodes, master.string), "node");
            const Value& observers = get_or(configuration, "observers", kEmptyList);
            for (std::size_t i = 0; i < observers.items.size(); ++i) {
                check_value(child(cpath + ".observers", i), observers.items[i],
                            defines(nodes, observers.items[i].string), "node");
            }
            const Value& placement = *configuration.get("tasks");
            for (std::size_t i = 0; i < placement.keys.size(); ++i) {
                check_key(cpath + ".tasks", placement, i, defines(tasks, placement.keys[i]), "task");
                check_value(cpath + ".tasks." + placement.keys[i], placement.items[i],
                            defines(nodes, placement.items[i].string), "node");
            }
        }
        // on_failure and on_recovery: configuration -> node -> configuration of the phase
        // (SAFE only as a failure edge's target).
        auto check_edges = [&](const std::string& key, bool safe_allowed) {
            const Value& graph = get_or(phase, key, kEmptyMapping);
            for (std::size_t c = 0; c < graph.keys.size(); ++c) {
                const std::string epath = base + "." + key + "." + graph.keys[c];
                check_key(base + "." + key, graph, c, defines(configurations, graph.keys[c]),
                          of_phase);
                const Value& edges = graph.items[c];
                for (std::size_t n = 0; n < edges.keys.size(); ++n) {
                    check_key(epath, edges, n, defines(nodes, edges.keys[n]), "node");
                    const Value& target = edges.items[n];
                    if (!safe_allowed || target.string != kSafe) {
                        check_value(epath + "." + edges.keys[n], target,
                                    defines(configurations, target.string), of_phase);
                    }
                }
            }
        };
        check_edges("on_failure", true);
        check_edges("on_recovery", false);
        const Value& on_phase = get_or(phase, "on_phase", kEmptyMapping);
        for (std::size_t q = 0; q < on_phase.keys.size(); ++q) {
            const std::string& target_phase = on_phase.keys[q];
            const std::string ppath = base + ".on_phase." + target_phase;
            check_key(base + ".on_phase", on_phase, q, defines(phases, target_phase), "phase");
            const Value* target = phases.get(target_phase);
            const Value& mapping = on_phase.items[q];
            for (std::size_t c = 0; c < mapping.keys.size(); ++c) {
                check_key(ppath, mapping, c, defines(configurations, mapping.keys[c]), of_phase);
                if (target != nullptr) {
                    const Value& to = mapping.items[c];
                    check_value(ppath + "." + mapping.keys[c], to,
                                defines(*target->get("configurations"), to.string),
                                "configuration of phase " + target_phase);
                }
            }
        }
        const Value& params = get_or(phase, "params", kEmptyMapping);
        for (std::size_t i = 0; i < params.keys.size(); ++i) {
            check_key(base + ".params", params, i, defines(tasks, params.keys[i]), "task");
        }
    }

    std::map<std::int64_t, std::string> ports;
    for (std::size_t t = 0; t < tasks.keys.size(); ++t) {
        const Value& port = *tasks.items[t].get("port");
        const auto [it, inserted] = ports.emplace(port.integer, tasks.keys[t]);
        if (!inserted) {
            errors.add(port.position, "port-conflict",
                       "task " + tasks.keys[t] + " uses port " + std::to_string(port.integer) +
                           ", already used by task " + it->second);
        }
    }
}

// --------------------------------------------------------------------------------------
// Building the model

std::vector<std::string> strings(const Value& list) {
    std::vector<std::string> out;
    out.reserve(list.items.size());
    for (const Value& item : list.items) out.push_back(item.string);
    return out;
}

Resources resources(const Value* raw, std::optional<std::int64_t> fallback) {
    Resources out{fallback, fallback};
    if (raw == nullptr) return out;
    if (const Value* cpu = raw->get("cpu")) out.cpu = cpu->integer;
    if (const Value* mem = raw->get("mem_mb")) out.mem_mb = mem->integer;
    return out;
}

Params params(const Value& raw) {
    Params out;
    for (std::size_t i = 0; i < raw.keys.size(); ++i) {
        const Value& value = raw.items[i];
        ParamValue param;
        switch (value.type) {
            case Type::string:
                param = value.string;
                break;
            case Type::integer:
                param = value.integer;
                break;
            case Type::number:
                param = value.number;
                break;
            case Type::boolean:
                param = value.boolean;
                break;
            default:
                break;  // excluded by the schema
        }
        out.emplace_back(raw.keys[i], std::move(param));
    }
    return out;
}

Mission build(const Value& root, const std::string& path) {
    Mission mission;
    mission.name = root.get("mission")->string;
    mission.path = path;
    const Value& heartbeat = *root.get("heartbeat");
    mission.heartbeat.period_ms = heartbeat.get("period_ms")->integer;
    mission.heartbeat.miss_limit = heartbeat.get("miss_limit")->integer;
    if (const Value* grace = heartbeat.get("startup_grace_ms")) {
        mission.heartbeat.startup_grace_ms = grace->integer;
    }

    const Value& nodes = *root.get("nodes");
    for (std::size_t i = 0; i < nodes.keys.size(); ++i) {
        const Value& raw = nodes.items[i];
        Node node;
        node.name = nodes.keys[i];
        node.kind = raw.get("kind")->string == "processing" ? NodeKind::processing
                                                            : NodeKind::interface;
        if (node.kind == NodeKind::interface) {
            const Value* role = raw.get("role");
            node.role = role != nullptr && role->string == "storage" ? NodeRole::storage
                                                                     : NodeRole::interface;
        }
        node.capabilities = strings(get_or(raw, "capabilities", kEmptyList));
        node.capacity = resources(raw.get("capacity"), std::nullopt);
        node.line = nodes.key_positions[i].line;
        mission.nodes.push_back(std::move(node));
    }

    const Value& tasks = *root.get("tasks");
    for (std::size_t i = 0; i < tasks.keys.size(); ++i) {
        const Value& raw = tasks.items[i];
        Task task;
        task.name = tasks.keys[i];
        task.port = raw.get("port")->integer;
        const Value* component = raw.get("component");
        task.component = component != nullptr ? component->string : task.name;
        task.requires_capabilities = strings(get_or(raw, "requires", kEmptyList));
        task.load = resources(raw.get("load"), 0);
        const Value* essential = raw.get("essential");
        task.essential = essential != nullptr && essential->boolean;
        const Value* checkpoint = raw.get("checkpoint");
        task.checkpoint = checkpoint != nullptr && checkpoint->boolean;
        task.inputs = strings(get_or(raw, "inputs", kEmptyList));
        if (const Value* period = raw.get("period_ms")) task.period_ms = period->integer;
        if (const Value* health = raw.get("health")) {
            Health h;
            if (const Value* min = health->get("min")) h.min = as_double(*min);
            if (const Value* max = health->get("max")) h.max = as_double(*max);
            if (const Value* deadline = health->get("deadline_ms")) h.deadline_ms = deadline->integer;
            task.health = h;
        }
        task.params = params(get_or(raw, "params", kEmptyMapping));
        task.line = tasks.key_positions[i].line;
        mission.tasks.push_back(std::move(task));
    }

    const Value& phases = *root.get("phases");
    for (std::size_t p = 0; p < phases.keys.size(); ++p) {
        const Value& raw = phases.items[p];
        Phase phase;
        phase.name = phases.keys[p];
        if (const Value* phase_tasks = raw.get("tasks")) {
            phase.tasks = strings(*phase_tasks);
        } else {
            phase.tasks = tasks.keys;
        }
        phase.initial = raw.get("initial")->string;
        const Value& configurations = *raw.get("configurations");
        for (std::size_t c = 0; c < configurations.keys.size(); ++c) {
            const Value& rc = configurations.items[c];
            Configuration configuration;
            configuration.name = configurations.keys[c];
            configuration.phase = phase.name;
            configuration.master = rc.get("master")->string;
            configuration.observers = strings(get_or(rc, "observers", kEmptyList));
            const Value& placement = *rc.get("tasks");
            for (std::size_t t = 0; t < placement.keys.size(); ++t) {
                configuration.placement.emplace_back(placement.keys[t], placement.items[t].string);
            }
            configuration.line = configurations.key_positions[c].line;
            phase.configurations.push_back(std::move(configuration));
        }
        auto edges_of = [&](const char* key) {
            std::vector<FailureEdge> out;
            const Value& graph = get_or(raw, key, kEmptyMapping);
            for (std::size_t c = 0; c < graph.keys.size(); ++c) {
                const Value& edges = graph.items[c];
                for (std::size_t n = 0; n < edges.keys.size(); ++n) {
                    out.push_back(FailureEdge{graph.keys[c], edges.keys[n], edges.items[n].string,
                                              edges.key_positions[n].line});
                }
            }
            return out;
        };
        phase.on_failure = edges_of("on_failure");
        phase.on_recovery = edges_of("on_recovery");
        const Value& on_phase = get_or(raw, "on_phase", kEmptyMapping);
        for (std::size_t q = 0; q < on_phase.keys.size(); ++q) {
            const Value& mapping = on_phase.items[q];
            for (std::size_t c = 0; c < mapping.keys.size(); ++c) {
                phase.on_phase.push_back(PhaseEdge{on_phase.keys[q], mapping.keys[c],
                                                   mapping.items[c].string,
                                                   mapping.key_positions[c].line});
            }
        }
        const Value& phase_params = get_or(raw, "params", kEmptyMapping);
        for (std::size_t t = 0; t < phase_params.keys.size(); ++t) {
            phase.params.emplace_back(phase_params.keys[t], params(phase_params.items[t]));
        }
        phase.line = phases.key_positions[p].line;
        mission.phases.push_back(std::move(phase));
    }

    const Value& tolerance = *root.get("tolerance");
    mission.tolerance.node_failures = tolerance.get("node_failures")->integer;
    if (const Value* tolerance_nodes = tolerance.get("nodes")) {
        mission.tolerance.nodes = strings(*tolerance_nodes);
    } else {
        mission.tolerance.nodes = nodes.keys;
    }
    return mission;
}

// Control characters and line breaks in a message (a quoted name may hold any) are
// escaped as Python's reader escapes them, so that every error prints as one line.
std::string one_line(const std::string& message) {
    std::string out;
    out.reserve(message.size());
    char buffer[16];
    for (std::size_t i = 0; i < message.size(); ++i) {
        const auto byte = static_cast<unsigned char>(message[i]);
        const auto next = i + 1 < message.size() ? static_cast<unsigned char>(message[i + 1]) : 0u;
        if (byte == '\t') {
            out += "\\t";
        } else if (byte == '\n') {
            out += "\\n";
        } else if (byte == '\r') {
            out += "\\r";
        } else if (byte < 0x20 || byte == 0x7F) {
            std::snprintf(buffer, sizeof buffer, "\\x%02x", byte);
            out += buffer;
        } else if (byte == 0xC2 && next >= 0x80 && next <= 0x9F) {  // U+0080..U+009F
            std::snprintf(buffer, sizeof buffer, "\\x%02x", next);
            out += buffer;
            ++i;
        } else if (byte == 0xE2 && next == 0x80 && i + 2 < message.size() &&
                   (message[i + 2] == '\xA8' || message[i + 2] == '\xA9')) {  // U+2028, U+2029
            out += message[i + 2] == '\xA8' ? "\\u2028" : "\\u2029";
            i += 2;
        } else {
            out += static_cast<char>(byte);
        }
    }
    return out;
}

LoadResult failed(std::vector<LoadError> errors) {
    for (LoadError& error : errors) error.message = one_line(error.message);
    std::sort(errors.begin(), errors.end(), [](const LoadError& a, const LoadError& b) {
        return std::tie(a.line, a.col, a.rule, a.message, a.file) <
               std::tie(b.line, b.col, b.rule, b.message, b.file);
    });
    errors.erase(std::unique(errors.begin(), errors.end(),
                             [](const LoadError& a, const LoadError& b) {
                                 return std::tie(a.line, a.col, a.rule, a.message, a.file) ==
                                        std::tie(b.line, b.col, b.rule, b.message, b.file);
                             }),
                 errors.end());
    LoadResult result;
    result.errors = std::move(errors);
    return result;
}

LoadResult load_text(const std::string& text, const std::string& path) {
    std::vector<LoadError> parse_errors;
    const std::optional<Value> root = detail::parse_yaml(text, path, parse_errors);
    if (!root) return failed(std::move(parse_errors));
    Errors errors(path);
    check_schema(*root, mission_schema().root, "", errors);
    if (!errors.empty()) return failed(std::move(errors.list()));
    check_rules(*root, errors);
    if (!errors.empty()) return failed(std::move(errors.list()));
    check_references(*root, errors);
    if (!errors.empty()) return failed(std::move(errors.list()));
    LoadResult result;
    result.mission = build(*root, path);
    return result;
}

LoadResult read_error(const std::string& path, const std::string& message) {
    return failed({LoadError{path, 1, 1, "yaml-syntax", message}});
}

}  // namespace

LoadResult load_mission_text(const std::string& text, const std::string& path) {
    try {
        if (const auto bad = detail::first_invalid_utf8(text)) {
            return read_error(path, "not UTF-8 text (byte " + std::to_string(*bad) + ")");
        }
        return load_text(text, path);
    } catch (const std::bad_alloc&) {
        return read_error(path, "out of memory while loading");
    }
}

LoadResult load_mission_file(const std::string& path) {
    // A file that opens with `{` is a mission image (keel-verify compile's output); every
    // tool that loads a mission flies images as it reads YAML.
    if (is_mission_image(path)) return load_mission_image(path);
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return read_error(path, std::string("cannot read: ") + std::strerror(errno));
    std::string bytes;
    struct stat info {};
    if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) &&
        static_cast<std::uint64_t>(info.st_size) > detail::kMaxFileBytes) {
        ::close(fd);
        return read_error(path, "the mission file is larger than " +
                                    std::to_string(detail::kMaxFileBytes / (1024 * 1024)) + " MiB");
    }
    char buffer[65536];
    for (;;) {
        const ssize_t n = ::read(fd, buffer, sizeof buffer);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int saved = errno;
            ::close(fd);
            return read_error(path, std::string("cannot read: ") + std::strerror(saved));
        }
        if (n == 0) break;
        bytes.append(buffer, static_cast<std::size_t>(n));
        if (bytes.size() > detail::kMaxFileBytes) {
            ::close(fd);
            return read_error(path, "the mission file is larger than " +
                                        std::to_string(detail::kMaxFileBytes / (1024 * 1024)) +
                                        " MiB");
        }
    }
    ::close(fd);
    return load_mission_text(bytes, path);
}

}  // namespace keel::mission
