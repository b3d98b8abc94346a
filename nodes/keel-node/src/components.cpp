#include "keel/node/components.hpp"

#include "core/tasking/builtin.hpp"
#if KEEL_NODE_WITH_EO
#include "keel/eo/components.hpp"
#endif

namespace keel::node {

bool register_node_components(tasking::ComponentRegistry& registry) {
    // producer, consumer, passthrough: the prototype3 mission's tasks (config/prototype3.yaml).
    const bool builtin = tasking::register_builtin_components(registry);
#if KEEL_NODE_WITH_EO
    // sensor, acca, sink, aocs, downlink: the earth-observation mission's tasks
    // (config/earth_observation.yaml; nodes/components).
    return eo::components::register_eo_components(registry) && builtin;
#else
    return builtin;
#endif
}

bool node_components_include_eo() {
    return KEEL_NODE_WITH_EO != 0;
}

}  // namespace keel::node
