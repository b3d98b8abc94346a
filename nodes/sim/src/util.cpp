#include "nodes/sim/src/util.hpp"

#include "core/fsm/json.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>

namespace keel::sim {

std::vector<std::string> split_words(std::string_view line) {
    std::vector<std::string> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) words.emplace_back(line.substr(start, i - start));
    }
    return words;
}

namespace {
std::optional<double> parse_number(std::string_view text) {
    if (text.empty()) return std::nullopt;
    try {
        std::size_t used = 0;
        const double value = std::stod(std::string(text), &used);
        if (used != text.size() || !std::isfinite(value) || value < 0) return std::nullopt;
        return value;
    } catch (...) {
        return std::nullopt;
    }
}
}  // namespace

std::optional<TimeNs> parse_duration(std::string_view text) {
    struct Unit {
        std::string_view suffix;
        double nanoseconds;
    };
    static constexpr Unit units[] = {{"ms", 1e6}, {"us", 1e3}, {"ns", 1}, {"s", 1e9}, {"m", 60e9}};
    for (const auto& unit : units) {
        if (text.size() > unit.suffix.size() && text.ends_with(unit.suffix)) {
            auto value = parse_number(text.substr(0, text.size() - unit.suffix.size()));
            if (!value) return std::nullopt;
            return static_cast<TimeNs>(std::llround(*value * unit.nanoseconds));
        }
    }
    auto value = parse_number(text);
    if (!value) return std::nullopt;
    return static_cast<TimeNs>(std::llround(*value * 1e6));
}

std::optional<double> parse_rate(std::string_view text) {
    if (text.ends_with("%")) {
        auto value = parse_number(text.substr(0, text.size() - 1));
        if (!value || *value > 100) return std::nullopt;
        return *value / 100.0;
    }
    auto value = parse_number(text);
    if (!value || *value > 1) return std::nullopt;
    return value;
}

std::string flat_json_to_words(std::string_view json) {
    std::string out;
    std::size_t i = 0;
    auto skip = [&] {
        while (i < json.size() && (json[i] == ' ' || json[i] == ',' || json[i] == '{' || json[i] == '}')) ++i;
    };
    auto read_string = [&] {
        std::string value;
        ++i;  // opening quote
        while (i < json.size() && json[i] != '"') {
            if (json[i] == '\\' && i + 1 < json.size()) ++i;
            value.push_back(json[i++]);
        }
        ++i;
        return value;
    };
    while (true) {
        skip();
        if (i >= json.size() || json[i] != '"') break;
        const std::string key = read_string();
        if (i < json.size() && json[i] == ':') ++i;
        std::string value;
        if (i < json.size() && json[i] == '"') {
            value = read_string();
        } else if (i < json.size() && (json[i] == '[' || json[i] == '{')) {
            // A list or an object (a take-over's `ev`, `passed`), whole, without quotes.
            int depth = 0;
            do {
                if (json[i] == '[' || json[i] == '{') ++depth;
                if (json[i] == ']' || json[i] == '}') --depth;
                if (json[i] != '"') value.push_back(json[i]);
                ++i;
            } while (i < json.size() && depth > 0);
        } else {
            while (i < json.size() && json[i] != ',' && json[i] != '}') value.push_back(json[i++]);
        }
        if (!out.empty()) out.push_back(' ');
        out += key + "=" + value;
    }
    return out;
}

Distribution summarize(std::vector<double> values) {
    Distribution d;
    d.count = values.size();
    if (values.empty()) return d;
    std::sort(values.begin(), values.end());
    auto at = [&](double q) {
        const auto index = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size()))) ;
        return values[std::min(values.size() - 1, index == 0 ? 0 : index - 1)];
    };
    d.min = values.front();
    d.max = values.back();
    d.p50 = at(0.5);
    d.p90 = at(0.9);
    d.p99 = at(0.99);
    d.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
    return d;
}

void write_trace_line(std::ostream& out, TimeNs t, const std::string& node, const char* fsm,
                      const char* action, const std::string& args, const std::string& vars) {
    out << fsm::JsonObject()
               .field("t_ns", static_cast<std::int64_t>(t))
               .field("node", node)
               .field("fsm", fsm)
               .field("action", action)
               .raw("args", args)
               .raw("vars", vars)
               .str()
        << "\n";
}

void write_env_line(std::ostream& out, TimeNs t, const char* action, const std::string& args) {
    out << fsm::JsonObject()
               .field("t_ns", static_cast<std::int64_t>(t))
               .raw("node", "null")
               .field("fsm", "env")
               .field("action", action)
               .raw("args", args)
               .raw("vars", "{}")
               .str()
        << "\n";
}

}  // namespace keel::sim
