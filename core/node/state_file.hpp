// StateFile: one small record kept durable in place, for a node's own state (StateDb's
// node state; docs/fault-model.md, "Durable state").
//
// The node saves its state before every message that depends on it leaves (driver.hpp,
// rule 1), so the save is on the critical path of every switch. A SQLite commit with
// synchronous=FULL appends to its log and syncs it; this file is written in place: two
// slots of kSlotBytes, each save into the one not holding the newest record, then one
// fdatasync. The file's size never changes after it is created (allocated and synced
// with its directory once), so the sync has no metadata to write.
//
// A slot: magic "KEELNST1" (8 bytes), sequence (8), payload length (4), payload, CRC-32 of
// all of it (4); integers little-endian, the rest of the slot zero. load() takes the valid
// slot with the highest sequence. A save torn by a power loss leaves the other slot, the
// previous save, which nothing sent depended on yet (the save had not returned). A slot
// changed at rest after its save returned looks the same to the reader: the previous save
// is restored then too, and load() says so (`note`). That save is lost: the node's state
// goes back one save. Its restart is still seen (the boot identifier, whatever the saved
// incarnation); what else goes back with it (the ground's last seq, hold or pause, the
// revision flown) is stated in docs/fault-model.md, "Integrity at rest". A file with
// slots written but none valid, or a slot zeroed beside a record of a later save, is an
// error, never a first boot. Not thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace keel::node {

class StateFileError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class StateFile {
public:
    static constexpr std::size_t kSlotBytes = 4096;
    static constexpr std::size_t kHeaderBytes = 8 + 8 + 4;
    static constexpr std::size_t kMaxPayload = kSlotBytes - kHeaderBytes - 4;

    // Opens the file, creating it (two empty slots, synced with its directory) when it
    // does not exist. A StateFileError names the path and the system's reason.
    explicit StateFile(std::string path);
    ~StateFile();
    StateFile(const StateFile&) = delete;
    StateFile& operator=(const StateFile&) = delete;

    const std::string& path() const { return path_; }
    // Whether the file held no record when it was opened (created now, or never saved).
    bool empty_at_open() const { return empty_at_open_; }

    struct Record {
        std::vector<std::uint8_t> payload;
        std::uint64_t sequence = 0;
        std::size_t slot = 0;  // 0 or 1
        // Empty, or why a slot was passed over (the newest save torn or changed at rest).
        std::string note;
    };
    // The newest valid record; nothing when none was ever saved; a StateFileError when the
    // file holds slots written but none valid.
    std::optional<Record> load();
    // Writes `payload` (at most kMaxPayload bytes) into the older slot and syncs it; the
    // record is durable when this returns. A StateFileError when it could not be.
    void save(std::span<const std::uint8_t> payload);

    // The CRC-32 (IEEE, as zlib's) of `bytes`; crc32_extend, its register (no final
    // inversion) carried on over more bytes, from 0xFFFFFFFF.
    static std::uint32_t crc32(std::span<const std::uint8_t> bytes);
    static std::uint32_t crc32_extend(std::uint32_t crc, std::span<const std::uint8_t> bytes);

private:
    void open_slots();
    [[noreturn]] void fail(const std::string& what, int error) const;

    std::string path_;
    int fd_ = -1;
    std::uint64_t sequence_ = 0;   // of the newest valid record (0: none)
    std::size_t newest_slot_ = 1;  // where it is (a first save goes to slot 0)
    bool empty_at_open_ = true;
};

}  // namespace keel::node
