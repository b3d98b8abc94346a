// The checker: is a configuration valid under a failed set, for a phase? "Valid under the
// set F of failed nodes" (docs/missions.md), rule by rule, with the verifier's violation kinds (verify/keel_verify/check/
// model.py, `invalid_under`), which tests/placement cross-tests it against:
//
//   task-missing         a task of the phase is not placed (unless shed, below), or a task
//                        of another phase is
//   task-on-failed-node  a task is placed on a failed node
//   capability           a task is placed on a node without a capability it requires
//   capacity             a node's summed load is beyond its cpu or mem_mb capacity
//   master-invalid       the master is failed or not a processing node
//   observer-invalid     an observer is failed, not a processing node, the master or listed
//                        twice; or there is none while two or more processing nodes are alive
//   storage-unavailable  a checkpointed task is placed and no storage node is alive
//   malformed            an id beyond the mission's (a configuration from the wire)
//
// Small on purpose and separate from the placer (place.hpp), so that every node can run it
// on every configuration it is told to switch to before it acts, and a placer that errs is
// caught by it (core/fsm/online.hpp, online_problem). With Shedding::allowed (an online configuration) a task of the phase may be left
// unplaced, never an essential one.
#pragma once

#include <string>
#include <vector>

#include "core/placement/model.hpp"

namespace keel::placement {

struct Finding {
    std::string kind;
    int task = kNone;
    int node = kNone;
    std::string message;
};

enum class Shedding { forbidden, allowed };

// Every rule `config` breaks in `phase` under `failed`; empty when it is valid. `failed`
// has one entry per node (a shorter vector is read as those nodes alive).
std::vector<Finding> check(const Model& model, int phase, const FailedSet& failed,
                           const Configuration& config, Shedding shedding = Shedding::forbidden);

inline bool valid(const Model& model, int phase, const FailedSet& failed,
                  const Configuration& config, Shedding shedding = Shedding::forbidden) {
    return check(model, phase, failed, config, shedding).empty();
}

}  // namespace keel::placement
