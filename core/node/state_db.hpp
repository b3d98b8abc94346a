// StateDb: what a node keeps on disk, in two files beside each other.
//
//   PATH.state   the node's own state (the protocol's PersistentState without checkpoints:
//                epoch, the last view accepted, the boot counter and identifier, the
//                revision and image flown, the ground's last seq, the nodes it holds out
//                and the tasks it paused), so a restarted node boots as the spec's
//                Restart(n) says. A record file written in place with one fdatasync
//                (state_file.hpp): the save is on the critical path of every switch. A
//                record that cannot be read (no slot passes its checksum, a field beyond
//                its width, a view that does not decode) is a StateDbError naming the
//                file and the field, never a silent first boot (keel-node --cold-start
//                discards it).
//   PATH         SQLite (WAL journal), table `checkpoints`: on the Storage node the latest
//                checkpoint of every task, by task name, written as the checkpointing
//                service stores them (act::StoreCheckpoint, off the loop:
//                CheckpointPersister), so the Storage node's checkpoints survive its
//                restart. Its table `node_state` is where Keel kept the node's state
//                before the state file: one row, read while the state file holds no
//                record (an upgraded node), replaced at the first save to the state file
//                by a marker (view_format 0): from then on a state file with no record is
//                an error (lost or emptied), never a first boot.
//                Its view is a blob in the layout `view_format` names (wire.hpp): 2, or 1
//                in databases written when a mission held at most 64 nodes.
//
// Integrity at rest (fault model 3): each record carries the CRC-32 of its fields (the
// state file's slots; the rows' column `crc`, NULL in a row written before checksums). A
// node state row that fails it, or whose epoch or incarnation is beyond its width, is a
// StateDbError; a checkpoint that fails it is left out of load_checkpoints and reported:
// lost, never restored.
//
// Writes are durable when they return: the state file's fdatasync; the database's
// synchronous=FULL (WAL: the log is synced at every commit), so a power loss loses nothing
// a caller was told is written, and an acknowledgement that waits for the write
// (checkpoint_persister.hpp) stands for data on the disk. Durability::normal
// (synchronous=NORMAL: a power loss may lose the last few commits, never corrupts) is for
// measuring what FULL costs (keel-store-bench). Every sqlite3 call is checked; a failing
// call is a StateDbError with SQLite's message and the file's path. Not thread-safe: one
// connection per thread. The node's loop owns one; the Storage node's checkpoint writer
// (checkpoint_persister.hpp) opens its own on the same file (WAL: the loop's writes wait
// at most for one checkpoint's transaction, SQLite's busy timeout of 2 s bounding it) and
// never touches the state file.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fsm/node_protocol.hpp"
#include "core/node/state_file.hpp"

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

// The checksum of a node_state row as an older Keel wrote it (its fields in the row's
// columns: the view blob, the id lists as "3,7"), which load_state checks.
std::uint32_t node_state_row_crc(std::uint64_t epoch, std::span<const std::uint8_t> view, std::uint64_t incarnation,
                                 std::int64_t format, std::uint32_t boot, std::int64_t revision,
                                 std::int64_t ground_seq, const std::string& held_out, const std::string& image,
                                 const std::string& paused);

class StateDb {
public:
    explicit StateDb(const std::string& path, Durability durability = Durability::full);
    ~StateDb();
    StateDb(const StateDb&) = delete;
    StateDb& operator=(const StateDb&) = delete;

    const std::string& path() const { return path_; }

    // Nothing when no state was saved; a StateDbError when the saved state cannot be read
    // (no record of the state file passes its checksum, a field beyond its width or
    // unreadable). `note`: why the state file's newest slot was passed over, if it was
    // (StateFile::Record::note), else left empty.
    std::optional<StoredState> load_state(std::string* note = nullptr);
    // Durable when it returns (one fdatasync of the state file); a StateDbError when not.
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

    // The node state a database of an older Keel holds (its node_state row), read until the
    // state file holds a record.
    std::optional<StoredState> load_legacy_state();
    // Whether the database's node_state row is the marker a save to the state file leaves.
    bool moved_to_file();
    static constexpr std::int64_t kMovedToFile = 0;  // the marker row's view_format
    StateFile& state_file();

    std::string path_;
    sqlite3* db_ = nullptr;
    std::unique_ptr<StateFile> state_file_;  // opened at the first load_state or save_state
    bool moved_ = false;  // the marker is known to be there
    sqlite3_stmt* store_checkpoint_ = nullptr;
    sqlite3_stmt* replace_checkpoint_ = nullptr;
};

}  // namespace keel::node
