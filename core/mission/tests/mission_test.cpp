// The mission model's lookups and the loader's edge cases (load_mission_text).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/mission/yaml_source.hpp"

namespace keel::mission {
namespace {

const char* const kMinimal = R"(mission: minimal
schema: 1
heartbeat: {period_ms: 100, miss_limit: 3}
tolerance: {node_failures: 1}
nodes:
  PN1: {kind: processing, capabilities: [opencv]}
  PN2: {kind: processing}
  ST1: {kind: interface, role: storage}
  IF1: {kind: interface, capacity: {cpu: 20}}
tasks:
  t1: {port: 10, requires: [opencv], params: {gain: 0.5, mode: fast, n: 3, on: true}}
  t2: {port: 11, inputs: [t1], health: {min: 0, max: 1.5}}
phases:
  main:
    initial: C1
    configurations:
      C1: {master: PN1, observers: [PN2], tasks: {t1: PN1, t2: PN2}}
      C2: {master: PN2, tasks: {t1: PN1, t2: PN2}}
    on_failure:
      C1: {PN1: C2, PN2: SAFE}
    on_phase:
      other: {C1: D1}
  other:
    tasks: [t2]
    initial: D1
    configurations:
      D1: {master: PN1, tasks: {t2: PN1}}
)";

Mission load_ok(const std::string& text) {
    LoadResult result = load_mission_text(text, "test.yaml");
    EXPECT_TRUE(result.ok()) << (result.errors.empty() ? "" : result.errors[0].to_string());
    return result.ok() ? *result.mission : Mission{};
}

LoadError load_one_error(const std::string& text) {
    LoadResult result = load_mission_text(text, "test.yaml");
    EXPECT_FALSE(result.ok());
    EXPECT_EQ(result.errors.size(), 1u);
    if (result.errors.size() != 1) {
        for (const LoadError& e : result.errors) ADD_FAILURE() << "reported: " << e.to_string();
    }
    return result.errors.empty() ? LoadError{} : result.errors[0];
}

TEST(Mission, LoadsAndFillsDefaults) {
    const Mission m = load_ok(kMinimal);
    EXPECT_EQ(m.name, "minimal");
    EXPECT_EQ(m.path, "test.yaml");
    EXPECT_EQ(m.heartbeat.period_ms, 100);
    EXPECT_EQ(m.tolerance.nodes, (std::vector<std::string>{"PN1", "PN2", "ST1", "IF1"}));
    ASSERT_EQ(m.nodes.size(), 4u);
    EXPECT_EQ(m.nodes[0].role, NodeRole::none);
    EXPECT_EQ(m.nodes[2].role, NodeRole::storage);
    EXPECT_EQ(m.nodes[3].role, NodeRole::interface);
    EXPECT_EQ(m.nodes[3].capacity.cpu, 20);
    EXPECT_FALSE(m.nodes[3].capacity.mem_mb.has_value());
    EXPECT_EQ(m.nodes[1].line, 7);
    const Task* t1 = m.task("t1");
    ASSERT_NE(t1, nullptr);
    EXPECT_EQ(t1->component, "t1");
    EXPECT_EQ(t1->load.cpu, 0);
    EXPECT_EQ(t1->load.mem_mb, 0);
    ASSERT_EQ(t1->params.size(), 4u);
    EXPECT_EQ(std::get<double>(t1->params[0].second), 0.5);
    EXPECT_EQ(std::get<std::string>(t1->params[1].second), "fast");
    EXPECT_EQ(std::get<std::int64_t>(t1->params[2].second), 3);
    EXPECT_EQ(std::get<bool>(t1->params[3].second), true);
    const Task* t2 = m.task("t2");
    ASSERT_TRUE(t2->health.has_value());
    EXPECT_EQ(t2->health->min, 0.0);
    EXPECT_EQ(t2->health->max, 1.5);
    EXPECT_FALSE(t2->health->deadline_ms.has_value());
    ASSERT_EQ(m.phases.size(), 2u);
    EXPECT_EQ(m.phases[0].tasks, (std::vector<std::string>{"t1", "t2"}));
    EXPECT_EQ(m.phases[1].tasks, (std::vector<std::string>{"t2"}));
}

TEST(Mission, Lookups) {
    const Mission m = load_ok(kMinimal);
    EXPECT_EQ(m.address_of("PN1"), 0);
    EXPECT_EQ(m.address_of("IF1"), 3);
    EXPECT_EQ(m.address_of("nope"), -1);
    EXPECT_EQ(m.processing_nodes(), (std::vector<std::string>{"PN1", "PN2"}));
    EXPECT_EQ(m.storage_nodes(), (std::vector<std::string>{"ST1"}));
    EXPECT_TRUE(m.node("PN1")->has_capability("opencv"));
    EXPECT_FALSE(m.node("PN2")->has_capability("opencv"));
    EXPECT_EQ(m.node("XX"), nullptr);
    EXPECT_EQ(m.phase("other")->initial, "D1");
    EXPECT_EQ(m.phase("none"), nullptr);
    const Configuration* d1 = m.configuration("D1");
    ASSERT_NE(d1, nullptr);
    EXPECT_EQ(d1->phase, "other");
    EXPECT_EQ(*d1->node_of("t2"), "PN1");
    EXPECT_EQ(d1->node_of("t1"), nullptr);
    const Phase& main = m.phases[0];
    EXPECT_EQ(main.configuration("C2")->master, "PN2");
    EXPECT_EQ(main.configuration("D1"), nullptr);
    const FailureEdge* edge = main.failure_edge("C1", "PN2");
    ASSERT_NE(edge, nullptr);
    EXPECT_EQ(edge->next, kSafe);
    EXPECT_EQ(edge->line, 20);
    EXPECT_EQ(main.failure_edge("C2", "PN1"), nullptr);
    const PhaseEdge* phase_edge = main.phase_edge("other", "C1");
    ASSERT_NE(phase_edge, nullptr);
    EXPECT_EQ(phase_edge->to, "D1");
    EXPECT_EQ(main.phase_edge("other", "C2"), nullptr);
}

TEST(Mission, ErrorFormatAndExitCodes) {
    const LoadError e{"m.yaml", 3, 9, "bad-value", "schema is the integer 2; allowed: 1"};
    EXPECT_EQ(e.to_string(), "m.yaml:3:9: bad-value: schema is the integer 2; allowed: 1");
    EXPECT_TRUE(e.is_input_error());
    EXPECT_FALSE((LoadError{"m", 1, 1, "port-conflict", "x"}.is_input_error()));
    LoadResult result;
    result.errors.push_back(LoadError{"m", 1, 1, "unknown-reference", "x"});
    EXPECT_EQ(result.exit_code(), 1);
    result.errors.push_back(e);
    EXPECT_EQ(result.exit_code(), 2);
}

TEST(Loader, EmptyTextIsASyntaxError) {
    for (const char* text : {"", "# only a comment\n", "\n\n"}) {
        const LoadError e = load_one_error(text);
        EXPECT_EQ(e.rule, "yaml-syntax");
        EXPECT_EQ(e.message, "the mission file is empty");
        EXPECT_EQ(e.line, 1);
        EXPECT_EQ(e.col, 1);
    }
}


// The minimal mission with `from` replaced by `to` (once).
std::string minimal_with(const std::string& from, const std::string& to) {
    std::string text = kMinimal;
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

TEST(Loader, FloatsPrintLikePython) {
    using detail::python_float_repr;
    EXPECT_EQ(python_float_repr(1.0), "1.0");
    EXPECT_EQ(python_float_repr(-0.0), "-0.0");
    EXPECT_EQ(python_float_repr(0.25), "0.25");
    EXPECT_EQ(python_float_repr(1000.0), "1000.0");
    EXPECT_EQ(python_float_repr(1e16), "1e+16");
    EXPECT_EQ(python_float_repr(1234567890123456.0), "1234567890123456.0");
    EXPECT_EQ(python_float_repr(0.0001), "0.0001");
    EXPECT_EQ(python_float_repr(0.00001), "1e-05");
    EXPECT_EQ(python_float_repr(-2.5e-300), "-2.5e-300");
    EXPECT_EQ(python_float_repr(0.1), "0.1");
    EXPECT_EQ(python_float_repr(1.0 / 3.0), "0.3333333333333333");
    EXPECT_EQ(python_float_repr(HUGE_VAL), "inf");
    EXPECT_EQ(python_float_repr(std::nan("")), "nan");
}

TEST(Loader, EmptyValuesArePlacedAfterTheirIndicator) {
    // PyYAML puts an empty scalar just after the ':' (or '-') that introduced it, however
    // many blank lines and comments follow.
    LoadError e = load_one_error(
        minimal_with("heartbeat: {period_ms: 100, miss_limit: 3}", "heartbeat:   # later\n\n# x"));
    EXPECT_EQ(e.rule, "wrong-type");
    EXPECT_EQ(e.line, 3);
    EXPECT_EQ(e.col, 11);
    e = load_one_error(minimal_with("  PN2: {kind: processing}",
                                    "  PN2:\n    kind: processing\n    capabilities:\n    - opencv\n    -"));
    EXPECT_EQ(e.message, "nodes.PN2.capabilities.1 must be a string, not null");
    EXPECT_EQ(e.line, 11);
    EXPECT_EQ(e.col, 6);
    // At the end of the text, after a comment with no line break.
    const LoadResult end = load_mission_text("mission: m\nschema: 1\nheartbeat: {period_ms: 1, miss_limit: 1}\n"
                                             "tolerance: {node_failures: 0}\nnodes: {PN1: {kind: processing}}\n"
                                             "tasks: {}\nphases:\n  # comment", "t");
    ASSERT_EQ(end.errors.size(), 1u);
    EXPECT_EQ(end.errors[0].message, "phases must be a mapping, not null");
    EXPECT_EQ(end.errors[0].line, 7);
    EXPECT_EQ(end.errors[0].col, 8);
    e = load_one_error(minimal_with("{master: PN2, tasks:", "{master: , tasks:"));
    EXPECT_EQ(e.message, "phases.main.configurations.C2.master must be a string, not null");
    EXPECT_EQ(e.line, 18);
    EXPECT_EQ(e.col, 19);
}

TEST(Loader, KeysAreTakenAsWritten) {
    const Mission m = load_ok(minimal_with("  PN2: {kind: processing}", "  null: {kind: processing}\n  PN2: {kind: processing}"));
    EXPECT_NE(m.node("null"), nullptr);
    const LoadError e = load_one_error(minimal_with("  PN2: {kind: processing}", "  ~: {kind: processing}"));
    EXPECT_EQ(e.rule, "bad-name");
    EXPECT_EQ(e.message, "'~' is not a valid name in nodes");
}

TEST(Loader, PositionsCountCharactersAndSkipTheByteOrderMark) {
    LoadError e = load_one_error("\xef\xbb\xbf" + minimal_with("mission: minimal", "mission: 5"));
    EXPECT_EQ(e.line, 1);
    EXPECT_EQ(e.col, 10);
    e = load_one_error(minimal_with("  t2: {port: 11,", "  t2: {params: {x: \"\xc3\xa9\xc3\xa9\"}, port: 0,"));
    EXPECT_EQ(e.rule, "out-of-range");
    EXPECT_EQ(e.line, 12);
    EXPECT_EQ(e.col, 33);  // 35 in bytes
}

TEST(Loader, LineEndings) {
    std::string crlf;
    std::string cr;
    for (char c : minimal_with("miss_limit: 3", "miss_limit: 0")) {
        crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
        cr += c == '\n' ? '\r' : c;
    }
    for (const std::string& text : {crlf, cr}) {
        const LoadError e = load_one_error(text);
        EXPECT_EQ(e.rule, "out-of-range");
        EXPECT_EQ(e.line, 3);
        EXPECT_EQ(e.col, 41);
    }
    EXPECT_EQ(load_one_error(minimal_with("minimal", "mini\xe2\x80\xa8mal")).rule, "yaml-syntax");
    EXPECT_EQ(load_one_error(minimal_with("minimal", "mini\xc2\x85mal")).rule, "yaml-syntax");
}

TEST(Loader, TabsOnlyInQuotedOrBlockScalarsAndComments) {
    load_ok(minimal_with("mission: minimal", "mission: \"tab\there\"  #\tcomment\n#\tcomment"));
    load_ok(minimal_with("mission: minimal", "mission: |\n  tab\there\n"));
    load_ok("\xef\xbb\xbf#\tcomment after the byte-order mark\n" + std::string(kMinimal));
    for (const char* bad : {"mission:\tminimal", "mission: mini\tmal", "mission: minimal\t",
                            "mission: |\n\ttab\n"}) {
        EXPECT_EQ(load_one_error(minimal_with("mission: minimal", bad)).rule, "yaml-syntax") << bad;
    }
}

TEST(Loader, YamlThatTheParsersWouldReadApartIsRefused) {
    for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
             {"port: 10", "port: !!int \"10\""},
             {"port: 10", "port: ! 10"},
             {"mission: minimal", "mission: \"minimal"},
             {"mission: minimal", "mission: &m: minimal"},
             {"mission: minimal", "mission:\nminimal"},
             {"  PN2: {kind: processing}", "  PN2\n  PN3: {kind: processing}"},
             {"  PN2: {kind: processing}", "  : {kind: processing}"},
             {"observers: [PN2]", "observers: [PN2, , PN1]"},
             {"observers: [PN2]", "observers: [:PN2]"},
             {"mission: minimal", "mission: &a x\nother: &a y"},
             {"mission: minimal", "mission: \x01"},
             {"mission: minimal", "mission: minimal\n? \n: x"},
         }) {
        const LoadError e = load_one_error(minimal_with(from, to));
        EXPECT_EQ(e.rule, "yaml-syntax") << to;
    }
    EXPECT_EQ(load_one_error(std::string(kMinimal) + "---\nmission: again\n").rule, "yaml-syntax");
    EXPECT_EQ(load_one_error("# nothing but\n...\n").message,
              "expected the node content, but found '<document end>'");
}

TEST(Loader, IntegersAreIntegersAndFitIn64Bits) {
    LoadError e = load_one_error(minimal_with("period_ms: 100", "period_ms: 100.0"));
    EXPECT_EQ(e.rule, "wrong-type");
    EXPECT_EQ(e.message, "heartbeat.period_ms must be an integer, not the number 100.0");
    e = load_one_error(minimal_with("period_ms: 100", "period_ms: -00099999999999999999999"));
    EXPECT_EQ(e.rule, "out-of-range");
    EXPECT_EQ(e.message, "the integer -99999999999999999999 does not fit in 64 bits");
    // Two errors at one place: not an integer, and beyond the maximum.
    const LoadResult both = load_mission_text(minimal_with("period_ms: 100", "period_ms: 1e9"), "t");
    ASSERT_EQ(both.errors.size(), 2u);
    EXPECT_EQ(both.errors[0].rule, "out-of-range");
    EXPECT_EQ(both.errors[1].rule, "wrong-type");
}

TEST(Loader, ErrorsAreSortedDedupedAndOneLine) {
    // A duplicate key inside an anchored mapping used twice is one error, not two.
    const LoadError e = load_one_error(minimal_with(
        "  PN1: {kind: processing, capabilities: [opencv]}\n  PN2: {kind: processing}",
        "  PN1: &p {kind: processing, kind: interface}\n  PN2: *p"));
    EXPECT_EQ(e.rule, "duplicate-key");
    const LoadResult result = load_mission_text(
        minimal_with("  t1: {", "  \"a\\nb\": {port: 10}\n  \"c\\td\": {port: 12}\n  t1: {"), "t");
    ASSERT_EQ(result.errors.size(), 2u);
    EXPECT_EQ(result.errors[0].message, "'a\\nb' is not a valid name in tasks");
    EXPECT_EQ(result.errors[1].message, "'c\\td' is not a valid name in tasks");
    EXPECT_LT(result.errors[0].line, result.errors[1].line);
}

TEST(Loader, Limits) {
    std::string deep = "mission: " + std::string(101, '[') + std::string(101, ']') + "\n";
    LoadError e = load_one_error(deep);
    EXPECT_EQ(e.message, "nested deeper than 100 levels");
    e = load_one_error("a: &x [*x]\n");
    EXPECT_EQ(e.message, "cyclic alias");
    EXPECT_EQ(e.line, 1);
    EXPECT_EQ(e.col, 4);
    e = load_one_error(std::string(16 * 1024 * 1024 + 1, '#'));
    EXPECT_EQ(e.message, "the mission file is larger than 16 MiB");
}

TEST(Loader, FilesThatCannotBeRead) {
    LoadResult result = load_mission_file("/nonexistent/mission.yaml");
    ASSERT_EQ(result.errors.size(), 1u);
    EXPECT_EQ(result.errors[0].to_string(),
              "/nonexistent/mission.yaml:1:1: yaml-syntax: cannot read: No such file or directory");
    result = load_mission_file("/");
    ASSERT_EQ(result.errors.size(), 1u);
    EXPECT_EQ(result.errors[0].message, "cannot read: Is a directory");
    EXPECT_EQ(result.exit_code(), 2);
    const LoadError e = load_one_error("mission: \xff\xfe\n");
    EXPECT_EQ(e.message, "not UTF-8 text (byte 9)");
}

}  // namespace
}  // namespace keel::mission
