// The mission model's lookups and defaults, on the shipped prototype3 mission as a node reads
// it (its image, tests/missions/images/good/), and the loader's error format.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/mission/image.hpp"
#include "core/mission/mission.hpp"

namespace keel::mission {
namespace {

const std::string kImage =
    std::string(KEEL_SOURCE_DIR) + "/tests/missions/images/good/prototype3.json";

Mission prototype3() {
    LoadResult result = load_mission_image(kImage);
    EXPECT_TRUE(result.ok()) << (result.errors.empty() ? "" : result.errors[0].to_string());
    return result.ok() ? *result.mission : Mission{};
}

TEST(Mission, ReadFromItsImageWithDefaultsFilled) {
    const Mission m = prototype3();
    EXPECT_EQ(m.name, "prototype3");
    EXPECT_EQ(m.path, kImage);
    EXPECT_EQ(m.heartbeat.period_ms, 100);
    EXPECT_EQ(m.heartbeat.startup_grace_ms, kDefaultStartupGraceMs);
    EXPECT_EQ(m.heartbeat.tie_grace, 0);  // not stated: the ground is no voter
    EXPECT_EQ(m.tolerance.nodes, (std::vector<std::string>{"PN1", "PN2", "PN3"}));
    ASSERT_EQ(m.nodes.size(), 4u);
    EXPECT_EQ(m.nodes[0].role, NodeRole::none);
    EXPECT_EQ(m.nodes[3].role, NodeRole::storage);
    EXPECT_EQ(m.nodes[3].capacity.mem_mb, 4096);
    EXPECT_EQ(m.nodes[1].line, 0);  // an image has no source positions
    const Task* a = m.task("taskA");
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->component, "producer");
    EXPECT_EQ(a->period_ms, 20);
    EXPECT_FALSE(a->essential);
    EXPECT_FALSE(a->health.has_value());
    const Task* b = m.task("taskB");
    ASSERT_NE(b, nullptr);
    EXPECT_TRUE(b->essential && b->checkpoint);
    EXPECT_EQ(b->inputs, (std::vector<std::string>{"taskA"}));
    EXPECT_FALSE(b->period_ms.has_value());
    ASSERT_EQ(m.phases.size(), 2u);
    EXPECT_EQ(m.phases[0].tasks, (std::vector<std::string>{"taskA", "taskB"}));  // default: all
}

TEST(Mission, Lookups) {
    const Mission m = prototype3();
    EXPECT_EQ(m.address_of("PN1"), 0);
    EXPECT_EQ(m.address_of("ST1"), 3);
    EXPECT_EQ(m.address_of("nope"), -1);
    EXPECT_EQ(m.processing_nodes(), (std::vector<std::string>{"PN1", "PN2", "PN3"}));
    EXPECT_EQ(m.storage_nodes(), (std::vector<std::string>{"ST1"}));
    EXPECT_EQ(m.node("XX"), nullptr);
    EXPECT_EQ(m.phase("science")->initial, "S1");
    EXPECT_EQ(m.phase("none"), nullptr);
    const Configuration* s3 = m.configuration("S3");
    ASSERT_NE(s3, nullptr);
    EXPECT_EQ(s3->phase, "science");
    EXPECT_EQ(s3->observers, (std::vector<std::string>{"PN3"}));
    EXPECT_EQ(*s3->node_of("taskB"), "PN1");
    EXPECT_EQ(m.configuration("SAFE"), nullptr);
    const Phase& nominal = m.phases[0];
    EXPECT_EQ(nominal.configuration("P2")->master, "PN2");
    EXPECT_EQ(nominal.configuration("S1"), nullptr);  // another phase's
    const FailureEdge* edge = nominal.failure_edge("P2", "PN3");
    ASSERT_NE(edge, nullptr);
    EXPECT_EQ(edge->next, kSafe);
    EXPECT_EQ(nominal.failure_edge("P1", "ST1"), nullptr);
    EXPECT_EQ(nominal.recovery_edge("P2", "PN1"), nullptr);
    const PhaseEdge* phase_edge = nominal.phase_edge("science", "P4");
    ASSERT_NE(phase_edge, nullptr);
    EXPECT_EQ(phase_edge->to, "S4");
    EXPECT_EQ(nominal.phase_edge("nominal", "P1"), nullptr);
}

TEST(Mission, CapabilitiesAndNodeOf) {
    Mission m;
    Node node;
    node.name = "PN1";
    node.capabilities = {"opencv"};
    m.nodes.push_back(node);
    EXPECT_TRUE(m.node("PN1")->has_capability("opencv"));
    EXPECT_FALSE(m.node("PN1")->has_capability("gpu"));
    Configuration c;
    c.placement = {{"t1", "PN1"}};
    EXPECT_EQ(*c.node_of("t1"), "PN1");
    EXPECT_EQ(c.node_of("t2"), nullptr);
}

TEST(Mission, ErrorFormatAndExitCodes) {
    const LoadError e{"m.json", 1, 1, "tampered", "the image's sha256 is not its content's"};
    EXPECT_EQ(e.to_string(), "m.json:1:1: tampered: the image's sha256 is not its content's");
    EXPECT_TRUE(e.is_input_error());
    EXPECT_FALSE((LoadError{"m", 1, 1, "port-conflict", "x"}.is_input_error()));
    LoadResult result;
    result.errors.push_back(LoadError{"m", 1, 1, "unknown-reference", "x"});
    EXPECT_EQ(result.exit_code(), 1);
    result.errors.push_back(e);
    EXPECT_EQ(result.exit_code(), 2);
}

TEST(Mission, NormalisedJsonHoldsWhatWasRead) {
    const std::string json = to_json(prototype3());
    // Canonical: sorted keys, no whitespace.
    EXPECT_EQ(json.rfind("{\"heartbeat\":{\"miss_limit\":3,\"period_ms\":100,", 0), 0u) << json;
    EXPECT_NE(json.find("\"mission\":\"prototype3\",\"nodes\":[{\"capabilities\":[],"), std::string::npos);
    EXPECT_NE(json.find("\"on_phase\":[{\"from\":\"P1\",\"phase\":\"science\",\"to\":\"S1\"}"),
              std::string::npos);
    EXPECT_EQ(json.find("on_recovery"), std::string::npos);  // absent when empty
    EXPECT_EQ(json.find(' '), std::string::npos);
}

}  // namespace
}  // namespace keel::mission
