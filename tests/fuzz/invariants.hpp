// The invariants the protocol fuzzer checks after every call into a node, whatever the
// node was sent (fault model 3: a node that says something wrong harms no one but itself,
// so none of these may break on any input). Each is named as keel-sim's checkers and the
// specs name theirs; a broken one aborts the process with its name and what broke it, and
// libFuzzer keeps the input that did (README.md says how to replay it).
//
// | invariant            | what holds                                                   |
// |----------------------|--------------------------------------------------------------|
// | CodecRoundTripInv    | decode(b) ok => encode(decode(b)) == b (one encoding per     |
// |                      | value), and every Send decodes to itself                     |
// | ViewValidInv         | the view a node holds, and the view a Master drives, is one  |
// |                      | the decision graph places (fsm::view_problem), or the        |
// |                      | initial view                                                 |
// | EpochWidthInv        | no epoch a node holds or drives exceeds kMaxEpoch (24 bits)  |
// | MonotoneInv          | a node's epoch, and the <<epoch, seq>> of its view, never    |
// |                      | go back (a restart resumes from them)                        |
// | OneMasterPerEpochInv | a Master's epoch is its own in the succession, and no two    |
// |                      | nodes are Master of one epoch over a run                     |
// | TasksPlacedInv       | a node's active tasks are placed on it by its view; it runs  |
// |                      | only active tasks, and nothing while it holds or is excluded |
// | ActionsInv           | actions name the mission's nodes and tasks; a Send goes to   |
// |                      | another node, in its sender's name; only the Storage node    |
// |                      | stores; Activate starts a task not running, Deactivate       |
// |                      | stops one that runs                                          |
// | TickProgressInv      | after tick(now), next_tick_ns() > now (a driver that ticks   |
// |                      | at next_tick_ns never spins)                                 |
// | EventBoundInv        | the honest traffic of one run_until stays within             |
// |                      | kMaxEventsPerRun (cluster.hpp)                               |
//
// Besides these, AddressSanitizer, UBSan and the state machines' own assertions abort on
// whatever they catch.
#pragma once

#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/fsm/codec.hpp"
#include "core/fsm/node_protocol.hpp"

namespace keel::fuzz {

// Reports a broken invariant on stderr and aborts (libFuzzer saves the input).
[[noreturn]] void broken(const char* invariant, const std::string& what);

class Invariants {
  public:
    explicit Invariants(const fsm::Topology& topology)
        : topology_(&topology), last_(static_cast<std::size_t>(topology.node_count())) {}

    // The call the next checks follow, for the report ("step", "tick", ...), and its time.
    void set_call(const char* call, fsm::TimeNs now);

    // `bytes` decoded to `decoded`: encoding it again gives `bytes` back.
    static void check_decoded(std::span<const std::uint8_t> bytes,
                              const fsm::DecodedMessage& decoded);
    // The actions one call into `node` returned, before they are carried out; `running`:
    // the tasks the node ran before the call.
    void check_actions(const fsm::NodeProtocol& node, const std::vector<fsm::Action>& actions,
                       fsm::TaskSet running) const;
    // The node's state after the call; `running`: what it runs once the actions are done.
    void check_node(const fsm::NodeProtocol& node, const fsm::TaskSet& running);
    // After tick(now): `next_tick_ns` is the node's next_tick_ns().
    void check_tick(const fsm::NodeProtocol& node, fsm::TimeNs next_tick_ns, fsm::TimeNs now) const;

  private:
    // "PN2 (Observer, epoch 4, view P3 4.1) after step at 1.234 s": where a finding happened.
    std::string where(const fsm::NodeProtocol& node) const;
    void check_view(const fsm::NodeProtocol& node, const fsm::View& view, const char* verb) const;

    const fsm::Topology* topology_;
    const char* call_ = "boot";
    fsm::TimeNs now_ = 0;
    // OneMasterPerEpochInv: each epoch's Master, as first seen.
    std::vector<std::pair<fsm::Epoch, fsm::NodeId>> masters_;
    // MonotoneInv: per node, its epoch and its view's switch id after its last call.
    struct Last {
        fsm::Epoch epoch = 0;
        fsm::Epoch view_epoch = 0;
        fsm::Seq view_seq = 0;
    };
    std::vector<Last> last_;
};

}  // namespace keel::fuzz
