#include "core/node/state_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace keel::node {

namespace {

constexpr std::array<std::uint8_t, 8> kMagic{'K', 'E', 'E', 'L', 'N', 'S', 'T', '1'};

template <typename Int>
void put(std::uint8_t* at, Int value) {
    for (std::size_t i = 0; i < sizeof(Int); ++i) at[i] = static_cast<std::uint8_t>(value >> (8 * i));
}

template <typename Int>
Int get(const std::uint8_t* at) {
    Int value = 0;
    for (std::size_t i = 0; i < sizeof(Int); ++i) value |= static_cast<Int>(at[i]) << (8 * i);
    return value;
}

// What a slot holds: nothing written (all zero), a valid record, or bytes that fail.
enum class Slot : std::uint8_t { blank, valid, invalid };

struct Read {
    Slot kind = Slot::blank;
    std::uint64_t sequence = 0;
    std::vector<std::uint8_t> payload;
};

Read read_slot(const std::array<std::uint8_t, StateFile::kSlotBytes>& slot) {
    Read read;
    if (std::all_of(slot.begin(), slot.end(), [](std::uint8_t b) { return b == 0; })) return read;
    read.kind = Slot::invalid;
    if (!std::equal(kMagic.begin(), kMagic.end(), slot.begin())) return read;
    const std::uint32_t length = get<std::uint32_t>(slot.data() + 16);
    if (length > StateFile::kMaxPayload) return read;
    const std::size_t end = StateFile::kHeaderBytes + length;
    if (get<std::uint32_t>(slot.data() + end) != StateFile::crc32({slot.data(), end})) return read;
    read.kind = Slot::valid;
    read.sequence = get<std::uint64_t>(slot.data() + 8);
    read.payload.assign(slot.begin() + StateFile::kHeaderBytes, slot.begin() + static_cast<std::ptrdiff_t>(end));
    return read;
}

// The directory's entry for the file, synced: 0, or the error.
int sync_directory_of(const std::string& path) {
    const std::size_t slash = path.find_last_of('/');
    const std::string directory = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
    const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return errno;
    const int result = ::fsync(fd) == 0 ? 0 : errno;
    ::close(fd);
    return result;
}

}  // namespace

std::uint32_t StateFile::crc32_extend(std::uint32_t crc, std::span<const std::uint8_t> bytes) {
    static const std::array<std::uint32_t, 256> table = [] {
        std::array<std::uint32_t, 256> t{};
        for (std::uint32_t i = 0; i < 256; ++i) {
            std::uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1u) != 0 ? 0xEDB8'8320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    for (const std::uint8_t byte : bytes) crc = table[(crc ^ byte) & 0xFFu] ^ (crc >> 8);
    return crc;
}

std::uint32_t StateFile::crc32(std::span<const std::uint8_t> bytes) {
    return crc32_extend(0xFFFF'FFFFu, bytes) ^ 0xFFFF'FFFFu;
}

StateFile::StateFile(std::string path) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) fail("cannot open", errno);
    try {
        open_slots();
    } catch (...) {
        ::close(fd_);
        fd_ = -1;
        throw;
    }
}

void StateFile::open_slots() {
    struct stat status {};
    if (::fstat(fd_, &status) != 0) fail("cannot stat", errno);
    if (status.st_size < static_cast<off_t>(2 * kSlotBytes)) {
        // New, or cut short (created by a boot that died before this): both slots
        // allocated in full, what is there kept, so that no save changes the file's size.
        const std::vector<std::uint8_t> zeros(2 * kSlotBytes - static_cast<std::size_t>(status.st_size), 0);
        if (::pwrite(fd_, zeros.data(), zeros.size(), status.st_size) != static_cast<ssize_t>(zeros.size())) {
            fail("cannot allocate", errno);
        }
        if (::fsync(fd_) != 0) fail("cannot sync", errno);
    }
    // The file's name, durable before any save stands for it (every open: a boot that
    // died between creating the file and syncing its directory left it unsynced).
    if (const int error = sync_directory_of(path_); error != 0) fail("cannot sync its directory", error);
    // The newest record's sequence, for the next save (load() reports the rest).
    try {
        if (const std::optional<Record> record = load()) {
            sequence_ = record->sequence;
            newest_slot_ = record->slot;
            empty_at_open_ = false;
        }
    } catch (const StateFileError&) {
        empty_at_open_ = false;  // the next load() says why; a save starts over after it
    }
}

StateFile::~StateFile() {
    if (fd_ >= 0) ::close(fd_);
}

void StateFile::fail(const std::string& what, int error) const {
    throw StateFileError(path_ + ": " + what + ": " + std::strerror(error));
}

std::optional<StateFile::Record> StateFile::load() {
    std::array<Read, 2> slots;
    for (std::size_t i = 0; i < 2; ++i) {
        std::array<std::uint8_t, kSlotBytes> bytes{};
        const ssize_t got = ::pread(fd_, bytes.data(), bytes.size(), static_cast<off_t>(i * kSlotBytes));
        if (got < 0) fail("cannot read", errno);  // a short read leaves zeros: a blank tail
        slots[i] = read_slot(bytes);
    }
    // Both slots are written from the second save on: a blank slot beside a record of a
    // later save was zeroed since (cut or wiped at rest), not never written.
    for (std::size_t i = 0; i < 2; ++i) {
        if (slots[i].kind == Slot::blank && slots[1 - i].kind == Slot::valid && slots[1 - i].sequence >= 2) {
            slots[i].kind = Slot::invalid;
        }
    }
    const bool valid0 = slots[0].kind == Slot::valid;
    const bool valid1 = slots[1].kind == Slot::valid;
    if (!valid0 && !valid1) {
        if (slots[0].kind == Slot::blank && slots[1].kind == Slot::blank) return std::nullopt;
        throw StateFileError(path_ + ": no record in it passes its checksum (changed on the disk since it "
                                     "was saved): not restored; start the node with --cold-start");
    }
    const std::size_t newest = valid0 && valid1 ? (slots[1].sequence > slots[0].sequence ? 1 : 0) : (valid1 ? 1 : 0);
    Record record;
    record.sequence = slots[newest].sequence;
    record.slot = newest;
    record.payload = std::move(slots[newest].payload);
    if (slots[1 - newest].kind == Slot::invalid) {
        record.note = "slot " + std::to_string(1 - newest) + " of " + path_ +
                      " fails its checksum (a save torn by a power loss, or changed on the disk since): restored "
                      "save " + std::to_string(record.sequence) + " from slot " + std::to_string(newest) +
                      ". If the other slot held the newer save, that save is lost: the node's state goes back one "
                      "save (its restart is seen by its boot identifier; the ground's last command, hold or pause, "
                      "and the revision flown, may go back with it)";
    }
    return record;
}

void StateFile::save(std::span<const std::uint8_t> payload) {
    if (payload.size() > kMaxPayload) {
        throw StateFileError(path_ + ": a record of " + std::to_string(payload.size()) + " bytes exceeds the " +
                             std::to_string(kMaxPayload) + " a slot holds");
    }
    const std::uint64_t sequence = sequence_ + 1;
    // Never over the newest record: it stands until this one is on the disk.
    const std::size_t slot = 1 - newest_slot_;
    std::array<std::uint8_t, kSlotBytes> bytes{};
    std::copy(kMagic.begin(), kMagic.end(), bytes.begin());
    put<std::uint64_t>(bytes.data() + 8, sequence);
    put<std::uint32_t>(bytes.data() + 16, static_cast<std::uint32_t>(payload.size()));
    std::copy(payload.begin(), payload.end(), bytes.begin() + kHeaderBytes);
    const std::size_t end = kHeaderBytes + payload.size();
    put<std::uint32_t>(bytes.data() + end, crc32({bytes.data(), end}));
    const ssize_t wrote = ::pwrite(fd_, bytes.data(), bytes.size(), static_cast<off_t>(slot * kSlotBytes));
    if (wrote < 0) fail("cannot write", errno);
    if (wrote != static_cast<ssize_t>(bytes.size())) fail("cannot write", ENOSPC);
    if (::fdatasync(fd_) != 0) fail("cannot sync", errno);
    sequence_ = sequence;
    newest_slot_ = slot;
}

}  // namespace keel::node
