// Keel's built-in components: what keel-node runs, by the names missions use (a task's
// `component:`).
//
//   producer, consumer, passthrough        core/tasking/builtin.hpp (config/prototype3.yaml)
//   sensor, acca, sink, aocs, downlink     nodes/components (config/earth_observation.yaml),
//                                          when Keel is built with them (KEEL_WITH_EO)
//
// Adding a component to keel-node is one entry in src/components.cpp: a name and a factory.
// A node binary of your own registers its components next to these (or instead of them)
// through keel_add_node() and keel/node/main.hpp, without touching Keel (docs/components.md).
// A mission that names a component registered nowhere makes the node exit 2, naming the
// task's file:line.
#pragma once

#include "core/tasking/registry.hpp"

namespace keel::node {

// Registers every built-in component of this build of Keel. False on a duplicate name.
bool register_node_components(tasking::ComponentRegistry& registry);

// True when this build of Keel carries the earth-observation components.
bool node_components_include_eo();

}  // namespace keel::node
