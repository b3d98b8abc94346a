#include "core/node/subscriptions.hpp"

#include <gtest/gtest.h>

#include "core/mission/image.hpp"
#include "core/mission/mission.hpp"

namespace keel::node {
namespace {

TEST(Subscriptions, FollowTheConsumerAcrossConfigurations) {
    auto loaded = mission::load_mission_image(std::string(KEEL_SOURCE_DIR) +
                                              "/tests/missions/images/good/prototype3.json");
    ASSERT_TRUE(loaded.ok());
    std::string error;
    auto topology = fsm::Topology::build(*loaded.mission, &error);
    ASSERT_TRUE(topology) << error;
    Subscriptions subscriptions(*loaded.mission, *topology);
    const fsm::TaskId task_a = *topology->task_id("taskA");
    const fsm::TaskId task_b = *topology->task_id("taskB");
    fsm::View view = topology->initial_view();  // P1: taskB on PN3
    EXPECT_TRUE(subscriptions.update(view));
    ASSERT_EQ(subscriptions.destinations(task_a).size(), 1u);
    EXPECT_EQ(subscriptions.destinations(task_a)[0], *topology->node_id("PN3"));
    EXPECT_TRUE(subscriptions.destinations(task_b).empty());
    EXPECT_FALSE(subscriptions.update(view));
    view.config = *topology->config_id("P4");  // PN3 failed: taskB on PN1
    view.base = view.config;
    EXPECT_TRUE(subscriptions.update(view));
    EXPECT_EQ(subscriptions.destinations(task_a)[0], *topology->node_id("PN1"));
    EXPECT_EQ(subscriptions.describe(), "taskA(100) -> PN1");
}

}  // namespace
}  // namespace keel::node
