// The keel-node program as a library: a node binary is a set of components plus this entry
// point. keel-node itself is Keel's built-in components plus node_main(); a binary of your
// own is your components (with or without Keel's) plus node_main(), with keel-node's whole
// command line: its flags, stdin control lines, stdout status lines, NDJSON trace and exit
// codes (nodes/cluster/README.md has that contract; docs/components.md the walk-through).
//
// keel_add_node() (cmake/KeelNode.cmake, shipped in Keel's CMake package) writes the main
// function for a CMake target; what it writes amounts to:
//
//   #include "keel/node/components.hpp"
//   #include "keel/node/main.hpp"
//   namespace thermal { bool register_components(keel::tasking::ComponentRegistry&); }
//
//   int main(int argc, char** argv) {
//       const keel::node::ComponentSet sets[] = {
//           {"Keel's built-in components", keel::node::register_node_components},
//           {"thermal::register_components", thermal::register_components},
//       };
//       return keel::node::node_main(argc, argv, sets, {"thermal-node", "1.0.0"});
//   }
//
// A registration function adds factories and returns false when a name it adds is taken
// (ComponentRegistry::add's result); it runs once, before the flags are read.
#pragma once

#include <functional>
#include <span>
#include <string>

#include "core/tasking/registry.hpp"

namespace keel::node {

// How a node binary names itself.
struct NodeProgram {
    std::string name = "keel-node";  // in the usage text, in messages and for --version
    std::string version;             // printed by --version; empty: Keel's version
};

// A family of components and who registers it (the name is for messages only).
struct ComponentSet {
    std::string name;
    std::function<bool(tasking::ComponentRegistry&)> add;
};

// The version of Keel this library was built from (the repository's VERSION).
const char* keel_version();

// Registers every set into `registry`, in order. Returns an empty string when every name
// was free, else a sentence naming the component registered twice and the sets that did.
std::string register_component_sets(tasking::ComponentRegistry& registry,
                                    std::span<const ComponentSet> sets);

// keel-node's command line over the components of `registry`. Returns the exit code when
// the node does not run (--help, --version, --list-components, bad input: 2, cannot
// start: 3, credentials refused: 4). When the node ran, it ends the process with the
// node's exit code (std::_Exit after flushing the logs: the stdin reader thread of
// --control-stdin cannot be joined), so nothing after the call runs.
int node_main(int argc, char** argv, const tasking::ComponentRegistry& registry,
              const NodeProgram& program = {});

// The same, registering `sets` first; a component name registered twice exits 3, naming it.
int node_main(int argc, char** argv, std::span<const ComponentSet> sets,
              const NodeProgram& program = {});

}  // namespace keel::node
