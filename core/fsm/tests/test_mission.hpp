// Missions built in code for the state-machine unit tests, so they do not depend on the
// YAML loader: the paper's three-node prototype (config/prototype3.yaml).
#pragma once

#include "core/fsm/topology.hpp"
#include "core/mission/mission.hpp"

namespace keel::fsm::testing {

// PN1 master, PN2/PN3 observers, ST1 storage; taskA (plain), taskB (essential,
// checkpointed); phases nominal (P1..P4) and science (S1..S4), as in the YAML file.
keel::mission::Mission prototype3();
Topology prototype3_topology();
// The topology of `mission`; throws when it does not build.
Topology topology_of(const keel::mission::Mission& mission);

}  // namespace keel::fsm::testing
