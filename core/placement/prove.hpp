// The prover of a mission's online phases: the placer (place.hpp) run on every failure
// sequence, as the nodes run it (core/fsm/online.hpp), and its answers checked
// (check.hpp). keel-place IMAGE --prove prints it; keel-verify check runs it for a mission
// with a phase whose `placement` is not graph (docs/missions.md, "Placement modes and what
// is proved").
//
// For each phase placed `online` or `graph+online`, from every phase's initial configuration
// with no node failed, every sequence of at most `failures` distinct node failures, in every order.
// A state is (F, configuration): the failed set and the configuration the cluster runs.
// The failure of a node n alive in F leads, with F' = F + n, to:
//   - in a graph+online phase, from a configuration of the graph: the graph's on_failure
//     edge for n, unless it says SAFE, its master is not the elected one, its master or a
//     task's host is in F' (Topology::walk's rule), or the edge is missing where n
//     matters (master, observer or a task's host); the same configuration
//     where n matters not and has no edge; the placer otherwise;
//   - else (an online phase, or an online configuration) the placer,
//     place(model, phase, F', current).
// The elected master is the current one if alive, else the current configuration's first
// alive observer (spec/Election.tla); the placer's master must be that node.
//
// Within the mission's tolerance (F has at most tolerance.node_failures nodes, all of them
// in tolerance.nodes) a violation is: the placer answers safe mode, its master is not the
// elected one, or the checker (Shedding::allowed, so an essential task shed too) finds its
// configuration invalid under F'. Beyond the tolerance a checker finding is still a
// violation (the placer is wrong); safe mode and shed tasks are counted, by failed set.
//
// Readmissions: in every state reached (F, configuration), the readmission of each node of
// F (spec/Rejoin.tla; core/fsm/online.hpp's recovery_target): in a graph+online phase the
// graph's configuration of the smaller failed set where it is not SAFE and its master is
// the current one or the readmitted node's (a state this exploration or the verifier's
// proof covers); the placer otherwise, from the current configuration. Within the
// tolerance of the smaller set, the placer's safe mode, another master or a checker
// finding is a violation. The states after a readmission are not explored further.
//
// Phase changes: in every state reached, a change into every other phase, as the Master
// makes it (core/fsm/online.hpp's phase_target, the Master staying): from a configuration
// of the graph its on_phase entry, from an online one the target phase's graph
// configuration of F (unless the target is placed online), where that entry's master is
// the current one, no node of F is its master or a task's host and (into a phase not placed
// by its graph alone) the checker finds it valid under F; otherwise, into a phase not
// placed by its graph, the placer; otherwise the change is refused. The configuration
// reached is explored in its phase like any other (its failures up to K in all, its
// readmissions, its phase changes). Phases placed by their graph are explored too, their
// failures by the graph alone (SAFE where it has no answer), for the states from which
// they change into a phase proved here; what happens inside them is the verifier's Z3
// proof's, and a change between two of them too. Within the tolerance, a change the
// mission names (an on_phase entry into the target phase) that is refused, or one into a
// configuration of the graph that is not valid under F, is `phase-transition-invalid`; a
// placer's answer the checker refuses is a violation anywhere.
//
// States are memoised on (phase, F, configuration), each kept as a 128-bit fingerprint of
// those bytes (as TLC keeps 64-bit ones; two states share one with a chance of about
// n^2 / 2^129 among n): each is expanded once, so the work is the number of distinct
// states times the placer's cost, not the number of orders.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/placement/model.hpp"

namespace keel::placement {

// Failure sequences longer than this are not explored (the states grow as nodes^K).
inline constexpr int kMaxProveFailures = 8;
// Threads a proof runs on, at most.
inline constexpr int kMaxProveThreads = 64;
// Violations listed per phase (all are counted).
inline constexpr int kMaxListedViolations = 100;
// Failures and phase changes applied, every phase together, before the proof gives up,
// incomplete (never a pass): a two-phase 64-node mission at K = 3 applies about 4.4 million.
inline constexpr std::int64_t kMaxProveTransitions = 50'000'000;

// A move of a violation's path: the failure of `node`, or a phase change into `phase`.
struct ProveEvent {
    int node = kNone;
    int phase = kNone;
};

struct ProveViolation {
    // "safe-mode-within-tolerance", "master-mismatch", "phase-transition-invalid", or a
    // checker kind (check.hpp).
    std::string kind;
    std::vector<int> sequence;  // the failed nodes, in order
    std::string message;
    std::vector<ProveEvent> path;  // the failures and phase changes, in order, from
    int start = kNone;             // this phase's initial configuration
};

// Failed sets, each by the worst outcome over the orders of its failures: SAFE (or a
// violation), else some task shed, else every task running.
struct Outcomes {
    std::int64_t failed_sets = 0;
    std::int64_t running_every_task = 0;
    std::int64_t shedding = 0;
    std::int64_t safe = 0;
    std::vector<std::int64_t> shed_by_task;  // failed sets where task t is shed, per task id
};

struct PhaseProof {
    int phase = kNone;
    mission::PlacementMode mode = mission::PlacementMode::graph;
    int failures = 0;                 // the longest sequence explored
    std::int64_t states = 0;          // distinct (F, configuration) below K failures, expanded once
    std::int64_t transitions = 0;     // failures applied to them
    std::int64_t placements = 0;      // calls of the placer
    std::int64_t readmissions = 0;    // readmissions the placer answered (each state's, each node)
    std::int64_t phase_changes = 0;   // phase changes into (or, from a graph phase's, out of) it
    std::int64_t violation_count = 0;
    std::vector<ProveViolation> violations;  // the first kMaxListedViolations
    bool complete = true;  // false: max_transitions reached, not every sequence explored
    Outcomes within;  // non-empty failed sets within the tolerance
    Outcomes beyond;  // failed sets beyond it
};

// Whether `phase` has a proof here: its placement is not graph.
bool proved_online(const mission::Mission& mission, int phase);

// The proofs of every phase of `mission` that is proved_online, in phase order, with
// failure sequences of at most `failures` nodes (0 <= failures <= kMaxProveFailures) and
// every phase change between them. `model` is Model::build(mission). At most
// `max_transitions` failures and phase changes are applied in all (then no proof is
// `complete`).
//
// The readmissions (most of the placer's calls) are checked on `threads` threads in all,
// the exploring one included (0: one per core, at most kMaxProveThreads); the proofs are
// the same for any number, their listed violations included.
std::vector<PhaseProof> prove(const mission::Mission& mission, const Model& model, int failures,
                              std::int64_t max_transitions = kMaxProveTransitions, int threads = 0);

// The proof of `phase` (proved_online) of `prove`'s.
PhaseProof prove_phase(const mission::Mission& mission, const Model& model, int phase, int failures,
                       std::int64_t max_transitions = kMaxProveTransitions);

}  // namespace keel::placement
