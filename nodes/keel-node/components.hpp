// The components a keel-node can run, by the names missions use (`component:` of a task).
//
// Adding a component is one entry in components.cpp: a name and a factory. A mission that
// names a component registered nowhere makes keel-node exit 2, naming the task's
// file:line.
#pragma once

#include "core/tasking/registry.hpp"

namespace keel::node {

// Registers every component this build of keel-node carries. False on a duplicate name.
bool register_node_components(tasking::ComponentRegistry& registry);

}  // namespace keel::node
