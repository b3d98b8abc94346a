#include "core/node/state_db.hpp"

#include <sqlite3.h>

#include <string_view>

#include "core/node/wire.hpp"

namespace keel::node {

StateDb::StateDb(const std::string& path) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
        SQLITE_OK) {
        fail("cannot open");
    }
    sqlite3_busy_timeout(db_, 2000);
    exec("PRAGMA journal_mode=WAL");
    exec("PRAGMA synchronous=NORMAL");
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
    save_state_ = prepare(
        "INSERT INTO node_state (id, epoch, view, incarnation, view_format) VALUES (0, ?1, ?2, ?3, ?4)"
        " ON CONFLICT(id) DO UPDATE SET epoch = ?1, view = ?2, incarnation = ?3, view_format = ?4");
    store_checkpoint_ = prepare(
        "INSERT INTO checkpoints (task, version, state, lineage) VALUES (?1, ?2, ?3, ?4)"
        " ON CONFLICT(task) DO UPDATE SET version = ?2, state = ?3, lineage = ?4,"
        " stored_at = strftime('%Y-%m-%dT%H:%M:%f', 'now')"
        " WHERE (?4, ?2) >= (checkpoints.lineage, checkpoints.version)");
}

StateDb::~StateDb() {
    sqlite3_finalize(save_state_);
    sqlite3_finalize(store_checkpoint_);
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

std::optional<StoredState> StateDb::load_state() {
    sqlite3_stmt* statement =
        prepare("SELECT epoch, view, incarnation, view_format FROM node_state WHERE id = 0");
    std::optional<StoredState> result;
    std::string refused;
    if (sqlite3_step(statement) == SQLITE_ROW) {
        StoredState state;
        state.epoch = static_cast<fsm::Epoch>(sqlite3_column_int64(statement, 0));
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
        if (view) {
            state.view = *view;
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
    const std::vector<std::uint8_t> view = encode_view(state.view);
    sqlite3_reset(save_state_);
    sqlite3_bind_int64(save_state_, 1, state.epoch);
    sqlite3_bind_blob(save_state_, 2, view.data(), static_cast<int>(view.size()), SQLITE_TRANSIENT);
    sqlite3_bind_int64(save_state_, 3, state.incarnation);
    sqlite3_bind_int64(save_state_, 4, kViewFormat);
    if (sqlite3_step(save_state_) != SQLITE_DONE) fail("save node state");
}

std::vector<NamedCheckpoint> StateDb::load_checkpoints() {
    sqlite3_stmt* statement =
        prepare("SELECT task, version, state, lineage FROM checkpoints ORDER BY task");
    std::vector<NamedCheckpoint> result;
    while (sqlite3_step(statement) == SQLITE_ROW) {
        NamedCheckpoint checkpoint;
        checkpoint.task = reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
        checkpoint.version.count = static_cast<std::uint64_t>(sqlite3_column_int64(statement, 1));
        checkpoint.version.lineage = static_cast<std::uint64_t>(sqlite3_column_int64(statement, 3));
        const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(statement, 2));
        const int size = sqlite3_column_bytes(statement, 2);
        if (blob != nullptr) checkpoint.state.assign(blob, blob + size);
        result.push_back(std::move(checkpoint));
    }
    sqlite3_finalize(statement);
    return result;
}

void StateDb::store_checkpoint(const std::string& task, fsm::Version version,
                               const std::vector<std::uint8_t>& state) {
    sqlite3_reset(store_checkpoint_);
    sqlite3_bind_text(store_checkpoint_, 1, task.c_str(), static_cast<int>(task.size()),
                      SQLITE_TRANSIENT);
    sqlite3_bind_int64(store_checkpoint_, 2, static_cast<sqlite3_int64>(version.count));
    sqlite3_bind_int64(store_checkpoint_, 4, static_cast<sqlite3_int64>(version.lineage));
    // An empty vector's data() may be null, and SQLite binds a null pointer as SQL NULL,
    // which the NOT NULL column refuses: an empty state is an empty blob.
    if (state.empty()) {
        sqlite3_bind_zeroblob(store_checkpoint_, 3, 0);
    } else {
        sqlite3_bind_blob(store_checkpoint_, 3, state.data(), static_cast<int>(state.size()),
                          SQLITE_TRANSIENT);
    }
    if (sqlite3_step(store_checkpoint_) != SQLITE_DONE) fail("store checkpoint");
}

}  // namespace keel::node
