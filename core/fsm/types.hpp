// Small value types every Keel state machine shares: node, task and configuration ids,
// epochs, virtual time, and compact id sets.
//
// Ids are indexes into the mission in file order (Mission::address_of for nodes), so a
// message can carry them in two bytes and every node agrees on them without a lookup table
// on the wire.
//
// The capacity, stated once: at most kMaxNodes nodes and kMaxTasks tasks per mission.
// Everything else derives from these two numbers — the sets below, the codec's limits
// (codec.hpp), the mission image loader's (core/mission/image.hpp) — and the verifier
// mirrors them in verify/keel_verify/limits.py (tests/verify/test_compile.py keeps the two
// equal). Topology::build rejects larger missions with a message; keel-verify compile
// refuses them before it proves anything.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

namespace keel::fsm {

// Virtual or real time in nanoseconds. The state machines never read a clock: the caller
// passes `now` with every event, and time never goes backwards between calls.
using TimeNs = std::int64_t;
inline constexpr TimeNs kNanosecondsPerMillisecond = 1'000'000;

using NodeId = std::uint16_t;     // Mission::address_of(name)
using TaskId = std::uint16_t;     // index in Mission::tasks
using ConfigId = std::uint16_t;   // index in Topology::configs (every phase, file order)
using PhaseId = std::uint8_t;     // index in Mission::phases
using Epoch = std::uint32_t;      // MasterElection's epoch; 0 means "none yet"
using Seq = std::uint32_t;        // ConfigSwitch's switch counter within an epoch

// The widths of the quantities that travel, stated once (fault model 3: every value from
// the wire or the disk is bounded where it is decoded, against these and the mission's
// counts). An epoch is 24 bits everywhere: the envelope carries it in 3 bytes
// (core/net/envelope.hpp, max_epoch, which core/node/runtime.cpp asserts equal), the codec
// refuses a larger one, and no node ever adopts or opens one above it. A switch counter
// stays below 2^31 so that a successor never wraps. A version's step count and lineage fit
// a signed 64-bit integer, the width the Storage node's SQLite store compares them in.
// Incarnations stay below 2^31 for the same reason as switch counters.
inline constexpr Epoch kMaxEpoch = 0xFF'FFFF;
inline constexpr Seq kMaxSeq = 0x7FFF'FFFF;
inline constexpr std::uint64_t kMaxVersionCount = 0x7FFF'FFFF'FFFF'FFFF;
// The largest step count a node takes from another node: a restore reply, a holder's
// hand-off, the stored state a held task resumes from (spec/ValueFault.tla, Adoptable). No
// correct run counts that far (2^62 steps at a million a second take 146,000 years), and a
// host that took a count no larger steps on for as long again before its versions leave
// the codec's width (kMaxVersionCount), past which its writes no longer decode. The
// Storage node stores any count the codec carries; a state above this one is treated as
// lost by the node it is offered to.
inline constexpr std::uint64_t kMaxAdoptedCount = std::uint64_t{1} << 62;
inline constexpr std::uint32_t kMaxIncarnation = 0x7FFF'FFFF;

// A task's state version: the lineage the state belongs to, then the steps executed in it,
// compared in that order (spec/Handoff.tla, "Lineages"). A start without the Storage node
// (from a hand-off, or an unrecoverable one) opens a new lineage named by the view it
// starts in, so the state the cluster went on with is newer than any state of a lineage it
// abandoned, even one with more steps still held by an excluded Storage node. A start (or a
// resumption) from the Storage node keeps the stored state's lineage, unless it is of an
// epoch above the view's: then it runs on in a lineage of the view (spec/ValueFault.tla,
// RunLineage); 0 is the initial lineage.
// (Constructors, not an aggregate: a bare integer never becomes a Version by accident.)
struct Version {
    constexpr Version() = default;
    constexpr Version(std::uint64_t lineage_id, std::uint64_t steps) : lineage(lineage_id), count(steps) {}
    std::uint64_t lineage = 0;  // lineage_of(epoch, seq) of the view that opened it
    std::uint64_t count = 0;    // steps executed in the lineage
    friend constexpr auto operator<=>(const Version&, const Version&) = default;
};
// A view's switch id <<epoch, seq>> as a lineage: ordered as the switches are.
constexpr std::uint64_t lineage_of(Epoch epoch, Seq seq) {
    return (std::uint64_t{epoch} << 32) | seq;
}
constexpr Epoch lineage_epoch(std::uint64_t lineage) { return static_cast<Epoch>(lineage >> 32); }
constexpr Seq lineage_seq(std::uint64_t lineage) { return static_cast<Seq>(lineage & 0xFFFFFFFFu); }

// The capacity (see the header comment). Multiples of 64: a set is a whole number of words.
inline constexpr int kMaxNodes = 256;
inline constexpr int kMaxTasks = 1024;
// "No node" and "no task": outside every valid id.
inline constexpr NodeId kNoNode = 0xFFFF;
inline constexpr TaskId kNoTask = 0xFFFF;
static_assert(kMaxNodes <= kNoNode && kMaxTasks <= kNoTask,
              "every valid id fits in its type, below its sentinel");
// The decision graph's safe-mode target, as a configuration id.
inline constexpr ConfigId kSafeConfig = 0xFFFF;
inline constexpr ConfigId kNoConfig = 0xFFFE;
// An online configuration (core/fsm/online.hpp): computed by the Master's placer beyond the
// decision graph, carried whole by the view (View::online).
inline constexpr ConfigId kOnlineConfig = 0xFFFD;

// A set of ids below Capacity, as a fixed array of 64-bit words (word i holds ids 64 i to
// 64 i + 63): no allocation, copied and compared as a value. It also keeps a bound on the
// words in use (every word from `used_` on is zero), so that an operation touches only the
// words a mission's ids reach: a 4-node mission's sets cost one word, as they did when a
// set was one word, however large the capacity. The codec puts only the words up to the
// last non-empty one on the wire (used_words).
template <typename Id, int Capacity>
class IdSet {
    static_assert(Capacity > 0 && Capacity % 64 == 0, "a set is a whole number of words");
    static_assert(Capacity - 1 <= std::numeric_limits<Id>::max(), "every member fits in Id");
    static_assert(Capacity / 64 <= std::numeric_limits<std::uint8_t>::max(), "used_ counts words");

public:
    static constexpr int kCapacity = Capacity;
    static constexpr int kWords = Capacity / 64;

    constexpr IdSet() = default;

    constexpr bool contains(Id id) const {
        return id < Capacity && ((words_[id / 64] >> (id % 64)) & 1u) != 0;
    }
    constexpr void insert(Id id) {
        assert(id < Capacity);
        words_[id / 64] |= std::uint64_t{1} << (id % 64);
        if (id / 64 >= used_) used_ = static_cast<std::uint8_t>(id / 64 + 1);
    }
    constexpr void erase(Id id) {
        if (id < Capacity) words_[id / 64] &= ~(std::uint64_t{1} << (id % 64));
    }
    constexpr bool empty() const {
        for (int i = 0; i < used_; ++i) {
            if (words_[i] != 0) return false;
        }
        return true;
    }
    constexpr int size() const {
        int count = 0;
        for (int i = 0; i < used_; ++i) count += std::popcount(words_[i]);
        return count;
    }
    constexpr bool includes(const IdSet& other) const {
        for (int i = 0; i < other.used_; ++i) {
            if ((other.words_[i] & ~words_[i]) != 0) return false;
        }
        return true;
    }
    // Whether the two sets share a member: `!(a & b).empty()` without the set in between.
    constexpr bool intersects(const IdSet& other) const {
        const int used = std::min(used_, other.used_);
        for (int i = 0; i < used; ++i) {
            if ((words_[i] & other.words_[i]) != 0) return true;
        }
        return false;
    }
    constexpr IdSet& operator|=(const IdSet& other) {
        for (int i = 0; i < other.used_; ++i) words_[i] |= other.words_[i];
        used_ = std::max(used_, other.used_);
        return *this;
    }
    constexpr IdSet operator|(const IdSet& other) const {
        IdSet set = *this;
        set |= other;
        return set;
    }
    constexpr IdSet operator&(const IdSet& other) const {
        IdSet set;
        set.used_ = std::min(used_, other.used_);
        for (int i = 0; i < set.used_; ++i) set.words_[i] = words_[i] & other.words_[i];
        return set;
    }
    constexpr IdSet minus(const IdSet& other) const {
        IdSet set = *this;
        const int used = std::min(used_, other.used_);
        for (int i = 0; i < used; ++i) set.words_[i] &= ~other.words_[i];
        return set;
    }
    // Equal members (the bound on the words in use is no part of the value).
    friend constexpr bool operator==(const IdSet& a, const IdSet& b) {
        const int used = std::max(a.used_, b.used_);
        for (int i = 0; i < used; ++i) {
            if (a.words_[i] != b.words_[i]) return false;
        }
        return true;
    }

    // Calls f(id) for every member in increasing order.
    template <typename F>
    void for_each(F&& f) const {
        for (int i = 0; i < used_; ++i) {
            std::uint64_t rest = words_[i];
            while (rest != 0) {
                const int bit = std::countr_zero(rest);
                rest &= rest - 1;
                f(static_cast<Id>(i * 64 + bit));
            }
        }
    }

    // The words, for the codec: word(i) holds ids 64 i to 64 i + 63; used_words() counts
    // the words up to the last non-empty one (0 for the empty set).
    constexpr std::uint64_t word(int index) const { return words_[index]; }
    constexpr void set_word(int index, std::uint64_t value) {
        words_[index] = value;
        if (value != 0 && index >= used_) used_ = static_cast<std::uint8_t>(index + 1);
    }
    constexpr int used_words() const {
        int used = used_;
        while (used > 0 && words_[used - 1] == 0) --used;
        return used;
    }

private:
    std::array<std::uint64_t, kWords> words_{};
    std::uint8_t used_ = 0;  // words_[i] == 0 for every i >= used_
};

using NodeSet = IdSet<NodeId, kMaxNodes>;
using TaskSet = IdSet<TaskId, kMaxTasks>;

// The roles of MasterElection.
enum class Role : std::uint8_t { Master, Observer, Worker };
const char* to_string(Role role);

// An online configuration (docs/missions.md, "Placement modes"): the phase it belongs to,
// its master and observers (priority order) and, per task of the mission, the hosting node
// (kNoNode: not placed, or shed). Immutable once made; views share it.
struct OnlineConfig {
    PhaseId phase = 0;
    NodeId master = kNoNode;
    std::vector<NodeId> observers;
    std::vector<NodeId> host;
    friend bool operator==(const OnlineConfig&, const OnlineConfig&) = default;
};

// An online configuration held by a view, compared by contents (two views that carry equal
// configurations are equal views, wherever each was decoded).
class OnlinePtr {
public:
    OnlinePtr() = default;
    OnlinePtr(std::nullptr_t) {}  // NOLINT(google-explicit-constructor): as shared_ptr's
    OnlinePtr(std::shared_ptr<const OnlineConfig> config) : config_(std::move(config)) {}  // NOLINT
    const OnlineConfig* get() const { return config_.get(); }
    const OnlineConfig& operator*() const { return *config_; }
    const OnlineConfig* operator->() const { return config_.get(); }
    explicit operator bool() const { return config_ != nullptr; }
    friend bool operator==(const OnlinePtr& a, const OnlinePtr& b) {
        if (a.config_ == nullptr || b.config_ == nullptr) return a.config_ == b.config_;
        return a.config_ == b.config_ || *a.config_ == *b.config_;
    }
    friend bool operator==(const OnlinePtr& a, std::nullptr_t) { return a.config_ == nullptr; }

private:
    std::shared_ptr<const OnlineConfig> config_;
};

// A configuration as the cluster agrees on it: what a reconfiguration command carries.
// `config` is the decision-graph configuration, kOnlineConfig for an online one (`online`
// holds it), or kSafeConfig for safe mode; `base` is the configuration safe mode was
// entered from (equal to `config` otherwise), which fixes the phase and the observers that
// keep monitoring in safe mode (kOnlineConfig: `online` is that base). `master` is the
// node that drives the view; `failed` every node the cluster has excluded so far (never
// shrinks). `online` is set exactly when `base` is kOnlineConfig (admission.hpp refuses
// any other view).
struct View {
    Epoch epoch = 0;
    Seq seq = 0;
    ConfigId config = kNoConfig;
    ConfigId base = kNoConfig;
    NodeId master = kNoNode;
    NodeSet failed;
    OnlinePtr online{};  // an initializer: views written without it stay complete aggregates

    bool is_safe() const { return config == kSafeConfig; }
    bool is_online() const { return base == kOnlineConfig; }
    friend bool operator==(const View&, const View&) = default;
};

// The total order of switches: <<epoch, seq>>, compared lexicographically.
inline bool newer_than(Epoch epoch_a, Seq seq_a, Epoch epoch_b, Seq seq_b) {
    return epoch_a > epoch_b || (epoch_a == epoch_b && seq_a > seq_b);
}

}  // namespace keel::fsm
