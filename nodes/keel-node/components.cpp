#include "nodes/keel-node/components.hpp"

#include "core/tasking/builtin.hpp"

namespace keel::node {

bool register_node_components(tasking::ComponentRegistry& registry) {
    // producer, consumer, passthrough: the prototype3 mission's tasks (config/prototype3.yaml).
    return tasking::register_builtin_components(registry);
}

}  // namespace keel::node
