#include "core/tasking/component.hpp"

#include <algorithm>
#include <variant>

#include "core/tasking/assert.hpp"

namespace keel::tasking {

std::string_view to_string(Outcome outcome) {
    switch (outcome) {
        case Outcome::success:
            return "success";
        case Outcome::failure:
            return "failure";
        case Outcome::error:
            return "error";
    }
    return "unknown";
}

Outcome worst(Outcome a, Outcome b) {
    return static_cast<std::uint8_t>(a) >= static_cast<std::uint8_t>(b) ? a : b;
}

std::string_view to_string(Trigger trigger) {
    switch (trigger) {
        case Trigger::inputs:
            return "inputs";
        case Trigger::timer:
            return "timer";
        case Trigger::event:
            return "event";
    }
    return "unknown";
}

bool PortTypes::accepts(TypeId type) const {
    return inputs.empty() || std::find(inputs.begin(), inputs.end(), type) != inputs.end();
}

bool PortTypes::emits(TypeId type) const {
    return outputs.empty() || std::find(outputs.begin(), outputs.end(), type) != outputs.end();
}

const mission::ParamValue* ComponentContext::param(std::string_view name) const {
    // Merged parameters may hold a name twice (task, then phase): the last one wins.
    const mission::ParamValue* found = nullptr;
    for (const auto& [key, value] : params) {
        if (key == name) found = &value;
    }
    return found;
}

std::optional<std::int64_t> ComponentContext::int_param(std::string_view name,
                                                        std::int64_t fallback) const {
    const mission::ParamValue* value = param(name);
    if (value == nullptr) return fallback;
    if (const auto* integer = std::get_if<std::int64_t>(value)) return *integer;
    return std::nullopt;
}

std::optional<double> ComponentContext::double_param(std::string_view name, double fallback) const {
    const mission::ParamValue* value = param(name);
    if (value == nullptr) return fallback;
    if (const auto* real = std::get_if<double>(value)) return *real;
    if (const auto* integer = std::get_if<std::int64_t>(value)) {
        return static_cast<double>(*integer);
    }
    return std::nullopt;
}

std::optional<std::string> ComponentContext::string_param(std::string_view name,
                                                          std::string fallback) const {
    const mission::ParamValue* value = param(name);
    if (value == nullptr) return fallback;
    if (const auto* text = std::get_if<std::string>(value)) return *text;
    return std::nullopt;
}

std::optional<bool> ComponentContext::bool_param(std::string_view name, bool fallback) const {
    const mission::ParamValue* value = param(name);
    if (value == nullptr) return fallback;
    if (const auto* flag = std::get_if<bool>(value)) return *flag;
    return std::nullopt;
}

Inputs::Inputs(const std::vector<std::string>* names, Trigger trigger)
    : names_(names), trigger_(trigger) {
    KEEL_TASKING_ASSERT(names_ != nullptr);
    samples_.resize(names_->size());
}

const std::string& Inputs::name(std::size_t index) const {
    KEEL_TASKING_ASSERT(index < names_->size());
    return (*names_)[index];
}

const Sample* Inputs::get(std::size_t index) const {
    KEEL_TASKING_ASSERT(index < samples_.size());
    return samples_[index] ? &*samples_[index] : nullptr;
}

const Sample* Inputs::get(std::string_view input_name) const {
    for (std::size_t index = 0; index < names_->size(); ++index) {
        if ((*names_)[index] == input_name) return get(index);
    }
    return nullptr;
}

std::size_t Inputs::present() const {
    std::size_t count = 0;
    for (const auto& sample : samples_) count += sample.has_value() ? 1 : 0;
    return count;
}

void Inputs::set(std::size_t index, Sample sample) {
    KEEL_TASKING_ASSERT(index < samples_.size());
    samples_[index] = std::move(sample);
}

Outputs::Outputs(PortNumber port, std::uint64_t* sequence, std::int64_t timestamp_ns,
                 std::size_t capacity)
    : port_(port), sequence_(sequence), timestamp_ns_(timestamp_ns), capacity_(capacity) {
    KEEL_TASKING_ASSERT(sequence_ != nullptr);
    KEEL_TASKING_ASSERT(capacity_ > 0);
}

void Outputs::emit(TypeId type_id, Payload payload) {
    KEEL_TASKING_ASSERT(payload != nullptr);
    if (samples_.size() >= capacity_) {
        ++dropped_;
        return;
    }
    Sample sample;
    sample.type_id = type_id;
    sample.sequence = ++*sequence_;
    sample.source_port = port_;
    sample.timestamp_ns = timestamp_ns_;
    sample.payload = std::move(payload);
    samples_.push_back(std::move(sample));
}

void Outputs::emit(TypeId type_id, std::vector<std::uint8_t> bytes) {
    emit(type_id, make_payload(std::move(bytes)));
}

}  // namespace keel::tasking
