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
        fsm::NodeSet failed;
        failed.insert(0);
        failed.insert(255);
        db.save_state({2, fsm::View{2, 1, 3, 3, 200, failed}, 1});
        db.store_checkpoint("taskB", {0, 10}, {1, 2});
        db.store_checkpoint("taskB", {0, 12}, {3});
        db.store_checkpoint("taskB", {0, 11}, {9});  // older: ignored
    }
    StateDb db(path);
    const auto state = db.load_state();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->epoch, 2u);
    EXPECT_EQ(state->view.config, 3);
    EXPECT_EQ(state->view.master, 200);
    EXPECT_TRUE(state->view.failed.contains(0) && state->view.failed.contains(255));
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

// The host's write over a foreign pin (fsm::CheckpointStore::overridden) is kept on disk
// though its version is lower; a later ordinary write goes on from it.
TEST(StateDb, AReplacingWriteKeepsALowerVersion) {
    const std::string path = temp_db("replace");
    {
        StateDb db(path);
        db.store_checkpoint("taskB", {0, std::uint64_t{1} << 40}, {66});
        db.store_checkpoint("taskB", {0, 10}, {10});  // ordinary: ignored
        db.store_checkpoint("taskB", {0, 11}, {11}, true);
        db.store_checkpoint("taskB", {0, 12}, {12});
    }
    StateDb db(path);
    const auto checkpoints = db.load_checkpoints();
    ASSERT_EQ(checkpoints.size(), 1u);
    EXPECT_EQ(checkpoints[0].version, (fsm::Version{0, 12}));
    EXPECT_EQ(checkpoints[0].state, (std::vector<std::uint8_t>{12}));
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

// A database written when a mission held at most 64 nodes (no view_format column, the view
// in format 1) opens and its state is read; the next save writes format 2.
TEST(StateDb, ADatabaseWithAViewOfFormatOneOpens) {
    const std::string path = temp_db("format1");
    {
        sqlite3* raw = nullptr;
        ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
        ASSERT_EQ(sqlite3_exec(raw,
                               "CREATE TABLE node_state (id INTEGER PRIMARY KEY CHECK (id = 0),"
                               " epoch INTEGER NOT NULL, view BLOB NOT NULL, incarnation INTEGER NOT NULL);"
                               "INSERT INTO node_state VALUES (0, 4,"
                               " x'000000040000000200030003ff0000000000000006', 7);",
                               nullptr, nullptr, nullptr),
                  SQLITE_OK);
        sqlite3_close(raw);
    }
    {
        StateDb db(path);
        const auto state = db.load_state();
        ASSERT_TRUE(state);
        EXPECT_EQ(state->epoch, 4u);
        EXPECT_EQ(state->incarnation, 7u);
        EXPECT_EQ(state->view.epoch, 4u);
        EXPECT_EQ(state->view.seq, 2u);
        EXPECT_EQ(state->view.config, 3);
        EXPECT_EQ(state->view.master, fsm::kNoNode);
        EXPECT_TRUE(state->view.failed.contains(1) && state->view.failed.contains(2));
        EXPECT_EQ(state->view.failed.size(), 2);
        db.save_state(*state);
    }
    StateDb db(path);
    const auto again = db.load_state();
    ASSERT_TRUE(again);
    EXPECT_EQ(again->view, (fsm::View{4, 2, 3, 3, fsm::kNoNode, again->view.failed}));
    EXPECT_EQ(again->view.failed.size(), 2);
    std::filesystem::remove(path);
}

// A view this Keel cannot read (a format of a newer Keel, or a corrupt blob) stops the load
// with a message naming the problem, never a silent first boot.
TEST(StateDb, AnUnreadableViewIsRefusedWithAMessage) {
    const std::string path = temp_db("unreadable");
    {
        StateDb db(path);
        db.save_state({2, fsm::View{2, 1, 3, 3, 1, {}}, 1});
    }
    auto set = [&](const char* sql) {
        sqlite3* raw = nullptr;
        ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
        ASSERT_EQ(sqlite3_exec(raw, sql, nullptr, nullptr, nullptr), SQLITE_OK);
        sqlite3_close(raw);
    };
    set("UPDATE node_state SET view_format = 3");
    try {
        StateDb(path).load_state();
        FAIL() << "a view of format 3 was read";
    } catch (const StateDbError& error) {
        EXPECT_NE(std::string(error.what()).find("the persisted view (format 3) is unreadable: a format "
                                                 "this Keel does not read (it reads 1 and 2)"),
                  std::string::npos)
            << error.what();
    }
    set("UPDATE node_state SET view_format = 2, view = x'0000'");
    try {
        StateDb(path).load_state();
        FAIL() << "a corrupt view was read";
    } catch (const StateDbError& error) {
        EXPECT_NE(std::string(error.what()).find("input ends inside view.epoch"), std::string::npos)
            << error.what();
    }
    std::filesystem::remove(path);
}

// Fault model 3, integrity at rest: a row changed on the disk since it was written (a bit
// flipped, a torn or edited row) is never restored.
TEST(StateDb, ARecordChangedOnTheDiskFailsItsChecksum) {
    const std::string path = temp_db("checksum");
    {
        StateDb db(path);
        db.save_state({4, fsm::View{4, 2, 3, 3, 1, {}}, 2});
        db.store_checkpoint("taskA", {0, 41}, {1, 2, 3});
        db.store_checkpoint("taskB", {fsm::lineage_of(4, 2), 7}, {9, 9});
    }
    auto set = [&](const char* sql) {
        sqlite3* raw = nullptr;
        ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
        ASSERT_EQ(sqlite3_exec(raw, sql, nullptr, nullptr, nullptr), SQLITE_OK);
        sqlite3_close(raw);
    };
    {
        StateDb db(path);  // untouched: everything restores
        EXPECT_EQ(db.load_state()->epoch, 4u);
        std::vector<std::string> lost;
        EXPECT_EQ(db.load_checkpoints(&lost).size(), 2u);
        EXPECT_TRUE(lost.empty());
    }
    set("UPDATE checkpoints SET state = x'010203ff' WHERE task = 'taskA'");  // a flipped byte
    set("UPDATE checkpoints SET version = 8 WHERE task = 'taskB'");
    std::vector<std::string> lost;
    const auto kept = StateDb(path).load_checkpoints(&lost);
    EXPECT_TRUE(kept.empty());
    ASSERT_EQ(lost.size(), 2u);
    EXPECT_NE(lost[0].find("checkpoint of taskA"), std::string::npos) << lost[0];
    EXPECT_NE(lost[0].find("fails its checksum"), std::string::npos) << lost[0];
    set("UPDATE node_state SET incarnation = 3");
    try {
        StateDb(path).load_state();
        FAIL() << "a changed node state was restored";
    } catch (const StateDbError& error) {
        EXPECT_NE(std::string(error.what()).find("fails its checksum"), std::string::npos) << error.what();
    }
    // Written again, the rows are whole again.
    {
        StateDb db(path);
        db.save_state({5, fsm::View{5, 1, 3, 3, 2, {}}, 3});
        db.store_checkpoint("taskA", {0, 42}, {1});
        EXPECT_EQ(db.load_state()->epoch, 5u);
        EXPECT_EQ(db.load_checkpoints().size(), 1u);  // taskA; taskB stays lost
    }
    std::filesystem::remove(path);
}

TEST(StateDb, ARowWithoutAChecksumFromAnOlderDatabaseStillOpens) {
    const std::string path = temp_db("no-crc");
    {
        StateDb db(path);
        db.save_state({2, fsm::View{2, 1, 3, 3, 1, {}}, 1});
        db.store_checkpoint("taskA", {0, 5}, {1});
    }
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, "UPDATE node_state SET crc = NULL; UPDATE checkpoints SET crc = NULL", nullptr,
                           nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(raw);
    StateDb db(path);
    EXPECT_EQ(db.load_state()->epoch, 2u);
    EXPECT_EQ(db.load_checkpoints().size(), 1u);
    std::filesystem::remove(path);
}

// The boot identifier of the node that saved its state is saved with it, in its checksum;
// a row written before the column (NULL) reads as 0 and keeps its checksum.
TEST(StateDb, TheBootThatSavedTheStateIsKeptAndChecked) {
    const std::string path = temp_db("boot");
    {
        StateDb db(path);
        db.save_state({3, fsm::View{3, 1, 3, 3, 1, {}}, 2, 0xBEEF});
    }
    EXPECT_EQ(StateDb(path).load_state()->boot, 0xBEEFu);
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, "UPDATE node_state SET boot = 48880 + 1", nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(raw);
    try {
        StateDb(path).load_state();
        FAIL() << "a changed boot identifier was restored";
    } catch (const StateDbError& error) {
        EXPECT_NE(std::string(error.what()).find("fails its checksum"), std::string::npos) << error.what();
    }
    {
        StateDb db(path);
        db.save_state({3, fsm::View{3, 1, 3, 3, 1, {}}, 2});  // no boot saved: NULL-like 0
    }
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, "UPDATE node_state SET boot = NULL", nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(raw);
    const auto state = StateDb(path).load_state();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->boot, 0u);
    std::filesystem::remove(path);
}

// The last ground command's seq (ground.hpp) is saved with the state, in its checksum: a
// changed one is refused as any changed row.
TEST(StateDb, TheLastGroundSeqIsKeptAndChecked) {
    const std::string path = temp_db("ground");
    {
        StateDb db(path);
        db.save_state({3, fsm::View{3, 1, 3, 3, 1, {}}, 2, 7, 0, 1'795'000'000'000'000});
    }
    EXPECT_EQ(StateDb(path).load_state()->ground_seq, 1'795'000'000'000'000);
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, "UPDATE node_state SET ground_seq = 1", nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(raw);
    EXPECT_THROW(StateDb(path).load_state(), StateDbError);
    std::filesystem::remove(path);
}

// The image the node flew is saved with the state, in its checksum, and with the nodes
// the ground holds out: an update (another image) is told apart at the next boot.
TEST(StateDb, TheImageFlownAndTheNodesHeldOutAreKeptAndChecked) {
    const std::string path = temp_db("image");
    fsm::NodeSet held;
    held.insert(2);
    held.insert(200);
    {
        StateDb db(path);
        db.save_state({3, fsm::View{3, 1, 3, 3, 1, {}}, 2, 7, 0, 0, held, std::string(64, 'a')});
    }
    const auto state = StateDb(path).load_state();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->image, std::string(64, 'a'));
    EXPECT_EQ(state->held_out, held);
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, "UPDATE node_state SET image = 'b'", nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(raw);
    EXPECT_THROW(StateDb(path).load_state(), StateDbError);
    std::filesystem::remove(path);
}

// The tasks the ground paused are saved with the state, in its checksum: a restarted node
// keeps them paused; a changed or unreadable list is not restored.
TEST(StateDb, TheTasksPausedAreKeptAndChecked) {
    const std::string path = temp_db("paused");
    fsm::TaskSet paused;
    paused.insert(1);
    paused.insert(7);
    const StoredState saved{3, fsm::View{3, 1, 3, 3, 1, {}}, 2, 7, 0, 0, {}, std::string(64, 'a'), paused};
    {
        StateDb db(path);
        db.save_state(saved);
    }
    const auto state = StateDb(path).load_state();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->paused, paused);
    // Each change on the disk, to the row as saved: refused. The same ids moved to the
    // nodes held out sum apart from paused ones.
    for (const char* tampered : {"UPDATE node_state SET paused = '1'", "UPDATE node_state SET paused = '1,x'",
                                 "UPDATE node_state SET paused = '5000'",
                                 "UPDATE node_state SET held_out = paused, paused = NULL"}) {
        StateDb(path).save_state(saved);
        ASSERT_TRUE(StateDb(path).load_state());
        sqlite3* raw = nullptr;
        ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
        ASSERT_EQ(sqlite3_exec(raw, tampered, nullptr, nullptr, nullptr), SQLITE_OK);
        sqlite3_close(raw);
        EXPECT_THROW(StateDb(path).load_state(), StateDbError) << tampered;
    }
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
