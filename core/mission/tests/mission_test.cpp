// The mission model's lookups and the loader's edge cases (load_mission_text).
#include <gtest/gtest.h>

#include <string>

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

}  // namespace
}  // namespace keel::mission
