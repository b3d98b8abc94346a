// CompositeComponent: a component built from child components wired inside it, presenting
// the outer ports of one task (the paper's Fig. 4).
//
// Wiring is declared with the Builder:
//   child(name, component, inputs)        a child and the names of its inputs
//   expose_input(outer, child, input)     an input of the task feeds a child's input
//   connect(from, to, input)              a child's outputs feed a later child's input
//   expose_output(child)                  a child's outputs leave the task
//   control_value_from(child)             whose control value the task reports
//
// One execution of the composite is one synchronous pass over the children in the order
// they were added (so a connection must go from an earlier child to a later one, checked by
// build()): a child runs when every one of its inputs received a sample during this pass, or
// on every pass when it has no inputs. A child's error stops the pass. The outcome is the
// worst of the children's; the control value comes from the designated child, else from the
// last child that reported one. Children's port types hold inside the composite too: a
// sample a child does not accept is not handed to it, and a child's undeclared output
// type goes nowhere.
//
// Configuration: each child gets the task's context with its own input names and the
// parameters that either carry no child prefix or carry its own (`blur.sigma` reaches child
// `blur` as `sigma`). Snapshots nest the children's snapshots by child name.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/tasking/component.hpp"

namespace keel::tasking {

class CompositeComponent final : public Component {
  public:
    class Builder;
    struct BuildResult {
        std::unique_ptr<CompositeComponent> composite;  // null on error
        std::string error;
    };

    LifecycleResult configure(const ComponentContext& context) override;
    LifecycleResult activate(const std::optional<Snapshot>& snapshot) override;
    ExecutionResult execute(const Inputs& inputs, Outputs& outputs) override;
    Snapshot deactivate() override;
    Snapshot snapshot() const override;

    std::size_t child_count() const { return children_.size(); }

    // Composite snapshot format version (the payload nests child snapshots).
    static constexpr std::uint32_t snapshot_format_version = 1;

  private:
    struct Route {
        std::size_t child;  // target child index
        std::size_t input;  // target input index
    };
    struct Child {
        std::string name;
        ComponentPtr component;
        std::vector<std::string> inputs;
        std::vector<Route> routes;  // where this child's outputs go inside the composite
        bool exposed = false;       // its outputs leave the task
        std::uint64_t sequence = 0;
        bool active = false;
        PortTypes types;  // asked at build(): mistyped samples never reach the child
    };
    struct Exposure {
        std::string outer_input;
        Route route;
        std::size_t outer_index = 0;  // resolved at configure()
    };

    CompositeComponent() = default;

    std::vector<Child> children_;
    std::vector<Exposure> exposures_;
    std::optional<std::size_t> control_child_;
    std::size_t output_capacity_ = 64;
    // Samples received by each child's inputs during the current pass.
    std::vector<std::vector<std::optional<Sample>>> pending_;
};

class CompositeComponent::Builder {
  public:
    Builder& child(std::string name, ComponentPtr component, std::vector<std::string> inputs = {});
    Builder& expose_input(std::string outer_input, std::string to_child, std::string to_input);
    Builder& connect(std::string from_child, std::string to_child, std::string to_input);
    Builder& expose_output(std::string from_child);
    Builder& control_value_from(std::string child);
    // At most this many samples per child per pass (default 64).
    Builder& output_capacity(std::size_t samples);

    BuildResult build();

  private:
    struct Connection {
        std::string from, to, input;
    };
    struct Exposed {
        std::string outer, to, input;
    };
    std::vector<std::string> names_;
    std::vector<ComponentPtr> components_;
    std::vector<std::vector<std::string>> inputs_;
    std::vector<Connection> connections_;
    std::vector<Exposed> exposed_inputs_;
    std::vector<std::string> exposed_outputs_;
    std::optional<std::string> control_child_;
    std::size_t output_capacity_ = 64;
};

}  // namespace keel::tasking
