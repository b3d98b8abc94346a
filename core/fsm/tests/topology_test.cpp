#include "core/fsm/topology.hpp"

#include <gtest/gtest.h>

#include "test_mission.hpp"

namespace keel::fsm {
namespace {

class TopologyTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = *topology.node_id("PN1");
    NodeId PN2 = *topology.node_id("PN2");
    NodeId PN3 = *topology.node_id("PN3");
    NodeId ST1 = *topology.node_id("ST1");
    TaskId taskA = *topology.task_id("taskA");
    TaskId taskB = *topology.task_id("taskB");
    ConfigId id(const char* name) { return *topology.config_id(name); }
};

TEST_F(TopologyTest, IdsFollowFileOrder) {
    EXPECT_EQ(PN1, 0);
    EXPECT_EQ(ST1, 3);
    EXPECT_EQ(topology.storage_node(), ST1);
    EXPECT_EQ(topology.processing_nodes().size(), 3);
    EXPECT_EQ(topology.heartbeat_period_ns(), 100 * kNanosecondsPerMillisecond);
    EXPECT_EQ(topology.miss_limit(), 3);
}

TEST(TopologyBuild, StartupGraceIsInPeriodsAndNeverBelowTheMissLimit) {
    auto mission = testing::prototype3();
    EXPECT_EQ(Topology::build(mission, nullptr)->startup_grace_periods(), 20);  // default 2000 ms
    mission.heartbeat.startup_grace_ms = 450;
    EXPECT_EQ(Topology::build(mission, nullptr)->startup_grace_periods(), 5);  // rounded up
    mission.heartbeat.startup_grace_ms = 0;
    EXPECT_EQ(Topology::build(mission, nullptr)->startup_grace_periods(), 3);  // the miss limit
    mission.heartbeat.startup_grace_ms = -1;
    std::string error;
    EXPECT_FALSE(Topology::build(mission, &error));
    EXPECT_NE(error.find("startup_grace_ms"), std::string::npos) << error;
}

TEST(TopologyBuild, TieGraceIsTheMissionsAndZeroWhenNotStated) {
    auto mission = testing::prototype3();
    EXPECT_EQ(Topology::build(mission, nullptr)->tie_grace(), 0);  // the ground is no voter
    mission.heartbeat.tie_grace = 3;
    EXPECT_EQ(Topology::build(mission, nullptr)->tie_grace(), 3);
    mission.heartbeat.tie_grace = -1;
    std::string error;
    EXPECT_FALSE(Topology::build(mission, &error));
    EXPECT_NE(error.find("tie_grace"), std::string::npos) << error;
}

TEST_F(TopologyTest, EpochOwnershipFollowsSuccession) {
    EXPECT_EQ(topology.priority(), (std::vector<NodeId>{PN1, PN2, PN3}));
    EXPECT_EQ(topology.owner(1), PN1);
    EXPECT_EQ(topology.owner(2), PN2);
    EXPECT_EQ(topology.owner(4), PN1);
    EXPECT_EQ(topology.next_epoch(PN2, 1), 2u);
    EXPECT_EQ(topology.next_epoch(PN3, 1), 3u);
    EXPECT_EQ(topology.next_epoch(PN2, 2), 5u);
}

TEST_F(TopologyTest, InitialViewPlacesTasks) {
    const View view = topology.initial_view();
    EXPECT_EQ(view.epoch, 1u);
    EXPECT_EQ(topology.config_name(view.config), "P1");
    EXPECT_EQ(topology.host(view, taskA), PN2);
    EXPECT_EQ(topology.host(view, taskB), PN3);
    EXPECT_TRUE(topology.tasks_on(view, PN3).contains(taskB));
    EXPECT_EQ(topology.monitors(view).size(), 3);
    EXPECT_EQ(topology.role_in(view, PN1), Role::Master);
    EXPECT_EQ(topology.role_in(view, PN3), Role::Observer);
    EXPECT_EQ(topology.role_in(view, ST1), Role::Worker);
}

TEST_F(TopologyTest, WalkFollowsEdgesAndSkipsNodesThatDoNotMatter) {
    NodeSet failed;
    failed.insert(PN2);
    EXPECT_EQ(topology.walk(id("P1"), {PN2}, failed).config, id("P3"));
    failed.insert(PN1);
    EXPECT_EQ(topology.walk(id("P1"), {PN2, PN1}, failed).config, kSafeConfig);
    // PN2 does not matter to P3 (it hosts nothing there): the configuration stays.
    NodeSet only;
    only.insert(PN2);
    EXPECT_EQ(topology.walk(id("P3"), {PN2}, only).config, id("P3"));
}

// A readmission goes where the mission's on_recovery edge says, else to the configuration
// of the smaller failed set; from safe mode always to the latter.
TEST(TopologyBuild, RecoveryFollowsTheMissionsEdgeElseTheSmallerFailedSet) {
    keel::mission::Mission mission = testing::prototype3();
    std::string error;
    auto canonical = Topology::build(mission, &error);
    ASSERT_TRUE(canonical) << error;
    mission.phases[0].on_recovery.push_back({"P4", "PN3", "P3", 0});
    auto edged = Topology::build(mission, &error);
    ASSERT_TRUE(edged) << error;
    const NodeId PN2 = *edged->node_id("PN2");
    const NodeId PN3 = *edged->node_id("PN3");
    View view = edged->initial_view();
    view.config = view.base = *edged->config_id("P4");
    view.failed.insert(PN3);
    EXPECT_EQ(canonical->recovery_target(view, PN3), *edged->config_id("P1"));
    EXPECT_EQ(edged->recovery_target(view, PN3), *edged->config_id("P3"));
    view.failed.insert(PN2);
    view.config = kSafeConfig;  // beyond the tolerance: no edge from safe mode
    EXPECT_EQ(edged->recovery_target(view, PN3), *edged->config_id("P3"));  // the walk of {PN2}
    EXPECT_EQ(edged->recovery_target(view, PN2), *edged->config_id("P4"));  // the walk of {PN3}
}

// The Storage node matters to a configuration only when it places a checkpointed task, as
// keel-verify check reads the graph: without one, its failure keeps the configuration.
TEST(TopologyBuild, TheStorageNodeMattersOnlyWhereACheckpointedTaskIsPlaced) {
    keel::mission::Mission mission = testing::prototype3();
    std::string error;
    auto checkpointed = Topology::build(mission, &error);
    ASSERT_TRUE(checkpointed) << error;
    for (auto& task : mission.tasks) task.checkpoint = false;
    auto plain = Topology::build(mission, &error);
    ASSERT_TRUE(plain) << error;
    const NodeId ST1 = *plain->node_id("ST1");
    const ConfigId P1 = *plain->config_id("P1");
    NodeSet failed;
    failed.insert(ST1);
    EXPECT_EQ(checkpointed->walk(P1, {ST1}, failed).config, kSafeConfig);  // no edge for ST1
    EXPECT_EQ(plain->walk(P1, {ST1}, failed).config, P1);
}

TEST_F(TopologyTest, SafeModeRunsEssentialTasksOnTheMaster) {
    View view = topology.initial_view();
    view.config = kSafeConfig;
    view.master = PN3;
    view.failed.insert(PN1);
    EXPECT_EQ(topology.host(view, taskB), PN3);
    EXPECT_EQ(topology.host(view, taskA), kNoNode);
    EXPECT_EQ(topology.observers(view), (std::vector<NodeId>{PN2}));
}

TEST_F(TopologyTest, PhaseTargets) {
    EXPECT_EQ(topology.phase_target(id("P3"), *topology.phase_id("science")), id("S3"));
    EXPECT_EQ(topology.phase_target(kSafeConfig, 1), kNoConfig);
}

TEST(TopologyBuild, RejectsMissionsBeyondLimits) {
    auto mission = testing::prototype3();
    mission.heartbeat.period_ms = 0;
    std::string error;
    EXPECT_FALSE(Topology::build(mission, &error));
    EXPECT_NE(error.find("heartbeat"), std::string::npos);
}

}  // namespace
}  // namespace keel::fsm
