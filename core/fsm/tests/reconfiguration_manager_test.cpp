#include "core/fsm/reconfiguration_manager.hpp"

#include <gtest/gtest.h>

#include "test_mission.hpp"

namespace keel::fsm {
namespace {

class ReconfigurationManagerTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    View initial = topology.initial_view();
    Outbox out{false};
    ConfigId id(const char* name) { return *topology.config_id(name); }
    bool entered_safe_mode() {
        for (const auto& action : out.actions()) {
            if (std::holds_alternative<act::EnterSafeMode>(action)) return true;
        }
        return false;
    }
};

TEST_F(ReconfigurationManagerTest, WorkerFailureFollowsTheEdge) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    manager.boot_as_master(initial);
    auto next = manager.exclude(PN2, Evidence{}, out);
    ASSERT_TRUE(next);
    EXPECT_EQ(next->config, id("P3"));
    EXPECT_EQ(next->seq, 1u);
    EXPECT_EQ(next->epoch, 1u);
    EXPECT_TRUE(next->failed.contains(PN2));
    EXPECT_FALSE(manager.exclude(PN2, Evidence{}, out)) << "a second declaration changes nothing";
}

TEST_F(ReconfigurationManagerTest, SecondFailureEntersSafeMode) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    manager.boot_as_master(initial);
    manager.exclude(PN2, Evidence{}, out);
    auto next = manager.exclude(PN3, Evidence{}, out);
    ASSERT_TRUE(next);
    EXPECT_TRUE(next->is_safe());
    EXPECT_EQ(next->base, id("P3"));
    EXPECT_TRUE(entered_safe_mode());
    EXPECT_FALSE(manager.on_phase(1, out)) << "safe mode is terminal";
}

TEST_F(ReconfigurationManagerTest, StorageFailureWithoutEdgeEntersSafeMode) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    manager.boot_as_master(initial);
    auto next = manager.exclude(ST1, Evidence{}, out);
    ASSERT_TRUE(next);
    EXPECT_TRUE(next->is_safe());
}

TEST_F(ReconfigurationManagerTest, AGroundCommandLeavesSafeModeOnlyForAConfigurationThatFits) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    manager.boot_as_master(initial);
    std::string why;
    EXPECT_FALSE(manager.ground_recovery(id("P1"), &why, out));
    EXPECT_EQ(why, "the cluster is not in safe mode");
    manager.exclude(PN2, Evidence{}, out);  // P3
    manager.exclude(PN3, Evidence{}, out);  // SAFE, PN2 and PN3 failed
    ASSERT_TRUE(manager.driving().is_safe());
    EXPECT_FALSE(manager.ground_recovery(id("P1"), &why, out));
    EXPECT_NE(why.find("uses PN2 (observer)"), std::string::npos) << why;
    EXPECT_FALSE(manager.ground_recovery(id("P2"), &why, out));
    EXPECT_NE(why.find("master is PN2"), std::string::npos) << why;
    EXPECT_FALSE(manager.ground_recovery(id("S3"), &why, out));
    EXPECT_NE(why.find("phase science"), std::string::npos) << why;
    EXPECT_FALSE(manager.ground_recovery(kSafeConfig, &why, out));
    EXPECT_TRUE(manager.driving().is_safe()) << "a refusal changes nothing";
}

TEST_F(ReconfigurationManagerTest, AGroundCommandKeepsTheFailedSetAndItsEdges) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    manager.boot_as_master(initial);
    manager.exclude(ST1, Evidence{}, out);  // no edge: SAFE
    ASSERT_TRUE(manager.driving().is_safe());
    std::string why;
    const auto next = manager.ground_recovery(id("P1"), &why, out);
    ASSERT_TRUE(next) << why;
    EXPECT_EQ(next->config, id("P1"));
    EXPECT_EQ(next->base, id("P1"));
    EXPECT_TRUE(next->failed.contains(ST1));
    const auto after = manager.exclude(PN3, Evidence{}, out);
    ASSERT_TRUE(after);
    EXPECT_EQ(after->config, id("P4"));
}

TEST_F(ReconfigurationManagerTest, TakeOverWalksFromTheLastView) {
    ReconfigurationManager manager(topology, PN2, Mutant::none);
    NodeSet suspects;
    suspects.insert(PN1);
    const View next = manager.take_over(initial, 2, suspects, TakeOverEvidence{}, out);
    EXPECT_EQ(next.config, id("P2"));
    EXPECT_EQ(next.epoch, 2u);
    EXPECT_EQ(next.seq, 1u);
    EXPECT_EQ(next.master, PN2);
    EXPECT_TRUE(manager.active());
}

TEST_F(ReconfigurationManagerTest, TakeOverWithTwoFailuresIsSafe) {
    ReconfigurationManager manager(topology, PN3, Mutant::none);
    NodeSet suspects;
    suspects.insert(PN1);
    suspects.insert(PN2);
    const View next = manager.take_over(initial, 3, suspects, TakeOverEvidence{}, out);
    EXPECT_TRUE(next.is_safe());
    EXPECT_EQ(topology.host(next, 1), PN3);
}

TEST_F(ReconfigurationManagerTest, PhaseChangeMapsTheConfiguration) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    manager.boot_as_master(initial);
    manager.exclude(PN2, Evidence{}, out);  // P3
    auto next = manager.on_phase(*topology.phase_id("science"), out);
    ASSERT_TRUE(next);
    EXPECT_EQ(next->config, id("S3"));
    EXPECT_TRUE(next->failed.contains(PN2));
    EXPECT_FALSE(manager.on_phase(*topology.phase_id("science"), out)) << "already there";
}

TEST_F(ReconfigurationManagerTest, PhaseChangeOntoAFailedNodeIsRefused) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    View view = initial;
    view.failed.insert(PN3);  // P1 with PN3 excluded: S1 would place taskA on PN3
    manager.boot_as_master(view);
    EXPECT_FALSE(manager.on_phase(*topology.phase_id("science"), out));
}

TEST_F(ReconfigurationManagerTest, ReclaimReannouncesTheDrivenView) {
    ReconfigurationManager manager(topology, PN1, Mutant::none);
    manager.boot_as_master(initial);
    manager.exclude(PN2, Evidence{}, out);
    const View next = manager.reclaim(4, out);
    EXPECT_EQ(next.epoch, 4u);
    EXPECT_EQ(next.seq, 1u);
    EXPECT_EQ(next.config, id("P3"));
    EXPECT_TRUE(next.failed.contains(PN2));
}

TEST_F(ReconfigurationManagerTest, MutantKeepsTasksOnAFailedWorker) {
    ReconfigurationManager manager(topology, PN1, Mutant::ignore_failed_node_in_placement);
    manager.boot_as_master(initial);
    auto next = manager.exclude(PN3, Evidence{}, out);
    ASSERT_TRUE(next);
    EXPECT_EQ(next->config, id("P1"));
    EXPECT_EQ(topology.host(*next, 1), PN3);
}

}  // namespace
}  // namespace keel::fsm
