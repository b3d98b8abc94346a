#include "core/node/checkpoint_persister.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include "core/node/state_db.hpp"

namespace keel::node {
namespace {

using namespace std::chrono_literals;

std::string temp_db(const char* name) {
    const auto path = std::filesystem::temp_directory_path() /
                      (std::string("keel-persister-") + name + "-" + std::to_string(getpid()) +
                       ".sqlite");
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path.string() + suffix);
    return path.string();
}

// Another connection holding the database's write lock: the writer waits on it (SQLite's
// busy timeout) until release().
class WriteLock {
public:
    explicit WriteLock(const std::string& path) {
        EXPECT_EQ(sqlite3_open(path.c_str(), &db_), SQLITE_OK);
        EXPECT_EQ(sqlite3_exec(db_, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), SQLITE_OK);
    }
    void release() {
        if (db_ == nullptr) return;
        EXPECT_EQ(sqlite3_exec(db_, "COMMIT", nullptr, nullptr, nullptr), SQLITE_OK);
        sqlite3_close(db_);
        db_ = nullptr;
    }
    ~WriteLock() { release(); }

private:
    sqlite3* db_ = nullptr;
};

void wait_until_taken(const CheckpointPersister& persister) {
    for (int i = 0; i < 2000 && persister.waiting() > 0; ++i) std::this_thread::sleep_for(1ms);
    ASSERT_EQ(persister.waiting(), 0u);
}

std::vector<CheckpointPersister::Written> all_written(CheckpointPersister& persister) {
    persister.stop();
    return persister.take_written();
}

TEST(CheckpointPersister, WritesEveryTasksNewestCheckpointAndSaysSo) {
    const std::string path = temp_db("writes");
    StateDb{path};  // the tables
    std::atomic<int> woken{0};
    CheckpointPersister persister(path, [&] { ++woken; });
    persister.store(1, "taskB", {0, 3}, {3, 3});
    persister.store(0, "taskA", {0, 7}, {7});
    const auto written = all_written(persister);
    ASSERT_EQ(written.size(), 2u);
    EXPECT_EQ(woken.load(), 2);
    for (const auto& one : written) EXPECT_TRUE(one.error.empty()) << one.error;
    StateDb db(path);
    const auto stored = db.load_checkpoints();
    ASSERT_EQ(stored.size(), 2u);
    for (const auto& checkpoint : stored) {
        if (checkpoint.task == "taskB") {
            EXPECT_EQ(checkpoint.version, (fsm::Version{0, 3}));
            EXPECT_EQ(checkpoint.state, (std::vector<std::uint8_t>{3, 3}));
        } else {
            EXPECT_EQ(checkpoint.task, "taskA");
            EXPECT_EQ(checkpoint.version, (fsm::Version{0, 7}));
        }
    }
}

// While the writer is busy, checkpoints of a task replace each other: only the newest is
// written (counted as coalesced), and it is what the database holds.
TEST(CheckpointPersister, AWaitingCheckpointIsReplacedByANewerOne) {
    const std::string path = temp_db("coalesce");
    StateDb{path};
    WriteLock lock(path);
    CheckpointPersister persister(path, [] {});
    persister.store(1, "taskB", {0, 1}, {1});
    wait_until_taken(persister);  // the writer waits on the lock with version 1
    for (std::uint64_t version = 2; version <= 10; ++version) {
        persister.store(1, "taskB", {0, version}, {static_cast<std::uint8_t>(version)});
    }
    EXPECT_EQ(persister.waiting(), 1u);
    EXPECT_EQ(persister.coalesced(), 8u);  // 2..9
    lock.release();
    const auto written = all_written(persister);
    ASSERT_EQ(written.size(), 2u);
    EXPECT_EQ(written[0].version, (fsm::Version{0, 1}));
    EXPECT_EQ(written[1].version, (fsm::Version{0, 10}));
    StateDb db(path);
    const auto stored = db.load_checkpoints();
    ASSERT_EQ(stored.size(), 1u);
    EXPECT_EQ(stored[0].version, (fsm::Version{0, 10}));
    EXPECT_EQ(stored[0].state, (std::vector<std::uint8_t>{10}));
}

// One task's stream of checkpoints never keeps another task's waiting: the writer takes
// the tasks in turn.
TEST(CheckpointPersister, TasksAreWrittenInTurn) {
    const std::string path = temp_db("turns");
    StateDb{path};
    WriteLock lock(path);
    CheckpointPersister persister(path, [] {});
    persister.store(0, "taskA", {0, 1}, {1});
    wait_until_taken(persister);
    persister.store(1, "taskB", {0, 1}, {1});
    persister.store(0, "taskA", {0, 2}, {2});
    lock.release();
    const auto written = all_written(persister);
    ASSERT_EQ(written.size(), 3u);
    EXPECT_EQ(written[0].task, 0);
    EXPECT_EQ(written[1].task, 1);  // lowest task first would write taskA's version 2 here
    EXPECT_EQ(written[2].task, 0);
    EXPECT_EQ(written[2].version, (fsm::Version{0, 2}));
}

TEST(CheckpointPersister, AFailedWriteIsReportedWithSQLitesError) {
    const std::string path = temp_db("fails");
    StateDb{path};
    CheckpointPersister persister(path, [] {});
    {
        // The table goes away under the writer: its statement fails.
        sqlite3* db = nullptr;
        ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
        ASSERT_EQ(sqlite3_exec(db, "DROP TABLE checkpoints", nullptr, nullptr, nullptr), SQLITE_OK);
        sqlite3_close(db);
    }
    persister.store(1, "taskB", {0, 1}, {1});
    const auto written = all_written(persister);
    ASSERT_EQ(written.size(), 1u);
    EXPECT_NE(written[0].error, "");
}

TEST(CheckpointPersister, ADatabaseThatCannotBeOpenedStopsTheStart) {
    EXPECT_THROW(CheckpointPersister("/nonexistent-dir/keel.sqlite", [] {}), StateDbError);
}

// -- HeldUntilStored -------------------------------------------------------------------------

TEST(HeldUntilStored, NothingWaitsForATaskWithNothingUnwritten) {
    HeldUntilStored<int> held;
    EXPECT_FALSE(held.unwritten(1));
    held.queued(1, 1);
    EXPECT_TRUE(held.unwritten(1));
    EXPECT_FALSE(held.unwritten(2));
    EXPECT_TRUE(held.written(1, 1).empty());
    EXPECT_FALSE(held.unwritten(1));
}

TEST(HeldUntilStored, WhatWaitsGoesOnceItsCheckpointIsWrittenInTheOrderHeld) {
    HeldUntilStored<int> held;
    held.queued(1, 1);
    held.hold(1, 50);  // the StoreCheckpoint line of ticket 1
    held.queued(1, 2);
    held.hold(1, 70);  // ticket 2's line
    held.hold(1, 71);  // the acknowledgement of the final checkpoint, ticket 2
    held.queued(2, 3);
    held.hold(2, 10);
    EXPECT_EQ(held.held(), 4u);
    EXPECT_EQ(held.written(1, 1), (std::vector<int>{50}));
    EXPECT_TRUE(held.unwritten(1));  // ticket 2 is not written: the ack still waits
    EXPECT_EQ(held.written(2, 3), (std::vector<int>{10}));
    EXPECT_EQ(held.written(1, 2), (std::vector<int>{70, 71}));
    EXPECT_EQ(held.held(), 0u);
}

// A checkpoint replaced while waiting is never written: the newer one's write releases what
// waited for either.
TEST(HeldUntilStored, ANewerWriteReleasesWhatWaitedForAReplacedOne) {
    HeldUntilStored<int> held;
    held.queued(1, 1);
    held.hold(1, 50);
    held.queued(1, 2);
    held.hold(1, 60);
    EXPECT_EQ(held.written(1, 2), (std::vector<int>{50, 60}));
}

// The host's write that replaces a foreign pin (a lower version) is queued while the pin's
// own write is still under way: the pin's write finishing releases nothing that waits for
// the replacing one (by version, it would have: the pin's is higher).
TEST(HeldUntilStored, APinsWriteFinishingDoesNotReleaseWhatWaitsForItsReplacement) {
    HeldUntilStored<int> held;
    held.queued(1, 1);  // the pin, taken by the writer
    held.queued(1, 2);  // the host's replacing write
    held.hold(1, 20);   // its StoreCheckpoint line
    EXPECT_TRUE(held.written(1, 1).empty());
    EXPECT_TRUE(held.unwritten(1));
    EXPECT_EQ(held.written(1, 2), (std::vector<int>{20}));
}

// A write that failed releases nothing that waits for it: it is dropped.
TEST(HeldUntilStored, WhatWaitsForAFailedWriteIsDropped) {
    HeldUntilStored<int> held;
    held.queued(1, 1);
    held.hold(1, 10);
    held.queued(1, 2);
    held.hold(1, 20);
    EXPECT_EQ(held.failed(1, 1), 1u);
    EXPECT_EQ(held.held(), 1u);
    EXPECT_EQ(held.written(1, 2), (std::vector<int>{20}));
}

}  // namespace
}  // namespace keel::node
