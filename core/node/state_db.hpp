// StateDb: what a node keeps on disk, in one SQLite file (WAL journal).
//
//   node_state   one row: the protocol's PersistentState without checkpoints (epoch, the
//                last view accepted, the boot counter) — so a restarted node boots as the
//                spec's Restart(n) says, with its persisted epoch. The view is a blob in
//                the layout `view_format` names (wire.hpp): 2 today; 1 in databases
//                written when a mission held at most 64 nodes, still read. A view that
//                cannot be read (another format, a corrupt blob) is a StateDbError naming
//                the field, never a silent first boot (keel-node --cold-start discards it).
//   checkpoints  on the Storage node: the latest checkpoint of every task, by task name,
//                written as the checkpointing service stores them (act::StoreCheckpoint,
//                off the loop: CheckpointPersister),
//                so the Storage node's checkpoints survive its restart
//
// Integrity at rest (fault model 3): each row carries the CRC-32 of its fields (column
// `crc`; NULL in a row written before checksums, until it is written again). A node state
// that fails it, or whose epoch or incarnation is beyond its width, is a StateDbError (the
// node does not start on it; --cold-start discards it); a checkpoint that fails it is
// left out of load_checkpoints and reported: lost, never restored.
//
// Writes are small transactions, durable when they return: synchronous=FULL (WAL: the log
// is synced at every commit), so a power loss loses nothing a caller was told is written,
// and an acknowledgement that waits for the write (checkpoint_persister.hpp) stands for
// data on the disk. Durability::normal (synchronous=NORMAL: a power loss may lose the last
// few commits, never corrupts) is for measuring what FULL costs (keel-store-bench). Every sqlite3 call is checked; a failing call is a StateDbError
// with SQLite's message and the file's path. Not thread-safe: one connection per thread.
// The node's loop owns one; the Storage node's checkpoint writer (checkpoint_persister.hpp)
// opens its own on the same file (WAL: the loop's small writes wait at most for one
// checkpoint's transaction, SQLite's busy timeout of 2 s bounding it).
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fsm/node_protocol.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace keel::node {

class StateDbError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct StoredState {
    fsm::Epoch epoch = 0;
    fsm::View view;
    std::uint32_t incarnation = 0;
    std::uint32_t boot = 0;  // the boot identifier of the node that saved it (0: none saved)
    // The mission revision of the image the node flew when it saved it (0: none saved). A
    // node refuses an image of a lower revision.
    std::int64_t revision = 0;
    // The highest ground command seq the node admitted (ground.hpp; 0: none): a command
    // replayed after a restart is refused too.
    std::int64_t ground_seq = 0;
    // The nodes the ground holds out of the cluster (NodeProtocol::held_out).
    fsm::NodeSet held_out{};
    // The SHA-256 (hex) of the mission image the node flew when it saved it (empty: none
    // saved). A view names configurations by the image's ids: a node that boots on another
    // image (an update) does not restore it.
    std::string image{};
    // The tasks the ground paused (ConfigSwitch::paused), by this image's task ids.
    fsm::TaskSet paused{};
};

struct NamedCheckpoint {
    std::string task;
    fsm::Version version;
    std::vector<std::uint8_t> state;
};

// The layout of the view blob save_state writes (wire.hpp, encode_view).
inline constexpr int kViewFormat = 2;

enum class Durability : std::uint8_t { full, normal };

class StateDb {
public:
    explicit StateDb(const std::string& path, Durability durability = Durability::full);
    ~StateDb();
    StateDb(const StateDb&) = delete;
    StateDb& operator=(const StateDb&) = delete;

    const std::string& path() const { return path_; }

    // Nothing when no state was saved; a StateDbError when the saved view cannot be read.
    std::optional<StoredState> load_state();
    void save_state(const StoredState& state);

    // The checkpoints that pass their checksum (fault model 3, integrity at rest); each
    // one that fails, or holds a version beyond the codec's widths, is left out and, with
    // `lost`, described there (a sentence naming the task, its version and the file).
    std::vector<NamedCheckpoint> load_checkpoints(std::vector<std::string>* lost = nullptr);
    // Keeps the newer of the stored and the given version of the task's checkpoint (lineage
    // first, as fsm::Version compares); with `replaces`, the given one (the host's write
    // over a foreign writer's, fsm::CheckpointStore::overridden).
    void store_checkpoint(const std::string& task, fsm::Version version,
                          const std::vector<std::uint8_t>& state, bool replaces = false);

private:
    void exec(const char* sql);
    bool has_column(const char* table, const char* column);
    sqlite3_stmt* prepare(const char* sql);
    [[noreturn]] void fail(const std::string& what);

    std::string path_;
    sqlite3* db_ = nullptr;
    sqlite3_stmt* save_state_ = nullptr;
    sqlite3_stmt* store_checkpoint_ = nullptr;
    sqlite3_stmt* replace_checkpoint_ = nullptr;
};

}  // namespace keel::node
