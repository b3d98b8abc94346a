#include "core/node/state_db.hpp"

#include <sqlite3.h>

#include <fstream>
#include <iterator>

#include "core/node/wire.hpp"

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
    std::filesystem::remove(path.string() + ".state");
    return path.string();
}

std::string ids_text(const auto& set) {
    std::string text;
    set.for_each([&](auto id) { text += (text.empty() ? "" : ",") + std::to_string(id); });
    return text;
}

// The node_state row an older Keel saved (before the state file): its columns and their
// checksum, as that Keel wrote them. The database's schema is StateDb's.
void save_row(const std::string& path, const StoredState& state) {
    { StateDb schema(path); }
    const std::vector<std::uint8_t> view = encode_view(state.view);
    const std::string held = ids_text(state.held_out);
    const std::string paused = ids_text(state.paused);
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &raw), SQLITE_OK);
    sqlite3_stmt* insert = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(raw,
                                 "INSERT OR REPLACE INTO node_state (id, epoch, view, incarnation, view_format, crc,"
                                 " boot, revision, ground_seq, held_out, image, paused)"
                                 " VALUES (0, ?1, ?2, ?3, 2, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
                                 -1, &insert, nullptr),
              SQLITE_OK);
    sqlite3_bind_int64(insert, 1, state.epoch);
    sqlite3_bind_blob(insert, 2, view.data(), static_cast<int>(view.size()), SQLITE_TRANSIENT);
    sqlite3_bind_int64(insert, 3, state.incarnation);
    sqlite3_bind_int64(insert, 4,
                       node_state_row_crc(state.epoch, view, state.incarnation, 2, state.boot, state.revision,
                                          state.ground_seq, held, state.image, paused));
    sqlite3_bind_int64(insert, 5, state.boot);
    sqlite3_bind_int64(insert, 6, state.revision);
    sqlite3_bind_int64(insert, 7, state.ground_seq);
    sqlite3_bind_text(insert, 8, held.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert, 9, state.image.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(insert, 10, paused.c_str(), -1, SQLITE_TRANSIENT);
    EXPECT_EQ(sqlite3_step(insert), SQLITE_DONE);
    sqlite3_finalize(insert);
    sqlite3_close(raw);
}

std::vector<char> file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
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
    save_row(path, {2, fsm::View{2, 1, 3, 3, 1, {}}, 1});
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
    save_row(path, {4, fsm::View{4, 2, 3, 3, 1, {}}, 2});
    {
        StateDb db(path);
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
    save_row(path, {2, fsm::View{2, 1, 3, 3, 1, {}}, 1});
    {
        StateDb db(path);
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
    save_row(path, {3, fsm::View{3, 1, 3, 3, 1, {}}, 2, 0xBEEF});
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
    save_row(path, {3, fsm::View{3, 1, 3, 3, 1, {}}, 2});  // no boot saved: NULL-like 0
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
    save_row(path, {3, fsm::View{3, 1, 3, 3, 1, {}}, 2, 7, 0, 1'795'000'000'000'000});
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
    save_row(path, {3, fsm::View{3, 1, 3, 3, 1, {}}, 2, 7, 0, 0, held, std::string(64, 'a')});
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
    save_row(path, saved);
    const auto state = StateDb(path).load_state();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->paused, paused);
    // Each change on the disk, to the row as saved: refused. The same ids moved to the
    // nodes held out sum apart from paused ones.
    for (const char* tampered : {"UPDATE node_state SET paused = '1'", "UPDATE node_state SET paused = '1,x'",
                                 "UPDATE node_state SET paused = '5000'",
                                 "UPDATE node_state SET held_out = paused, paused = NULL"}) {
        save_row(path, saved);
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

// The node's state lives in the state file (state_file.hpp), every field of it.
TEST(StateDb, TheStateFileKeepsEveryFieldOfTheState) {
    const std::string path = temp_db("state-file");
    fsm::NodeSet held;
    held.insert(3);
    held.insert(255);
    fsm::TaskSet paused;
    paused.insert(0);
    paused.insert(1023);
    fsm::NodeSet failed;
    failed.insert(7);
    const StoredState saved{0xFF'FFFE, fsm::View{0xFF'FFFE, 9, 4, 2, 200, failed}, fsm::kMaxIncarnation,
                            0xDEAD'BEEF, 12, 1'795'000'000'000'000, held, std::string(64, 'c'), paused};
    StateDb(path).save_state(saved);
    EXPECT_TRUE(std::filesystem::is_regular_file(path + ".state"));
    const auto state = StateDb(path).load_state();
    ASSERT_TRUE(state);
    EXPECT_EQ(state->epoch, saved.epoch);
    EXPECT_EQ(state->view, saved.view);
    EXPECT_EQ(state->incarnation, saved.incarnation);
    EXPECT_EQ(state->boot, saved.boot);
    EXPECT_EQ(state->revision, saved.revision);
    EXPECT_EQ(state->ground_seq, saved.ground_seq);
    EXPECT_EQ(state->held_out, held);
    EXPECT_EQ(state->image, saved.image);
    EXPECT_EQ(state->paused, paused);
    // Saved again and again, the newest wins, the file's size never changes.
    const auto size = std::filesystem::file_size(path + ".state");
    for (std::uint32_t i = 1; i <= 5; ++i) {
        StateDb db(path);
        db.save_state({i, fsm::View{i, 1, 3, 3, 1, {}}, i});
        EXPECT_EQ(db.load_state()->incarnation, i);
    }
    EXPECT_EQ(StateDb(path).load_state()->epoch, 5u);
    EXPECT_EQ(std::filesystem::file_size(path + ".state"), size);
    std::filesystem::remove(path);
}

// A database of an older Keel: its node_state row is read until the state file holds a
// record, and replaced at the first save by a marker, so that a state file lost (or
// emptied) later is refused: never a first boot, never the older row's state.
TEST(StateDb, AnOlderDatabasesRowIsReadThenLeftBehind) {
    const std::string path = temp_db("legacy");
    save_row(path, {4, fsm::View{4, 2, 3, 3, 1, {}}, 6});
    {
        StateDb db(path);
        EXPECT_EQ(db.load_state()->incarnation, 6u);
        db.save_state({4, fsm::View{4, 2, 3, 3, 1, {}}, 7});
    }
    EXPECT_EQ(StateDb(path).load_state()->incarnation, 7u);
    for (const bool emptied : {false, true}) {
        std::filesystem::remove(path + ".state");
        if (emptied) write_bytes(path + ".state", std::vector<char>(2 * StateFile::kSlotBytes, 0));
        try {
            StateDb(path).load_state();
            ADD_FAILURE() << "a lost state file was a first boot (emptied: " << emptied << ")";
        } catch (const StateDbError& error) {
            EXPECT_NE(std::string(error.what()).find("says the node's state was saved there"), std::string::npos)
                << error.what();
        }
    }
    // A fresh database and no state file: a first boot.
    const std::string fresh = temp_db("legacy-fresh");
    EXPECT_FALSE(StateDb(fresh).load_state());
    std::filesystem::remove(path);
    std::filesystem::remove(fresh);
}

// A slot zeroed beside a record of a later save (the file cut or wiped at rest) is no
// "never written" slot: the save in the other slot is restored and the load says so; a
// file cut short is allocated in full again, and saves go on.
TEST(StateDb, AZeroedOrCutSlotIsSaidNotTakenForAFirstSave) {
    const std::string path = temp_db("zeroed");
    const std::string file = path + ".state";
    for (std::uint32_t i = 1; i <= 3; ++i) StateDb(path).save_state({3, fsm::View{3, i, 4, 4, 1, {}}, i});
    // Save 3 is in slot 0 (saves alternate from slot 0), save 2 in slot 1.
    std::vector<char> bytes = file_bytes(file);
    ASSERT_EQ(bytes.size(), 2 * StateFile::kSlotBytes);
    std::fill(bytes.begin(), bytes.begin() + StateFile::kSlotBytes, 0);
    write_bytes(file, bytes);
    std::string note;
    EXPECT_EQ(StateDb(path).load_state(&note)->incarnation, 2u);
    EXPECT_NE(note.find("fails its checksum"), std::string::npos) << note;
    // Cut after slot 0: slot 1 reads as zero beside save 3 (restored, said), and the file
    // is whole again for the next save.
    StateDb(path).save_state({3, fsm::View{3, 4, 4, 4, 1, {}}, 4});
    bytes = file_bytes(file);
    bytes.resize(StateFile::kSlotBytes);
    write_bytes(file, bytes);
    note.clear();
    {
        StateDb db(path);
        const auto state = db.load_state(&note);
        ASSERT_TRUE(state);
        EXPECT_NE(note, "");
        db.save_state({3, fsm::View{3, 5, 4, 4, 1, {}}, 5});
    }
    EXPECT_EQ(std::filesystem::file_size(file), 2 * StateFile::kSlotBytes);
    EXPECT_EQ(StateDb(path).load_state()->incarnation, 5u);
    std::filesystem::remove(path);
}

// Fault model 3 and power loss: every byte of the newest record changed (a bit flipped at
// rest, a save torn by a power loss) fails its slot's checksum. The previous save is
// restored then, and the load says so; with no previous save nothing is restored and the
// load is refused. A changed state is never restored as if it were the one saved.
TEST(StateDb, AChangedOrTornNewestRecordRestoresThePreviousSaveAndSaysSo) {
    const std::string path = temp_db("torn");
    const std::string file = path + ".state";
    StateDb(path).save_state({3, fsm::View{3, 1, 3, 3, 1, {}}, 1, 0, 0, 0, {}, std::string(64, 'a')});
    const std::vector<char> one_save = file_bytes(file);
    StateDb(path).save_state({3, fsm::View{3, 2, 4, 4, 1, {}}, 2, 0, 0, 0, {}, std::string(64, 'a')});
    const std::vector<char> two_saves = file_bytes(file);
    // The second save went to slot 1; its used bytes: the header, the record, the CRC.
    std::size_t used = StateFile::kSlotBytes;
    while (used > 0 && two_saves[StateFile::kSlotBytes + used - 1] == 0) --used;
    used = std::max(used, StateFile::kHeaderBytes + 4);
    int refused = 0;
    for (std::size_t at = 0; at < used; ++at) {
        std::vector<char> changed = two_saves;
        changed[StateFile::kSlotBytes + at] = static_cast<char>(changed[StateFile::kSlotBytes + at] ^ 0x10);
        write_bytes(file, changed);
        std::string note;
        const auto state = StateDb(path).load_state(&note);
        ASSERT_TRUE(state) << "byte " << at;
        EXPECT_EQ(state->incarnation, 1u) << "byte " << at;
        EXPECT_NE(note.find("fails its checksum"), std::string::npos) << "byte " << at << ": " << note;
        // The same change with no previous save to fall back on: refused.
        std::vector<char> alone = changed;
        std::fill(alone.begin(), alone.begin() + StateFile::kSlotBytes, 0);
        write_bytes(file, alone);
        try {
            StateDb(path).load_state();
            ADD_FAILURE() << "byte " << at << " changed and restored";
        } catch (const StateDbError& error) {
            ++refused;
            EXPECT_NE(std::string(error.what()).find("--cold-start"), std::string::npos) << error.what();
        }
    }
    EXPECT_EQ(refused, static_cast<int>(used));
    // Torn: the newest slot half written. The next save goes over the torn slot, never
    // over the record that stood.
    std::vector<char> torn = two_saves;
    std::fill(torn.begin() + StateFile::kSlotBytes + 10, torn.end(), 0);
    write_bytes(file, torn);
    {
        StateDb db(path);
        EXPECT_EQ(db.load_state()->incarnation, 1u);
        db.save_state({3, fsm::View{3, 2, 4, 4, 1, {}}, 3});
    }
    const std::vector<char> after = file_bytes(file);
    EXPECT_TRUE(std::equal(after.begin(), after.begin() + StateFile::kSlotBytes, one_save.begin()));
    std::string note;
    EXPECT_EQ(StateDb(path).load_state(&note)->incarnation, 3u);
    EXPECT_EQ(note, "");
    std::filesystem::remove(path);
}

TEST(StateDb, UnopenablePathIsAnError) {
    EXPECT_THROW(StateDb("/nonexistent-dir/x/state.sqlite"), StateDbError);
}

}  // namespace
}  // namespace keel::node
