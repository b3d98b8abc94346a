#include "core/node/state_db.hpp"

#include <sqlite3.h>

#include <charconv>

#include <array>
#include <span>
#include <string_view>

#include "core/fsm/json.hpp"
#include "core/node/state_file.hpp"
#include "core/node/wire.hpp"

namespace keel::node {

namespace {

// CRC-32 (IEEE 802.3, reflected, as zlib's), over a record's fields in a fixed order
// (integers as 8 bytes, big-endian; the task name then a 0 byte): a record written by this
// class and changed since on the disk (a bit flipped at rest, a torn or edited row) fails.
class Crc32 {
public:
    Crc32& bytes(std::span<const std::uint8_t> data) {
        crc_ = StateFile::crc32_extend(crc_, data);
        return *this;
    }
    Crc32& text(const std::string& value) {
        bytes({reinterpret_cast<const std::uint8_t*>(value.data()), value.size()});
        const std::uint8_t end = 0;
        return bytes({&end, 1});
    }
    Crc32& integer(std::uint64_t value) {
        std::uint8_t big_endian[8];
        for (int i = 0; i < 8; ++i) big_endian[i] = static_cast<std::uint8_t>(value >> (56 - 8 * i));
        return bytes(big_endian);
    }
    std::uint32_t value() const { return crc_ ^ 0xFFFF'FFFFu; }

private:
    std::uint32_t crc_ = 0xFFFF'FFFFu;
};

}  // namespace

// A boot identifier, revision or ground seq of 0 (none saved, as in rows written before
// them) is not in the sum, so those rows keep their checksum.
std::uint32_t node_state_row_crc(std::uint64_t epoch, std::span<const std::uint8_t> view, std::uint64_t incarnation,
                        std::int64_t format, std::uint32_t boot, std::int64_t revision,
                        std::int64_t ground_seq, const std::string& held_out, const std::string& image,
                        const std::string& paused) {
    Crc32 crc;
    crc.integer(epoch).bytes(view).integer(incarnation).integer(static_cast<std::uint64_t>(format));
    if (boot != 0) crc.integer(std::uint64_t{boot});
    if (revision != 0) crc.integer(static_cast<std::uint64_t>(revision));
    if (ground_seq != 0) crc.integer(static_cast<std::uint64_t>(ground_seq));
    if (!held_out.empty()) crc.text(held_out);
    if (!image.empty()) crc.text(image);
    // Tagged: the same ids as held out and not paused sum apart.
    if (!paused.empty()) crc.text("paused:" + paused);
    return crc.value();
}

namespace {

// A node or task set as its ids in increasing order, "3,7"; empty for none.
template <typename Set>
std::string encode_ids(const Set& set) {
    std::string text;
    set.for_each([&](auto id) {
        if (!text.empty()) text += ',';
        text += std::to_string(id);
    });
    return text;
}

template <typename Id, int Capacity>
std::optional<fsm::IdSet<Id, Capacity>> decode_ids(const std::string& text) {
    fsm::IdSet<Id, Capacity> set;
    std::size_t at = 0;
    while (at < text.size()) {
        std::size_t end = text.find(',', at);
        if (end == std::string::npos) end = text.size();
        unsigned id = 0;
        const auto [stop, error] = std::from_chars(text.data() + at, text.data() + end, id);
        if (error != std::errc{} || stop != text.data() + end || id >= static_cast<unsigned>(Capacity)) {
            return std::nullopt;
        }
        set.insert(static_cast<Id>(id));
        at = end + 1;
    }
    return set;
}

// The node state as the state file's record (state_file.hpp): layout 1, integers
// little-endian: epoch (8), incarnation (8), boot (4), revision (8), ground seq (8), the view
// (2 bytes of length, then format 2 of wire.hpp), the image's SHA-256 hex (1 byte of
// length, then the text), the nodes held out (kMaxNodes bits) and the tasks paused
// (kMaxTasks bits), each set's words in order.
constexpr std::uint8_t kStateRecordLayout = 1;

class RecordWriter {
public:
    template <typename Int>
    void integer(Int value) {
        for (std::size_t i = 0; i < sizeof(Int); ++i) bytes_.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
    }
    void raw(std::span<const std::uint8_t> data) { bytes_.insert(bytes_.end(), data.begin(), data.end()); }
    template <typename Set>
    void set(const Set& ids) {
        for (int w = 0; w < Set::kWords; ++w) integer<std::uint64_t>(ids.word(w));
    }
    std::vector<std::uint8_t> take() { return std::move(bytes_); }

private:
    std::vector<std::uint8_t> bytes_;
};

class RecordReader {
public:
    explicit RecordReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
    template <typename Int>
    bool integer(Int& value) {
        if (bytes_.size() - at_ < sizeof(Int)) return false;
        std::uint64_t bits = 0;
        for (std::size_t i = 0; i < sizeof(Int); ++i) bits |= std::uint64_t{bytes_[at_ + i]} << (8 * i);
        value = static_cast<Int>(bits);
        at_ += sizeof(Int);
        return true;
    }
    bool raw(std::size_t size, std::span<const std::uint8_t>& into) {
        if (bytes_.size() - at_ < size) return false;
        into = bytes_.subspan(at_, size);
        at_ += size;
        return true;
    }
    template <typename Set>
    bool set(Set& ids) {
        for (int w = 0; w < Set::kWords; ++w) {
            std::uint64_t word = 0;
            if (!integer(word)) return false;
            ids.set_word(w, word);
        }
        return true;
    }
    bool done() const { return at_ == bytes_.size(); }

private:
    std::span<const std::uint8_t> bytes_;
    std::size_t at_ = 0;
};

std::vector<std::uint8_t> encode_state_record(const StoredState& state) {
    RecordWriter out;
    out.integer(kStateRecordLayout);
    out.integer<std::uint64_t>(state.epoch);
    out.integer<std::uint64_t>(state.incarnation);
    out.integer<std::uint32_t>(state.boot);
    out.integer<std::int64_t>(state.revision);
    out.integer<std::int64_t>(state.ground_seq);
    const std::vector<std::uint8_t> view = encode_view(state.view);
    out.integer<std::uint16_t>(static_cast<std::uint16_t>(view.size()));
    out.raw(view);
    const std::size_t image = std::min<std::size_t>(state.image.size(), 255);
    out.integer<std::uint8_t>(static_cast<std::uint8_t>(image));
    out.raw({reinterpret_cast<const std::uint8_t*>(state.image.data()), image});
    out.set(state.held_out);
    out.set(state.paused);
    return out.take();
}

// The state a record holds, or why it cannot be restored.
std::optional<StoredState> decode_state_record(std::span<const std::uint8_t> bytes, std::string& why) {
    RecordReader in(bytes);
    StoredState state;
    std::uint8_t layout = 0;
    std::uint64_t epoch = 0;
    std::uint64_t incarnation = 0;
    std::uint16_t view_size = 0;
    std::uint8_t image_size = 0;
    std::span<const std::uint8_t> view_bytes;
    std::span<const std::uint8_t> image;
    if (!in.integer(layout) || layout != kStateRecordLayout) {
        why = "its record is of a layout this Keel does not read (it reads " + std::to_string(kStateRecordLayout) +
              "): written by a newer Keel?";
        return std::nullopt;
    }
    if (!in.integer(epoch) || !in.integer(incarnation) || !in.integer(state.boot) || !in.integer(state.revision) ||
        !in.integer(state.ground_seq) || !in.integer(view_size) || !in.raw(view_size, view_bytes) ||
        !in.integer(image_size) || !in.raw(image_size, image) || !in.set(state.held_out) || !in.set(state.paused) ||
        !in.done()) {
        why = "its record is not the length its fields say";
        return std::nullopt;
    }
    if (epoch > fsm::kMaxEpoch || incarnation > fsm::kMaxIncarnation) {
        why = "the persisted epoch " + std::to_string(epoch) + " or incarnation " + std::to_string(incarnation) +
              " is beyond its width (types.hpp)";
        return std::nullopt;
    }
    std::string view_why;
    const std::optional<fsm::View> view = decode_view(view_bytes, &view_why);
    if (!view) {
        why = "the persisted view is unreadable: " + view_why;
        return std::nullopt;
    }
    state.epoch = static_cast<fsm::Epoch>(epoch);
    state.incarnation = static_cast<std::uint32_t>(incarnation);
    state.view = *view;
    state.image.assign(image.begin(), image.end());
    return state;
}

std::uint32_t checkpoint_crc(const std::string& task, fsm::Version version, std::span<const std::uint8_t> state) {
    return Crc32().text(task).integer(version.lineage).integer(version.count).bytes(state).value();
}

}  // namespace

StateDb::StateDb(const std::string& path, Durability durability) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
        SQLITE_OK) {
        fail("cannot open");
    }
    sqlite3_busy_timeout(db_, 2000);
    exec("PRAGMA journal_mode=WAL");
    exec(durability == Durability::full ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
    exec("CREATE TABLE IF NOT EXISTS node_state ("
         " id INTEGER PRIMARY KEY CHECK (id = 0),"
         " epoch INTEGER NOT NULL, view BLOB NOT NULL, incarnation INTEGER NOT NULL,"
         " view_format INTEGER NOT NULL DEFAULT 1)");
    // A database written before the capacity grew past 64 nodes holds its view in format 1
    // (wire.hpp, decode_view_format1): the column is added with 1, and the view is read in
    // that format until the node saves its state again, in format 2.
    if (!has_column("node_state", "view_format")) {
        exec("ALTER TABLE node_state ADD COLUMN view_format INTEGER NOT NULL DEFAULT 1");
    }
    exec("CREATE TABLE IF NOT EXISTS checkpoints ("
         " task TEXT PRIMARY KEY, version INTEGER NOT NULL, state BLOB NOT NULL,"
         " stored_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%f', 'now')),"
         " lineage INTEGER NOT NULL DEFAULT 0)");
    // A database written before lineages (fsm::Version) holds every state in the initial
    // lineage: the column is added with 0.
    if (!has_column("checkpoints", "lineage")) {
        exec("ALTER TABLE checkpoints ADD COLUMN lineage INTEGER NOT NULL DEFAULT 0");
    }
    // Integrity at rest (fault model 3): every row carries the CRC-32 of its fields. A row
    // of a database written before checksums has none (NULL) until it is written again.
    if (!has_column("node_state", "crc")) exec("ALTER TABLE node_state ADD COLUMN crc INTEGER");
    if (!has_column("checkpoints", "crc")) exec("ALTER TABLE checkpoints ADD COLUMN crc INTEGER");
    // The boot identifier of the node that saved its state (its next boot sends it as its
    // previous boot): NULL in a row written before it.
    if (!has_column("node_state", "boot")) exec("ALTER TABLE node_state ADD COLUMN boot INTEGER");
    // The mission revision the node flew (NULL in a row written before it: 0).
    if (!has_column("node_state", "revision")) exec("ALTER TABLE node_state ADD COLUMN revision INTEGER");
    // The highest ground command seq the node admitted (NULL in a row written before it: 0).
    if (!has_column("node_state", "ground_seq")) exec("ALTER TABLE node_state ADD COLUMN ground_seq INTEGER");
    // The node ids the ground holds out, "3,7" (NULL in a row written before it: none).
    if (!has_column("node_state", "held_out")) exec("ALTER TABLE node_state ADD COLUMN held_out TEXT");
    // The SHA-256 of the image the node flew (NULL in a row written before it: unknown).
    if (!has_column("node_state", "image")) exec("ALTER TABLE node_state ADD COLUMN image TEXT");
    // The task ids the ground paused, "0,2" (NULL in a row written before it: none).
    if (!has_column("node_state", "paused")) exec("ALTER TABLE node_state ADD COLUMN paused TEXT");
    store_checkpoint_ = prepare(
        "INSERT INTO checkpoints (task, version, state, lineage, crc) VALUES (?1, ?2, ?3, ?4, ?5)"
        " ON CONFLICT(task) DO UPDATE SET version = ?2, state = ?3, lineage = ?4, crc = ?5,"
        " stored_at = strftime('%Y-%m-%dT%H:%M:%f', 'now')"
        " WHERE (?4, ?2) >= (checkpoints.lineage, checkpoints.version)");
    replace_checkpoint_ = prepare(
        "INSERT INTO checkpoints (task, version, state, lineage, crc) VALUES (?1, ?2, ?3, ?4, ?5)"
        " ON CONFLICT(task) DO UPDATE SET version = ?2, state = ?3, lineage = ?4, crc = ?5,"
        " stored_at = strftime('%Y-%m-%dT%H:%M:%f', 'now')");
}

StateDb::~StateDb() {
    sqlite3_finalize(store_checkpoint_);
    sqlite3_finalize(replace_checkpoint_);
    sqlite3_close(db_);
}

void StateDb::fail(const std::string& what) {
    const std::string message = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    throw StateDbError(path_ + ": " + what + ": " + message);
}

void StateDb::exec(const char* sql) {
    char* error = nullptr;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, &error) != SQLITE_OK) {
        const std::string text = error != nullptr ? error : "unknown error";
        sqlite3_free(error);
        throw StateDbError(path_ + ": " + text);
    }
}

bool StateDb::has_column(const char* table, const char* column) {
    sqlite3_stmt* statement = prepare((std::string("PRAGMA table_info(") + table + ")").c_str());
    bool found = false;
    while (!found && sqlite3_step(statement) == SQLITE_ROW) {
        const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(statement, 1));
        found = name != nullptr && std::string_view(name) == column;
    }
    sqlite3_finalize(statement);
    return found;
}

sqlite3_stmt* StateDb::prepare(const char* sql) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &statement, nullptr) != SQLITE_OK) fail("prepare");
    return statement;
}

StateFile& StateDb::state_file() {
    if (!state_file_) {
        try {
            state_file_ = std::make_unique<StateFile>(path_ + ".state");
        } catch (const StateFileError& error) {
            throw StateDbError(error.what());
        }
    }
    return *state_file_;
}

std::optional<StoredState> StateDb::load_state(std::string* note) {
    std::optional<StateFile::Record> record;
    try {
        record = state_file().load();
    } catch (const StateFileError& error) {
        throw StateDbError(error.what());
    }
    if (!record) {
        if (moved_to_file()) {
            throw StateDbError(state_file().path() + ": holds no saved state, but " + path_ +
                               " says the node's state was saved there (the file was lost, emptied or "
                               "replaced): not restored; start the node with --cold-start");
        }
        return load_legacy_state();
    }
    std::string why;
    std::optional<StoredState> state = decode_state_record(record->payload, why);
    if (!state) throw StateDbError(state_file().path() + ": " + why + ": not restored; start the node with --cold-start");
    if (note != nullptr) *note = record->note;
    return state;
}

bool StateDb::moved_to_file() {
    if (!moved_) {
        sqlite3_stmt* statement = prepare("SELECT view_format FROM node_state WHERE id = 0");
        moved_ = sqlite3_step(statement) == SQLITE_ROW && sqlite3_column_int64(statement, 0) == kMovedToFile;
        sqlite3_finalize(statement);
    }
    return moved_;
}

std::optional<StoredState> StateDb::load_legacy_state() {
    sqlite3_stmt* statement =
        prepare("SELECT epoch, view, incarnation, view_format, crc, boot, revision, ground_seq, held_out, image, "
                "paused FROM node_state "
                "WHERE id = 0");
    std::optional<StoredState> result;
    std::string refused;
    if (sqlite3_step(statement) == SQLITE_ROW) {
        StoredState state;
        const std::int64_t epoch = sqlite3_column_int64(statement, 0);
        const std::int64_t incarnation = sqlite3_column_int64(statement, 2);
        state.epoch = static_cast<fsm::Epoch>(epoch);
        const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(statement, 1));
        const int size = sqlite3_column_bytes(statement, 1);
        const std::span<const std::uint8_t> bytes(blob, blob != nullptr ? static_cast<std::size_t>(size) : 0);
        state.incarnation = static_cast<std::uint32_t>(sqlite3_column_int64(statement, 2));
        const std::int64_t format = sqlite3_column_int64(statement, 3);
        std::optional<fsm::View> view;
        std::string why;
        if (format == kViewFormat) {
            view = decode_view(bytes, &why);
        } else if (format == 1) {
            view = decode_view_format1(bytes);
            why = "not the 21 bytes of format 1";
        } else {
            why = "a format this Keel does not read (it reads 1 and " + std::to_string(kViewFormat) +
                  "): written by a newer Keel?";
        }
        const bool checked = sqlite3_column_type(statement, 4) != SQLITE_NULL;
        const auto crc = static_cast<std::uint32_t>(sqlite3_column_int64(statement, 4));
        state.boot = static_cast<std::uint32_t>(sqlite3_column_int64(statement, 5));  // NULL reads 0
        state.revision = sqlite3_column_int64(statement, 6);                          // NULL reads 0
        state.ground_seq = sqlite3_column_int64(statement, 7);                        // NULL reads 0
        const auto* held_text = sqlite3_column_text(statement, 8);                    // NULL: none
        const std::string held_out = held_text != nullptr ? reinterpret_cast<const char*>(held_text) : "";
        const std::optional<fsm::NodeSet> held = decode_ids<fsm::NodeId, fsm::kMaxNodes>(held_out);
        const auto* image_text = sqlite3_column_text(statement, 9);                   // NULL: unknown
        state.image = image_text != nullptr ? reinterpret_cast<const char*>(image_text) : "";
        const auto* paused_text = sqlite3_column_text(statement, 10);                 // NULL: none
        const std::string paused_ids = paused_text != nullptr ? reinterpret_cast<const char*>(paused_text) : "";
        const std::optional<fsm::TaskSet> paused = decode_ids<fsm::TaskId, fsm::kMaxTasks>(paused_ids);
        if (view && checked &&
            crc != node_state_row_crc(static_cast<std::uint64_t>(epoch), bytes, static_cast<std::uint64_t>(incarnation), format,
                             state.boot, state.revision, state.ground_seq, held_out, state.image,
                             paused_ids)) {
            refused = "the persisted state fails its checksum (changed on the disk since it was saved): "
                      "not restored; start the node with --cold-start";
        } else if (view && (epoch < 0 || epoch > fsm::kMaxEpoch || incarnation < 0 ||
                            incarnation > fsm::kMaxIncarnation)) {
            refused = "the persisted epoch " + std::to_string(epoch) + " or incarnation " +
                      std::to_string(incarnation) + " is beyond its width (types.hpp): not restored";
        } else if (view && !held) {
            refused = "the persisted nodes held out by the ground ('" + held_out + "') are unreadable: not restored";
        } else if (view && !paused) {
            refused = "the persisted tasks paused by the ground ('" + paused_ids + "') are unreadable: not restored";
        } else if (view) {
            state.view = *view;
            state.held_out = *held;
            state.paused = *paused;
            result = state;
        } else {
            refused = "the persisted view (format " + std::to_string(format) + ") is unreadable: " + why;
        }
    }
    sqlite3_finalize(statement);
    if (!refused.empty()) throw StateDbError(path_ + ": " + refused);
    return result;
}

void StateDb::save_state(const StoredState& state) {
    try {
        state_file().save(encode_state_record(state));
    } catch (const StateFileError& error) {
        throw StateDbError(error.what());
    }
    if (!moved_to_file()) {
        // Once per database: the row an older Keel saved, if any, is replaced by the
        // marker (view_format 0) saying the state lives in the state file now, so that a
        // state file lost later is an error, never a first boot nor an older state.
        exec("INSERT OR REPLACE INTO node_state (id, epoch, view, incarnation, view_format, crc)"
             " VALUES (0, 0, x'', 0, 0, NULL)");
        moved_ = true;
    }
}

std::vector<NamedCheckpoint> StateDb::load_checkpoints(std::vector<std::string>* lost) {
    sqlite3_stmt* statement =
        prepare("SELECT task, version, state, lineage, crc FROM checkpoints ORDER BY task");
    std::vector<NamedCheckpoint> result;
    while (sqlite3_step(statement) == SQLITE_ROW) {
        NamedCheckpoint checkpoint;
        const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
        checkpoint.task = name != nullptr ? name : "";
        const std::int64_t count = sqlite3_column_int64(statement, 1);
        const std::int64_t lineage = sqlite3_column_int64(statement, 3);
        checkpoint.version.count = static_cast<std::uint64_t>(count);
        checkpoint.version.lineage = static_cast<std::uint64_t>(lineage);
        const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(statement, 2));
        const int size = sqlite3_column_bytes(statement, 2);
        if (blob != nullptr) checkpoint.state.assign(blob, blob + size);
        // A record that fails its checksum, or holds a version beyond the widths the codec
        // admits, is lost: reported, never restored.
        std::string why;
        if (sqlite3_column_type(statement, 4) != SQLITE_NULL &&
            static_cast<std::uint32_t>(sqlite3_column_int64(statement, 4)) !=
                checkpoint_crc(checkpoint.task, checkpoint.version, checkpoint.state)) {
            why = "fails its checksum (changed on the disk since it was stored)";
        } else if (count < 0 || lineage < 0 || fsm::lineage_epoch(checkpoint.version.lineage) > fsm::kMaxEpoch ||
                   fsm::lineage_seq(checkpoint.version.lineage) > fsm::kMaxSeq) {
            why = "holds a version beyond its width";
        }
        if (!why.empty()) {
            if (lost != nullptr) {
                lost->push_back("checkpoint of " + checkpoint.task + " (" + fsm::version_text(checkpoint.version) +
                                ") in " + path_ + " " + why + ": treated as lost, not restored");
            }
            continue;
        }
        result.push_back(std::move(checkpoint));
    }
    sqlite3_finalize(statement);
    return result;
}

void StateDb::store_checkpoint(const std::string& task, fsm::Version version,
                               const std::vector<std::uint8_t>& state, bool replaces) {
    sqlite3_stmt* statement = replaces ? replace_checkpoint_ : store_checkpoint_;
    sqlite3_reset(statement);
    sqlite3_bind_text(statement, 1, task.c_str(), static_cast<int>(task.size()), SQLITE_TRANSIENT);
    sqlite3_bind_int64(statement, 2, static_cast<sqlite3_int64>(version.count));
    sqlite3_bind_int64(statement, 4, static_cast<sqlite3_int64>(version.lineage));
    // An empty vector's data() may be null, and SQLite binds a null pointer as SQL NULL,
    // which the NOT NULL column refuses: an empty state is an empty blob.
    if (state.empty()) {
        sqlite3_bind_zeroblob(statement, 3, 0);
    } else {
        sqlite3_bind_blob(statement, 3, state.data(), static_cast<int>(state.size()), SQLITE_TRANSIENT);
    }
    sqlite3_bind_int64(statement, 5, checkpoint_crc(task, version, state));
    if (sqlite3_step(statement) != SQLITE_DONE) fail("store checkpoint");
}

}  // namespace keel::node
