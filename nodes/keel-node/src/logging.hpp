// keel-node's log lines (stderr): every line carries the date and time in UTC, to the
// millisecond, so logs of several nodes (and of several days) line up; `--log-format
// json` writes one JSON object per line for log collectors.
//
//   text  2026-11-24T18:52:25.123Z info became Master of epoch 2
//   json  {"time":"2026-11-24T18:52:25.123Z","level":"info","node":"PN1","message":"..."}
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace keel::node {

enum class LogFormat { text, json };

// "text" or "json"; nullopt for anything else.
std::optional<LogFormat> parse_log_format(std::string_view name);

// Sets the default logger's pattern. `node` is the mission node the process runs (empty
// before the flags are read): the json format names it in every line (a text log is one
// file per node already).
void set_log_format(LogFormat format, const std::string& node);

// `text` as a JSON string's content (core/fsm/json.hpp's append_json_string, without the quotes).
void append_json_escaped(std::string& out, std::string_view text);

}  // namespace keel::node
