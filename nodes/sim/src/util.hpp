// Small parsing and formatting helpers shared by the scenario runner and the CLI.
#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "nodes/sim/src/simulation.hpp"

namespace keel::sim {

std::vector<std::string> split_words(std::string_view line);
// "300ms", "1.5s", "2000us", "10s"; a bare number is milliseconds.
std::optional<TimeNs> parse_duration(std::string_view text);
// "5%" or "0.05".
std::optional<double> parse_rate(std::string_view text);
// {"m":"PN1","n":"PN2","epoch":3} -> m=PN1 n=PN2 epoch=3; a list or an object is kept whole
// without its quotes: {"ev":{"PN1":["PN3"]}} -> ev={PN1:[PN3]}.
std::string flat_json_to_words(std::string_view json);

// One NDJSON trace line (docs/verification.md, spec/NAMES.md) for a state machine's Trace action...
void write_trace_line(std::ostream& out, TimeNs t, const std::string& node, const char* fsm,
                      const char* action, const std::string& args, const std::string& vars);
// ... and for an environment event (crash, restart, partition, ...): node null, fsm "env".
void write_env_line(std::ostream& out, TimeNs t, const char* action, const std::string& args);

struct Distribution {
    std::size_t count = 0;
    double min = 0, p50 = 0, p90 = 0, p99 = 0, max = 0, mean = 0;
};
Distribution summarize(std::vector<double> values);

}  // namespace keel::sim
