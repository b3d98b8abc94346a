// CheckpointPersister: the Storage node writes checkpoints to disk off its loop.
//
// A checkpoint of tens of MiB takes SQLite tens of milliseconds to write (95 ms for 16 MiB
// here). Written on the loop, a burst of them held the Storage node's heartbeats back long
// enough for it to be declared failed. The loop now hands each checkpoint the protocol
// stores (act::StoreCheckpoint) to one writer thread, which has its own connection to the
// node's database and runs at a lower priority than the loop. Per task, only the newest
// checkpoint waits: a newer one replaces a waiting older one (counted, coalesced()), as a
// write that arrives later would. So at most two states per task are held: the one being
// written and the newest waiting.
//
// Nothing the Storage node says about a task runs ahead of its disk (HeldUntilStored): its
// acknowledgement of a final checkpoint, its reply to a restore and its StoreCheckpoint
// trace line wait until the version they stand for is written. Seen from the other nodes
// (and the trace), a checkpoint is stored when it is on disk, as spec/Handoff.tla's Storage
// node holds what it stored across a restart (StoredMonotoneProp); a checkpoint still
// waiting when the Storage node crashes is a write that never arrived.
#pragma once

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/fsm/types.hpp"
#include "core/node/held_until_stored.hpp"
#include "core/tasking/pi_mutex.hpp"

namespace keel::node {

class StateDb;

class CheckpointPersister {
public:
    struct Written {
        fsm::TaskId task = 0;
        fsm::Version version;
        std::uint64_t ticket = 0;  // store()'s
        std::string error;  // empty: on disk; otherwise SQLite's error (the copy is lost)
    };

    // Opens its own connection to the database at `path` (a StateDbError if it cannot) and
    // starts the writer. `written` is called from the writer thread after each write (the
    // node wakes its loop with it).
    CheckpointPersister(const std::string& path, std::function<void()> written);
    // stop().
    ~CheckpointPersister();
    // Writes everything still waiting, then stops the writer (take_written() still reports
    // those writes). Idempotent.
    void stop();
    CheckpointPersister(const CheckpointPersister&) = delete;
    CheckpointPersister& operator=(const CheckpointPersister&) = delete;

    // Queues the task's checkpoint, replacing a waiting older one of the same task, and
    // returns its ticket (1, 2, ...: the order of the calls), which its Written carries.
    // `replaces`: written even below the version on disk (act::StoreCheckpoint); a
    // checkpoint that replaces a waiting one that did inherits it.
    std::uint64_t store(fsm::TaskId task, std::string task_name, fsm::Version version,
                        std::vector<std::uint8_t> state, bool replaces = false);
    // The writes finished since the last call, in the order they finished.
    std::vector<Written> take_written();
    // Checkpoints replaced while waiting by a newer one of their task.
    std::uint64_t coalesced() const;
    // Writes finished (on disk or failed).
    std::uint64_t writes() const;
    // Checkpoints queued and not yet taken by the writer.
    std::size_t waiting() const;

private:
    struct Waiting {
        std::string task_name;
        fsm::Version version;
        std::vector<std::uint8_t> state;
        bool replaces = false;
        std::uint64_t ticket = 0;
    };
    void run(StateDb* db);

    // Priority-inheriting (core/tasking/pi_mutex.hpp): the loop queues and takes here; the
    // writer runs at nice 10, or at the loop's priority under --realtime.
    mutable tasking::PiMutex mutex_;
    std::condition_variable_any wake_;
    std::map<fsm::TaskId, Waiting> waiting_;
    std::vector<Written> written_;
    std::uint64_t coalesced_ = 0;
    std::uint64_t tickets_ = 0;
    std::uint64_t writes_ = 0;
    bool stopping_ = false;
    std::function<void()> on_written_;
    std::thread writer_;
};

}  // namespace keel::node
