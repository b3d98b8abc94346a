// Small value types every Keel state machine shares: node, task and configuration ids,
// epochs, virtual time, and compact id sets.
//
// Ids are indexes into the mission in file order (Mission::address_of for nodes), so a
// message can carry them in a byte or two and every node agrees on them without a lookup
// table on the wire. Limits: at most 64 nodes and 64 tasks per mission (IdSet is one
// 64-bit word); Topology::build rejects larger missions with a message.
#pragma once

#include <bit>
#include <cassert>
#include <compare>
#include <cstdint>

namespace keel::fsm {

// Virtual or real time in nanoseconds. The state machines never read a clock: the caller
// passes `now` with every event, and time never goes backwards between calls.
using TimeNs = std::int64_t;
inline constexpr TimeNs kNanosecondsPerMillisecond = 1'000'000;

using NodeId = std::uint8_t;      // Mission::address_of(name)
using TaskId = std::uint8_t;      // index in Mission::tasks
using ConfigId = std::uint16_t;   // index in Topology::configs (every phase, file order)
using PhaseId = std::uint8_t;     // index in Mission::phases
using Epoch = std::uint32_t;      // MasterElection's epoch; 0 means "none yet"
using Seq = std::uint32_t;        // ConfigSwitch's switch counter within an epoch

// A task's state version: the lineage the state belongs to, then the steps executed in it,
// compared in that order (spec/Handoff.tla, "Lineages"). A start without the Storage node
// (from a hand-off, or an unrecoverable one) opens a new lineage named by the view it
// starts in, so the state the cluster went on with is newer than any state of a lineage it
// abandoned, even one with more steps still held by an excluded Storage node. A start from
// the Storage node keeps the stored state's lineage; 0 is the initial lineage.
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

inline constexpr NodeId kNoNode = 0xFF;
// The decision graph's safe-mode target, as a configuration id.
inline constexpr ConfigId kSafeConfig = 0xFFFF;
inline constexpr ConfigId kNoConfig = 0xFFFE;
inline constexpr int kMaxNodes = 64;
inline constexpr int kMaxTasks = 64;

// A set of node or task ids below 64, as one word: cheap to copy, compare and encode.
template <typename Id>
class IdSet {
public:
    constexpr IdSet() = default;
    static constexpr IdSet from_bits(std::uint64_t bits) {
        IdSet set;
        set.bits_ = bits;
        return set;
    }

    constexpr bool contains(Id id) const { return id < 64 && ((bits_ >> id) & 1u) != 0; }
    constexpr void insert(Id id) {
        assert(id < 64);
        bits_ |= std::uint64_t{1} << id;
    }
    constexpr void erase(Id id) {
        if (id < 64) bits_ &= ~(std::uint64_t{1} << id);
    }
    constexpr bool empty() const { return bits_ == 0; }
    constexpr int size() const { return std::popcount(bits_); }
    constexpr std::uint64_t bits() const { return bits_; }
    constexpr bool includes(IdSet other) const { return (other.bits_ & ~bits_) == 0; }
    constexpr IdSet operator|(IdSet other) const { return from_bits(bits_ | other.bits_); }
    constexpr IdSet operator&(IdSet other) const { return from_bits(bits_ & other.bits_); }
    constexpr IdSet minus(IdSet other) const { return from_bits(bits_ & ~other.bits_); }
    friend constexpr bool operator==(IdSet, IdSet) = default;

    // Calls f(id) for every member in increasing order.
    template <typename F>
    void for_each(F&& f) const {
        std::uint64_t rest = bits_;
        while (rest != 0) {
            const int id = std::countr_zero(rest);
            rest &= rest - 1;
            f(static_cast<Id>(id));
        }
    }

private:
    std::uint64_t bits_ = 0;
};

using NodeSet = IdSet<NodeId>;
using TaskSet = IdSet<TaskId>;

// The roles of MasterElection.
enum class Role : std::uint8_t { Master, Observer, Worker };
const char* to_string(Role role);

// A configuration as the cluster agrees on it: what a reconfiguration command carries.
// `config` is the decision-graph configuration, or kSafeConfig for safe mode; `base` is the
// configuration safe mode was entered from (equal to `config` otherwise), which fixes the
// phase and the observers that keep monitoring in safe mode. `master` is the node that
// drives the view; `failed` every node the cluster has excluded so far (never shrinks).
struct View {
    Epoch epoch = 0;
    Seq seq = 0;
    ConfigId config = kNoConfig;
    ConfigId base = kNoConfig;
    NodeId master = kNoNode;
    NodeSet failed;

    bool is_safe() const { return config == kSafeConfig; }
    friend bool operator==(const View&, const View&) = default;
};

// The total order of switches: <<epoch, seq>>, compared lexicographically.
inline bool newer_than(Epoch epoch_a, Seq seq_a, Epoch epoch_b, Seq seq_b) {
    return epoch_a > epoch_b || (epoch_a == epoch_b && seq_a > seq_b);
}

}  // namespace keel::fsm
