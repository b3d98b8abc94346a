#include "logging.hpp"

#include "core/fsm/json.hpp"

#include <memory>

#include <spdlog/pattern_formatter.h>
#include <spdlog/spdlog.h>

namespace keel::node {
namespace {

// %j: the message as JSON string content (spdlog's %v writes it as it is).
class JsonMessageFlag final : public spdlog::custom_flag_formatter {
public:
    void format(const spdlog::details::log_msg& msg, const std::tm&, spdlog::memory_buf_t& dest) override {
        std::string escaped;
        append_json_escaped(escaped, std::string_view(msg.payload.data(), msg.payload.size()));
        dest.append(escaped.data(), escaped.data() + escaped.size());
    }
    std::unique_ptr<custom_flag_formatter> clone() const override {
        return std::make_unique<JsonMessageFlag>();
    }
};

constexpr const char* kTime = "%Y-%m-%dT%H:%M:%S.%eZ";

}  // namespace

std::optional<LogFormat> parse_log_format(std::string_view name) {
    if (name == "text") return LogFormat::text;
    if (name == "json") return LogFormat::json;
    return std::nullopt;
}

// The message as JSON string content: core/fsm/json's quoting, without the quotes.
void append_json_escaped(std::string& out, std::string_view text) {
    std::string quoted;
    fsm::append_json_string(quoted, text);
    out.append(quoted, 1, quoted.size() - 2);
}

void set_log_format(LogFormat format, const std::string& node) {
    std::string pattern;
    if (format == LogFormat::text) {
        pattern = std::string(kTime) + " %^%l%$ %v";
        auto formatter = std::make_unique<spdlog::pattern_formatter>(
            pattern, spdlog::pattern_time_type::utc, std::string(spdlog::details::os::default_eol));
        spdlog::set_formatter(std::move(formatter));
        return;
    }
    std::string name;
    std::string escaped;
    append_json_escaped(escaped, node);
    for (const char c : escaped) name += c == '%' ? std::string("%%") : std::string(1, c);
    pattern = std::string(R"({"time":")") + kTime + R"(","level":"%l","node":")" + name +
              R"(","message":"%j"})";
    auto formatter = std::make_unique<spdlog::pattern_formatter>(
        spdlog::pattern_time_type::utc, std::string(spdlog::details::os::default_eol));
    formatter->add_flag<JsonMessageFlag>('j').set_pattern(pattern);
    spdlog::set_formatter(std::move(formatter));
}

}  // namespace keel::node
