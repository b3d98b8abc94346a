// keel-node's log formats: text lines start with the UTC date and time; json lines are
// JSON objects whatever the message holds.
#include "nodes/keel-node/src/logging.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

namespace keel::node {
namespace {

// Logs `message` through a default logger writing to a string, in `format`.
std::string log_line(LogFormat format, const std::string& node, const std::string& message) {
    std::ostringstream out;
    auto previous = spdlog::default_logger();
    spdlog::set_default_logger(std::make_shared<spdlog::logger>(
        "log-test", std::make_shared<spdlog::sinks::ostream_sink_mt>(out)));
    set_log_format(format, node);
    spdlog::warn("{}", message);
    spdlog::set_default_logger(previous);
    return out.str();
}

TEST(Logging, TextLinesCarryTheUtcDateAndTime) {
    const std::string line = log_line(LogFormat::text, "PN1", "became Master of epoch 2");
    EXPECT_TRUE(std::regex_search(
        line, std::regex(R"(^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{3}Z warning became Master of epoch 2\n$)")))
        << line;
}

TEST(Logging, JsonLinesAreObjectsWhateverTheMessageHolds) {
    const std::string message = "a \"quoted\" name, a back\\slash,\na new line, a tab\t, a bell \a and 50%";
    const std::string line = log_line(LogFormat::json, "PN\"1", message);
    ASSERT_FALSE(line.empty());
    EXPECT_EQ(line.back(), '\n');
    EXPECT_EQ(line.find('\n'), line.size() - 1) << "one line per message";
    const auto object = nlohmann::json::parse(line);
    EXPECT_EQ(object.at("message"), message);
    EXPECT_EQ(object.at("level"), "warning");
    EXPECT_EQ(object.at("node"), "PN\"1");
    EXPECT_TRUE(std::regex_match(object.at("time").get<std::string>(),
                                 std::regex(R"(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{3}Z)")));
}

TEST(Logging, TheFormatIsTextOrJson) {
    EXPECT_EQ(parse_log_format("text"), LogFormat::text);
    EXPECT_EQ(parse_log_format("json"), LogFormat::json);
    EXPECT_FALSE(parse_log_format("xml").has_value());
    EXPECT_FALSE(parse_log_format("").has_value());
}

}  // namespace
}  // namespace keel::node
