// The prover of a mission's online phases: the placer (place.hpp) run on every failure
// sequence, as the nodes run it (core/fsm/online.hpp), and its answers checked
// (check.hpp). keel-place IMAGE --prove prints it; keel-verify check runs it for a mission
// with a phase whose `placement` is not graph (docs/missions.md, "Placement modes and what
// is proved").
//
// For each phase placed `online` or `graph+online`, from its initial configuration with no
// node failed, every sequence of at most `failures` distinct node failures, in every order.
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
// States are memoised on (F, configuration): each is expanded once, so the work is the
// number of distinct states times the placer's cost, not the number of orders.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/placement/model.hpp"

namespace keel::placement {

// Failure sequences longer than this are not explored (the states grow as nodes^K).
inline constexpr int kMaxProveFailures = 8;
// Violations listed per phase (all are counted).
inline constexpr int kMaxListedViolations = 100;
// Failures applied per phase before the proof gives up, incomplete (never a pass): a
// 64-node mission at K = 3 applies about 265,000.
inline constexpr std::int64_t kMaxProveTransitions = 50'000'000;

struct ProveViolation {
    // "safe-mode-within-tolerance", "master-mismatch", or a checker kind (check.hpp).
    std::string kind;
    std::vector<int> sequence;  // the failed nodes, in order
    std::string message;
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
    std::int64_t violation_count = 0;
    std::vector<ProveViolation> violations;  // the first kMaxListedViolations
    bool complete = true;  // false: max_transitions reached, not every sequence explored
    Outcomes within;  // non-empty failed sets within the tolerance
    Outcomes beyond;  // failed sets beyond it
};

// Whether prove_phase explores `phase`: its placement is not graph.
bool proved_online(const mission::Mission& mission, int phase);

// The proof of `phase` (proved_online) of `mission`, with failure sequences of at most
// `failures` nodes (0 <= failures <= kMaxProveFailures). `model` is Model::build(mission).
// At most `max_transitions` failures are applied (then `complete` is false).
PhaseProof prove_phase(const mission::Mission& mission, const Model& model, int phase, int failures,
                       std::int64_t max_transitions = kMaxProveTransitions);

}  // namespace keel::placement
