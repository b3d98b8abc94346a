#include "core/node/state_db.hpp"

#include <sqlite3.h>

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
        db.store_checkpoint("taskB", {0, 10}, {1, 2});
        db.store_checkpoint("taskB", {0, 12}, {3});
        db.store_checkpoint("taskB", {0, 11}, {9});  // older: ignored
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
    EXPECT_EQ(checkpoints[0].version, (fsm::Version{0, 12}));
    EXPECT_EQ(checkpoints[0].state, (std::vector<std::uint8_t>{3}));
    std::filesystem::remove(path);
}

// A state of a newer lineage replaces one with more steps of an older lineage, and survives
// reopening; an older lineage's write, however many steps, is ignored.
TEST(StateDb, ANewerLineageReplacesMoreStepsOfAnOlderOne) {
    const std::string path = temp_db("lineage");
    {
        StateDb db(path);
        db.store_checkpoint("taskB", {0, 107}, {1});
        db.store_checkpoint("taskB", {fsm::lineage_of(3, 2), 5}, {2});
        db.store_checkpoint("taskB", {0, 200}, {3});  // the abandoned lineage: ignored
    }
    StateDb db(path);
    const auto checkpoints = db.load_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].version, (fsm::Version{fsm::lineage_of(3, 2), 5}));
    EXPECT_EQ(checkpoints[0].state, (std::vector<std::uint8_t>{2}));
    std::filesystem::remove(path);
}

// A database written before lineages (no lineage column) opens, its states in the initial
// lineage.
TEST(StateDb, ADatabaseWithoutLineagesOpens) {
    const std::string path = temp_db("old");
    {
        sqlite3* raw = nullptr;
        ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
        ASSERT_EQ(sqlite3_exec(raw,
                               "CREATE TABLE checkpoints (task TEXT PRIMARY KEY, version INTEGER NOT NULL,"
                               " state BLOB NOT NULL, stored_at TEXT NOT NULL DEFAULT 'x');"
                               "INSERT INTO checkpoints (task, version, state) VALUES ('taskB', 9, x'07');",
                               nullptr, nullptr, nullptr),
                  SQLITE_OK);
        sqlite3_close(raw);
    }
    StateDb db(path);
    auto checkpoints = db.load_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].version, (fsm::Version{0, 9}));
    db.store_checkpoint("taskB", {fsm::lineage_of(2, 1), 1}, {8});
    checkpoints = db.load_checkpoints();
    EXPECT_EQ(checkpoints[0].version, (fsm::Version{fsm::lineage_of(2, 1), 1}));
    std::filesystem::remove(path);
}

TEST(StateDb, EmptyStateIsStored) {
    const std::string path = temp_db("empty");
    {
        StateDb db(path);
        db.store_checkpoint("taskA", {0, 3}, {});
    }
    StateDb db(path);
    const auto checkpoints = db.load_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].version, (fsm::Version{0, 3}));
    EXPECT_TRUE(checkpoints[0].state.empty());
    std::filesystem::remove(path);
}

TEST(StateDb, UnopenablePathIsAnError) {
    EXPECT_THROW(StateDb("/nonexistent-dir/x/state.sqlite"), StateDbError);
}

}  // namespace
}  // namespace keel::node
