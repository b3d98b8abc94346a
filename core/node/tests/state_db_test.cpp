#include "core/node/state_db.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

namespace keel::node {
namespace {

std::string temp_db(const char* name) {
    const auto path = std::filesystem::temp_directory_path() /
                      (std::string("keel-node-") + name + "-" + std::to_string(getpid()) + ".sqlite");
    std::filesystem::remove(path);
    std::filesystem::remove(path.string() + "-wal");
    std::filesystem::remove(path.string() + "-shm");
    return path.string();
}

TEST(StateDb, StateAndCheckpointsSurviveReopening) {
    const std::string path = temp_db("reopen");
    {
        StateDb db(path);
        EXPECT_FALSE(db.load_state());
        db.save_state({2, fsm::View{2, 1, 3, 3, 1, fsm::NodeSet::from_bits(1)}, 1});
        db.store_checkpoint("taskB", 10, {1, 2});
        db.store_checkpoint("taskB", 12, {3});
        db.store_checkpoint("taskB", 11, {9});  // older: ignored
    }
    StateDb db(path);
    const auto state = db.load_state();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->epoch, 2u);
    EXPECT_EQ(state->view.config, 3);
    EXPECT_EQ(state->incarnation, 1u);
    const auto checkpoints = db.load_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].task, "taskB");
    EXPECT_EQ(checkpoints[0].version, 12u);
    EXPECT_EQ(checkpoints[0].state, (std::vector<std::uint8_t>{3}));
    std::filesystem::remove(path);
}

TEST(StateDb, EmptyStateIsStored) {
    const std::string path = temp_db("empty");
    {
        StateDb db(path);
        db.store_checkpoint("taskA", 3, {});
    }
    StateDb db(path);
    const auto checkpoints = db.load_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].version, 3u);
    EXPECT_TRUE(checkpoints[0].state.empty());
    std::filesystem::remove(path);
}

TEST(StateDb, UnopenablePathIsAnError) {
    EXPECT_THROW(StateDb("/nonexistent-dir/x/state.sqlite"), StateDbError);
}

}  // namespace
}  // namespace keel::node
