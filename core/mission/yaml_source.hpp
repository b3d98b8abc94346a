// Stage 0 of the mission loader: YAML text to plain data with positions.
//
// Internal to core/mission. This is the C++ twin of `_parse` and `_Document.convert` in
// verify/keel_verify/mission.py: the same YAML 1.2 core-schema typing of scalars, the same
// positions (PyYAML's start marks, 1-based, columns in characters), the same duplicate-key
// and non-scalar-key errors, and the same limits on aliases, nesting and size.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/mission/mission.hpp"

namespace keel::mission::detail {

// Limits shared with the Python reader (MAX_YAML_NODES, MAX_YAML_DEPTH, MAX_FILE_BYTES).
inline constexpr std::int64_t kMaxYamlNodes = 1'000'000;
inline constexpr int kMaxYamlDepth = 100;
inline constexpr std::size_t kMaxFileBytes = 16u * 1024u * 1024u;

struct Position {
    int line = 1;
    int col = 1;
};

// A value of the document, typed like JSON: what the Python reader's `convert` returns.
struct Value {
    enum class Type { null, boolean, integer, number, string, list, mapping };

    Type type = Type::null;
    bool boolean = false;
    std::int64_t integer = 0;
    double number = 0.0;
    std::string string;
    // List items, or mapping values (parallel to `keys` and `key_positions`), in file order.
    std::vector<Value> items;
    std::vector<std::string> keys;
    std::vector<Position> key_positions;
    Position position;  // where the value starts

    bool is_number() const { return type == Type::integer || type == Type::number; }
    // The value under `key` of a mapping, or nullptr.
    const Value* get(std::string_view key) const;
    // The position of `key` in a mapping (the key itself), or this value's position.
    Position key_position(std::string_view key) const;
};

// Parses YAML text (already checked to be UTF-8) into a Value. On failure returns
// nullopt and appends the errors of this stage, unsorted, to `errors`.
std::optional<Value> parse_yaml(const std::string& text, const std::string& file,
                                std::vector<LoadError>& errors);

// Checks that `bytes` is UTF-8 the way Python's strict decoder does; returns the offset
// of the first invalid sequence, or nullopt.
std::optional<std::size_t> first_invalid_utf8(std::string_view bytes);

// Python's repr() of a float ("1.0", "1e+16", "inf", "nan").
std::string python_float_repr(double value);

}  // namespace keel::mission::detail
