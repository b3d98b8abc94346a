#include "core/tasking/composite.hpp"

#include <algorithm>
#include <variant>

#include "core/tasking/assert.hpp"
#include "core/tasking/bytes.hpp"

namespace keel::tasking {

namespace {

std::optional<std::size_t> index_of(const std::vector<std::string>& names,
                                    const std::string& name) {
    const auto found = std::find(names.begin(), names.end(), name);
    if (found == names.end()) return std::nullopt;
    return static_cast<std::size_t>(found - names.begin());
}

}  // namespace

CompositeComponent::Builder& CompositeComponent::Builder::child(std::string name,
                                                                ComponentPtr component,
                                                                std::vector<std::string> inputs) {
    names_.push_back(std::move(name));
    components_.push_back(std::move(component));
    inputs_.push_back(std::move(inputs));
    return *this;
}

CompositeComponent::Builder& CompositeComponent::Builder::expose_input(std::string outer_input,
                                                                       std::string to_child,
                                                                       std::string to_input) {
    exposed_inputs_.push_back({std::move(outer_input), std::move(to_child), std::move(to_input)});
    return *this;
}

CompositeComponent::Builder& CompositeComponent::Builder::connect(std::string from_child,
                                                                  std::string to_child,
                                                                  std::string to_input) {
    connections_.push_back({std::move(from_child), std::move(to_child), std::move(to_input)});
    return *this;
}

CompositeComponent::Builder& CompositeComponent::Builder::expose_output(std::string from_child) {
    exposed_outputs_.push_back(std::move(from_child));
    return *this;
}

CompositeComponent::Builder& CompositeComponent::Builder::control_value_from(std::string child) {
    control_child_ = std::move(child);
    return *this;
}

CompositeComponent::Builder& CompositeComponent::Builder::output_capacity(std::size_t samples) {
    output_capacity_ = samples;
    return *this;
}

CompositeComponent::BuildResult CompositeComponent::Builder::build() {
    auto fail = [](std::string why) { return BuildResult{nullptr, std::move(why)}; };
    if (names_.empty()) return fail("a composite needs at least one child");
    if (output_capacity_ == 0) return fail("output capacity must be at least one sample");
    for (std::size_t index = 0; index < names_.size(); ++index) {
        if (names_[index].empty()) return fail("a child needs a name");
        if (components_[index] == nullptr) return fail("child '" + names_[index] + "' is null");
        if (index_of(names_, names_[index]) != index) {
            return fail("child '" + names_[index] + "' is declared twice");
        }
    }
    std::unique_ptr<CompositeComponent> composite(new CompositeComponent());
    composite->output_capacity_ = output_capacity_;
    for (std::size_t index = 0; index < names_.size(); ++index) {
        Child child;
        child.name = names_[index];
        child.component = std::move(components_[index]);
        child.inputs = inputs_[index];
        child.types = child.component->port_types();
        composite->children_.push_back(std::move(child));
    }
    // Every child input must be fed exactly once: by an exposed input or a connection.
    std::vector<std::vector<int>> feeds(names_.size());
    for (std::size_t index = 0; index < names_.size(); ++index) {
        feeds[index].assign(inputs_[index].size(), 0);
    }
    auto resolve = [&](const std::string& child_name,
                       const std::string& input) -> std::variant<Route, std::string> {
        const auto child = index_of(names_, child_name);
        if (!child) return "no child named '" + child_name + "'";
        const auto slot = index_of(inputs_[*child], input);
        if (!slot) return "child '" + child_name + "' has no input '" + input + "'";
        return Route{*child, *slot};
    };
    for (const Exposed& exposed : exposed_inputs_) {
        auto route = resolve(exposed.to, exposed.input);
        if (auto* why = std::get_if<std::string>(&route)) return fail(*why);
        const Route target = std::get<Route>(route);
        ++feeds[target.child][target.input];
        composite->exposures_.push_back({exposed.outer, target, 0});
    }
    for (const Connection& connection : connections_) {
        const auto from = index_of(names_, connection.from);
        if (!from) return fail("no child named '" + connection.from + "'");
        auto route = resolve(connection.to, connection.input);
        if (auto* why = std::get_if<std::string>(&route)) return fail(*why);
        const Route target = std::get<Route>(route);
        if (target.child <= *from) {
            return fail("connection " + connection.from + " -> " + connection.to +
                        " goes backwards: children run in the order they are added");
        }
        ++feeds[target.child][target.input];
        composite->children_[*from].routes.push_back(target);
    }
    for (std::size_t child = 0; child < names_.size(); ++child) {
        for (std::size_t input = 0; input < inputs_[child].size(); ++input) {
            if (feeds[child][input] != 1) {
                return fail("input '" + inputs_[child][input] + "' of child '" + names_[child] +
                            "' is fed " + std::to_string(feeds[child][input]) +
                            " times; it must be fed exactly once");
            }
        }
    }
    if (exposed_outputs_.empty()) return fail("a composite must expose at least one output");
    for (const std::string& name : exposed_outputs_) {
        const auto child = index_of(names_, name);
        if (!child) return fail("no child named '" + name + "' to expose");
        composite->children_[*child].exposed = true;
    }
    if (control_child_) {
        const auto child = index_of(names_, *control_child_);
        if (!child) return fail("no child named '" + *control_child_ + "' for the control value");
        composite->control_child_ = *child;
    }
    composite->pending_.resize(names_.size());
    for (std::size_t index = 0; index < names_.size(); ++index) {
        composite->pending_[index].resize(inputs_[index].size());
    }
    return BuildResult{std::move(composite), {}};
}

LifecycleResult CompositeComponent::configure(const ComponentContext& context) {
    for (Exposure& exposure : exposures_) {
        const auto outer = index_of(context.inputs, exposure.outer_input);
        if (!outer) {
            return LifecycleResult::broken("composite input '" + exposure.outer_input +
                                           "' is not an input of task '" + context.task + "'");
        }
        exposure.outer_index = *outer;
    }
    for (const std::string& input : context.inputs) {
        const bool used = std::any_of(exposures_.begin(), exposures_.end(),
                                      [&](const Exposure& e) { return e.outer_input == input; });
        if (!used) {
            return LifecycleResult::broken("input '" + input + "' of task '" + context.task +
                                           "' feeds no child of its composite component");
        }
    }
    for (Child& child : children_) {
        ComponentContext child_context;
        child_context.task = context.task + "/" + child.name;
        child_context.component = child.name;
        child_context.port = context.port;
        child_context.phase = context.phase;
        child_context.inputs = child.inputs;
        child_context.period_ms = context.period_ms;
        const std::string prefix = child.name + ".";
        for (const auto& [key, value] : context.params) {
            if (key.starts_with(prefix)) {
                child_context.params.emplace_back(key.substr(prefix.size()), value);
            } else if (key.find('.') == std::string::npos) {
                child_context.params.emplace_back(key, value);
            }
        }
        LifecycleResult result = child.component->configure(child_context);
        if (!result.succeeded()) {
            result.message = "child '" + child.name + "': " + result.message;
            return result;
        }
    }
    return LifecycleResult::ok();
}

LifecycleResult CompositeComponent::activate(const std::optional<Snapshot>& snapshot) {
    std::vector<std::optional<Snapshot>> restored(children_.size());
    if (snapshot) {
        if (snapshot->format_version != snapshot_format_version) {
            return LifecycleResult::failed("composite snapshot format " +
                                           std::to_string(snapshot->format_version) + " is not " +
                                           std::to_string(snapshot_format_version));
        }
        ByteReader reader(snapshot->payload);
        const std::uint32_t count = reader.u32();
        for (std::uint32_t entry = 0; entry < count && !reader.fail(); ++entry) {
            Snapshot child_snapshot;
            const std::string name = reader.string();
            child_snapshot.format_version = reader.u32();
            child_snapshot.payload = reader.bytes();
            child_snapshot.task = snapshot->task + "/" + name;
            child_snapshot.sequence = snapshot->sequence;
            std::optional<std::size_t> child;
            for (std::size_t index = 0; index < children_.size(); ++index) {
                if (children_[index].name == name) child = index;
            }
            if (!child) {
                return LifecycleResult::failed("snapshot holds unknown child '" + name + "'");
            }
            restored[*child] = std::move(child_snapshot);
        }
        if (reader.fail() || !reader.at_end()) {
            return LifecycleResult::failed("composite snapshot is truncated or corrupt");
        }
    }
    for (std::size_t index = 0; index < children_.size(); ++index) {
        LifecycleResult result = children_[index].component->activate(restored[index]);
        if (!result.succeeded()) {
            for (std::size_t undo = 0; undo < index; ++undo) {
                children_[undo].component->deactivate();
                children_[undo].active = false;
            }
            result.message = "child '" + children_[index].name + "': " + result.message;
            return result;
        }
        children_[index].active = true;
    }
    return LifecycleResult::ok();
}

ExecutionResult CompositeComponent::execute(const Inputs& inputs, Outputs& outputs) {
    for (auto& slots : pending_) {
        for (auto& slot : slots) slot.reset();
    }
    for (const Exposure& exposure : exposures_) {
        const Sample* sample = inputs.get(exposure.outer_index);
        if (sample != nullptr && children_[exposure.route.child].types.accepts(sample->type_id)) {
            pending_[exposure.route.child][exposure.route.input] = *sample;
        }
    }
    ExecutionResult result;
    std::optional<double> last_control_value;
    for (std::size_t index = 0; index < children_.size(); ++index) {
        Child& child = children_[index];
        auto& slots = pending_[index];
        const bool ready = std::all_of(slots.begin(), slots.end(),
                                       [](const auto& slot) { return slot.has_value(); });
        if (!ready) continue;
        Inputs child_inputs(&child.inputs,
                            child.inputs.empty() ? inputs.trigger() : Trigger::inputs);
        for (std::size_t slot = 0; slot < slots.size(); ++slot) {
            child_inputs.set(slot, std::move(*slots[slot]));
        }
        // Children's samples stay inside the task; port 0 marks them as internal.
        Outputs child_outputs(0, &child.sequence, outputs.timestamp_ns(), output_capacity_);
        const ExecutionResult child_result = child.component->execute(child_inputs, child_outputs);
        result.outcome = worst(result.outcome, child_result.outcome);
        if (child_result.control_value) last_control_value = child_result.control_value;
        if (control_child_ && *control_child_ == index) {
            result.control_value = child_result.control_value;
        }
        if (child_result.outcome == Outcome::error) break;
        for (const Sample& sample : child_outputs.samples()) {
            if (!child.types.emits(sample.type_id)) continue;
            for (const Route& route : child.routes) {
                if (!children_[route.child].types.accepts(sample.type_id)) continue;
                pending_[route.child][route.input] = sample;
            }
            if (child.exposed) outputs.emit(sample.type_id, sample.payload);
        }
    }
    if (!control_child_) result.control_value = last_control_value;
    return result;
}

Snapshot CompositeComponent::snapshot() const {
    Snapshot out;
    out.format_version = snapshot_format_version;
    put_u32(out.payload, static_cast<std::uint32_t>(children_.size()));
    for (const Child& child : children_) {
        const Snapshot state = child.component->snapshot();
        put_string(out.payload, child.name);
        put_u32(out.payload, state.format_version);
        put_bytes(out.payload, state.payload);
    }
    return out;
}

Snapshot CompositeComponent::deactivate() {
    Snapshot out;
    out.format_version = snapshot_format_version;
    put_u32(out.payload, static_cast<std::uint32_t>(children_.size()));
    for (Child& child : children_) {
        const Snapshot state = child.component->deactivate();
        child.active = false;
        put_string(out.payload, child.name);
        put_u32(out.payload, state.format_version);
        put_bytes(out.payload, state.payload);
    }
    return out;
}

}  // namespace keel::tasking
