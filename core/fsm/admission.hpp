// Admission: what a node checks of a message before any state machine acts on it (fault
// model 3: a node that says something wrong harms no one but itself; docs/fault-model.md
// has the authority table these checks enforce).
//
// Three layers, each pure (no state, no IO) so that the runtime, keel-sim, the fuzzer and
// the tests run the very same checks:
//  1. The codec (codec.hpp) bounds every value by the wire's widths (types.hpp: an epoch
//     is 24 bits, a switch counter below 2^31, a version within a signed 64-bit integer).
//  2. out_of_mission bounds every id by the mission's counts: node, task, configuration
//     and phase ids, the failed set, joint views. Only a holder of the Topology can.
//     NodeProtocol::step calls it first; a message that breaks a bound is dropped and
//     counted as malformed by kind (NodeStats::malformed), so no id from the wire reaches
//     an index, an assert or an arithmetic of a state machine.
//  3. view_problem and edge_problem are the receiver's check of its Master: the view a
//     Command asks a node to adopt must be one the proven decision graph can place
//     (view_problem), and the next switch of the receiver's own view must follow an edge
//     of the graph from it (edge_problem). NodeProtocol::handle_command refuses a Command
//     that fails either, counts it (NodeStats::commands_refused) and holds its sender
//     failed for good: an honest Master never sends one, so the refusal is proof.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/fsm/messages.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

// Why `message` names an id the mission does not have (a node, task, configuration or
// phase id at or above the mission's count, a failed set with such a node, a joint view
// with one), or nothing when every id is the mission's.
std::optional<std::string> out_of_mission(const Message& message, const Topology& topology);

// Why no honest Master commands `view` (every id of it is the mission's: out_of_mission
// passed), or nothing. The rules, from docs/missions.md's "valid under F" as the walks of
// the graph guarantee them: outside safe mode the view's configuration is its base and
// names the view's master; in safe mode the base is a configuration of the graph and the
// master a processing node; the master is not failed; no task of the configuration is
// placed on a failed node; and the view's epoch belongs to its master (MasterElection's
// ownership).
std::optional<std::string> view_problem(const View& view, const Topology& topology);

// The receiver's check of the next switch of its own view (same epoch, same master, seq
// one above): `next` must be reachable from `from` by one step the Master can take (the
// decision graph's failure edges for the nodes it adds, in some order; a phase edge with
// the same failed set; the same configuration again; leaving safe mode for a
// configuration of its phase). Returns why not, or nothing. Assumes view_problem(next)
// passed.
std::optional<std::string> edge_problem(const View& from, const View& next, const Topology& topology);

// A digest of everything `view` says (FNV-1a, 64 bits, over its epoch, seq, configuration,
// base, master and failed set): a Prepared ack carries it, so that nodes agree on a switch
// only when they hold the same view under its id, not merely the same id (rule 4).
std::uint64_t view_digest(const View& view);

// The epochs the succession goes round in one lap (a take-over opens at most the next
// epoch its Master owns): NodeProtocol::adoptable_epoch bounds what a node adopts by it,
// and no node adopts one within a lap of kMaxEpoch, so an epoch never outgrows its width.
inline Epoch epoch_lap(const Topology& topology) { return static_cast<Epoch>(topology.priority().size()); }
inline Epoch max_adoptable_epoch(const Topology& topology) { return kMaxEpoch - epoch_lap(topology); }

}  // namespace keel::fsm
