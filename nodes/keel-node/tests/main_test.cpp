// The node binary's components: the sets keel_add_node() registers, in order, and the
// refusal of a name registered twice, naming the component and who registered it.
#include "keel/node/main.hpp"

#include <gtest/gtest.h>

#include "core/tasking/builtin.hpp"
#include "keel/node/components.hpp"

namespace keel::node {
namespace {

bool register_thermal(tasking::ComponentRegistry& registry) {
    return registry.add("thermal", tasking::make_producer);
}

bool register_another_producer(tasking::ComponentRegistry& registry) {
    return registry.add("producer", tasking::make_consumer);
}

TEST(NodeMain, RegistersKeelsComponentsAndTheBinarysOwn) {
    const ComponentSet sets[] = {
        {"Keel's built-in components", register_node_components},
        {"thermal::register_components", register_thermal},
    };
    tasking::ComponentRegistry registry;
    EXPECT_EQ(register_component_sets(registry, sets), "");
    EXPECT_TRUE(registry.contains("thermal"));
    EXPECT_TRUE(registry.contains("producer"));
    EXPECT_EQ(registry.contains("acca"), node_components_include_eo());
    EXPECT_NE(registry.create("thermal"), nullptr);
}

TEST(NodeMain, ANameRegisteredTwiceIsNamedWithBothRegistrations) {
    const ComponentSet sets[] = {
        {"Keel's built-in components", register_node_components},
        {"thermal::register_components", register_another_producer},
    };
    tasking::ComponentRegistry registry;
    EXPECT_EQ(register_component_sets(registry, sets),
              "component 'producer' of thermal::register_components is already registered by "
              "Keel's built-in components");
    // A set that fails on its own (a name twice within it, or an empty factory) is named.
    const ComponentSet twice[] = {{"doubled", [](tasking::ComponentRegistry& own) {
        return register_thermal(own) && register_thermal(own);
    }}};
    tasking::ComponentRegistry other;
    EXPECT_EQ(register_component_sets(other, twice),
              "doubled registers a component name twice (or an empty factory)");
}

TEST(NodeMain, TheVersionIsKeels) {
    EXPECT_STREQ(keel_version(), KEEL_VERSION);
}

}  // namespace
}  // namespace keel::node
