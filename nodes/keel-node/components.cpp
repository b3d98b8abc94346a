#include "nodes/keel-node/components.hpp"

#include "core/tasking/builtin.hpp"
#include "keel/eo/components.hpp"

namespace keel::node {

bool register_node_components(tasking::ComponentRegistry& registry) {
    // producer, consumer, passthrough: the prototype3 mission's tasks (config/prototype3.yaml).
    const bool builtin = tasking::register_builtin_components(registry);
    // sensor, acca, sink, aocs, downlink: the earth-observation mission's tasks
    // (config/earth_observation.yaml; nodes/components).
    return eo::components::register_eo_components(registry) && builtin;
}

}  // namespace keel::node
