// The loader never throws and never crashes: every input is either a mission or a list of
// errors. Mutations of the good fixtures (seeded, so any failure reproduces from the seed
// printed with it) and a few hostile documents written by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <ctime>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/mission/mission.hpp"

namespace keel::mission {
namespace {

namespace fs = std::filesystem;

fs::path root() {
    const char* env = std::getenv("KEEL_ROOT");
    return env != nullptr ? fs::path(env) : fs::current_path();
}

std::string read(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
}

std::vector<std::string> good_missions() {
    std::vector<fs::path> paths;
    for (const fs::path& dir : {root() / "tests/missions/good", root() / "config"}) {
        if (!fs::is_directory(dir)) continue;
        for (const auto& entry : fs::directory_iterator(dir)) {
            if (entry.path().extension() == ".yaml") paths.push_back(entry.path());
        }
    }
    std::sort(paths.begin(), paths.end());
    std::vector<std::string> texts;
    for (const fs::path& p : paths) texts.push_back(read(p));
    return texts;
}

const char* const kTabsTail = "mission: x\n";

const std::set<std::string>& known_rules() {
    static const std::set<std::string> rules = {
        "yaml-syntax", "duplicate-key",  "unknown-key",       "missing-key",
        "wrong-type",  "out-of-range",   "bad-value",         "bad-name",
        "empty",       "duplicate-name", "unknown-reference", "port-conflict"};
    return rules;
}

// Loads `text` and checks the result is well-formed; returns false (with a message) if not.
::testing::AssertionResult loads_cleanly(const std::string& text) {
    LoadResult result;
    try {
        result = load_mission_text(text, "fuzz.yaml");
    } catch (const std::exception& error) {
        return ::testing::AssertionFailure() << "threw: " << error.what();
    } catch (...) {
        return ::testing::AssertionFailure() << "threw a non-exception";
    }
    if (result.ok() != result.errors.empty()) {
        return ::testing::AssertionFailure() << "a mission and errors, or neither";
    }
    for (const LoadError& e : result.errors) {
        if (e.line < 1 || e.col < 1 || known_rules().count(e.rule) == 0 || e.message.empty() ||
            e.file != "fuzz.yaml" || e.message.find('\n') != std::string::npos) {
            return ::testing::AssertionFailure() << "malformed error: " << e.to_string();
        }
    }
    if (!result.ok() && result.exit_code() == 0) {
        return ::testing::AssertionFailure() << "failed with exit code 0";
    }
    return ::testing::AssertionSuccess();
}

std::vector<std::string> split_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::string line;
    std::istringstream in(text);
    while (std::getline(in, line)) lines.push_back(line);
    return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
    std::string out;
    for (const std::string& line : lines) out += line + "\n";
    return out;
}

std::string mutate(std::string text, std::mt19937_64& rng) {
    static const std::vector<std::string> pieces = {
        ":", "- ", "[", "]", "{", "}", ",", "&a ", "*a", "!", "\t", "\"", "'", "#", "|", ">",
        "\n", std::string(1, '\0'), "\xff", "\xc3\xa9", "\xef\xbb\xbf", "\r", "? ", "~", "SAFE",
        "99999999999999999999999", "1e999", ".nan", "-", "  ", "---\n", "...\n", "<<: *a\n"};
    auto pick = [&](std::size_t n) {
        return n == 0 ? std::size_t{0} : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
    };
    switch (pick(8)) {
        case 0: {  // delete a line
            auto lines = split_lines(text);
            if (!lines.empty()) lines.erase(lines.begin() + static_cast<long>(pick(lines.size())));
            return join_lines(lines);
        }
        case 1: {  // duplicate a line
            auto lines = split_lines(text);
            if (!lines.empty()) {
                const std::size_t i = pick(lines.size());
                lines.insert(lines.begin() + static_cast<long>(i), lines[i]);
            }
            return join_lines(lines);
        }
        case 2: {  // swap two lines
            auto lines = split_lines(text);
            if (lines.size() > 1) std::swap(lines[pick(lines.size())], lines[pick(lines.size())]);
            return join_lines(lines);
        }
        case 3:  // flip a byte
            if (!text.empty()) text[pick(text.size())] = static_cast<char>(pick(256));
            return text;
        case 4:  // insert a piece of YAML syntax
            text.insert(pick(text.size() + 1), pieces[pick(pieces.size())]);
            return text;
        case 5:  // truncate
            text.resize(pick(text.size() + 1));
            return text;
        case 6: {  // indent or dedent a line
            auto lines = split_lines(text);
            if (!lines.empty()) {
                std::string& line = lines[pick(lines.size())];
                if (pick(2) == 0) {
                    line.insert(0, "  ");
                } else if (line.rfind("  ", 0) == 0) {
                    line.erase(0, 2);
                }
            }
            return join_lines(lines);
        }
        default: {  // delete a range of bytes
            if (text.empty()) return text;
            const std::size_t from = pick(text.size());
            text.erase(from, pick(std::min<std::size_t>(text.size() - from, 40) + 1));
            return text;
        }
    }
}

TEST(Robustness, GoodFixturesLoad) {
    const auto missions = good_missions();
    ASSERT_FALSE(missions.empty()) << "no good fixtures under " << root();
    for (const std::string& text : missions) EXPECT_TRUE(load_mission_text(text, "g").ok());
}

TEST(Robustness, MutatedFixturesNeverThrow) {
    const auto missions = good_missions();
    ASSERT_FALSE(missions.empty());
    constexpr int kCases = 4000;
    for (int seed = 0; seed < kCases; ++seed) {
        std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
        std::string text = missions[static_cast<std::size_t>(seed) % missions.size()];
        const int mutations = 1 + static_cast<int>(rng() % 4);
        for (int m = 0; m < mutations; ++m) text = mutate(std::move(text), rng);
        ASSERT_TRUE(loads_cleanly(text)) << "seed " << seed;
    }
}

TEST(Robustness, HostileDocuments) {
    // An alias bomb: 10^9 nodes once expanded.
    std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
    for (int i = 1; i < 10; ++i) {
        bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
        for (int k = 0; k < 10; ++k) bomb += (k ? ", *a" : "*a") + std::to_string(i - 1);
        bomb += "]\n";
    }
    // Deep nesting, in flow and block style, and through a chain of aliases.
    const std::string deep_flow = std::string(100000, '[') + std::string(100000, ']');
    std::string deep_block;
    for (int i = 0; i < 3000; ++i) deep_block += std::string(static_cast<std::size_t>(i), ' ') + "k:\n";
    std::string alias_chain = "a0: &a0 [x]\n";
    for (int i = 1; i < 300; ++i) {
        alias_chain += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" +
                       std::to_string(i - 1) + "]\n";
    }
    const std::vector<std::string> hostile = {
        bomb,
        deep_flow,
        deep_block,
        alias_chain,
        "a: &x [*x]\n",
        "a: &x {k: *x}\n",
        "&x [*x, *x]\n",
        "? [a, b]\n: c\n",
        "? {a: b}\n: c\n",
        "a: *undefined\n",
        "a: &x 1\nb: &x 2\n",
        "--- a\n--- b\n",
        std::string("mission: \0x\n", 12),
        "\xff\xfe m\0i\0",
        "\xef\xbb\xbf",
        "\t",
        "!!binary aGVsbG8=\n",
        "%YAML 3.0\n---\na: 1\n",
        "%TAG ! tag:example.com,2000:\n--- !foo 1\n",
        "mission: 99999999999999999999999999999999\n",
        "a: \"\\u12\"\n",
        "a: |\n\tx\n",
        "'",
        "\"",
        "[",
        "{",
        "- - - - -",
        ":",
        "? ",
        "a:\xe2\x80\xa8" "b",
        "a: \"\\ud83d\"\n",
        "...\n",
        "? \n: v\n",
        "a: \"\\N\\_\"\n",
        "&a: x\n",
        "a:\n\tb: 1\n",
    };
    for (std::size_t i = 0; i < hostile.size(); ++i) {
        EXPECT_TRUE(loads_cleanly(hostile[i])) << "hostile document " << i;
        EXPECT_FALSE(load_mission_text(hostile[i], "h").ok()) << "hostile document " << i;
    }
}


TEST(Robustness, LargeDocumentsLoadInLinearTime) {
    // Documents near the size limit, on one line and on many, with the constructs whose
    // positions are computed from the text (empty values, tabs in comments and strings).
    std::string one_line = "{";
    while (one_line.size() < 1'500'000) one_line += "k" + std::to_string(one_line.size()) + ": , ";
    one_line += "x: 1}";
    std::string many_lines;
    while (many_lines.size() < 1'500'000) {
        many_lines += "k" + std::to_string(many_lines.size()) + ":  #\tcomment\t\tend\n  \"a\tb\"\n";
    }
    std::string tabs_in_comment = "# " + std::string(1'500'000, '\t') + "\n" + kTabsTail;
    for (const std::string* text : {&one_line, &many_lines, &tabs_in_comment}) {
        // Processor time, not wall time: the machine running the tests may be busy.
        const std::clock_t start = std::clock();
        EXPECT_TRUE(loads_cleanly(*text));
        const double seconds = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
        EXPECT_LT(seconds, 60.0);  // quadratic time would take hours
    }
}

}  // namespace
}  // namespace keel::mission
