#include "core/tasking/builtin.hpp"

#include "core/tasking/assert.hpp"
#include "core/tasking/bytes.hpp"

namespace keel::tasking {

namespace {

// Sample payloads are bounded: the largest message the network layer carries.
constexpr std::int64_t max_payload_bytes = 64ll * 1024 * 1024;

class Producer final : public Component {
  public:
    LifecycleResult configure(const ComponentContext& context) override {
        const auto start = context.int_param("start", 0);
        const auto step = context.int_param("step", 1);
        const auto payload_bytes = context.int_param("payload_bytes", 8);
        if (!start || !step || !payload_bytes) {
            return LifecycleResult::failed("start, step and payload_bytes must be integers");
        }
        if (*payload_bytes < 8 || *payload_bytes > max_payload_bytes) {
            return LifecycleResult::failed("payload_bytes must be within 8.." +
                                           std::to_string(max_payload_bytes));
        }
        start_ = *start;
        step_ = *step;
        payload_bytes_ = static_cast<std::size_t>(*payload_bytes);
        return LifecycleResult::ok();
    }

    LifecycleResult activate(const std::optional<Snapshot>& snapshot) override {
        counter_ = start_;
        if (!snapshot) return LifecycleResult::ok();
        if (snapshot->format_version != 1) {
            return LifecycleResult::failed("producer snapshot format " +
                                           std::to_string(snapshot->format_version) + " is not 1");
        }
        ByteReader reader(snapshot->payload);
        const std::int64_t counter = reader.i64();
        if (reader.fail() || !reader.at_end()) {
            return LifecycleResult::failed("producer snapshot is corrupt");
        }
        counter_ = counter;
        return LifecycleResult::ok();
    }

    PortTypes port_types() const override { return {{}, {counter_type_id}}; }

    ExecutionResult execute(const Inputs&, Outputs& outputs) override {
        counter_ += step_;
        outputs.emit(counter_type_id, counter_payload(counter_, payload_bytes_));
        return {Outcome::success, static_cast<double>(counter_)};
    }

    Snapshot deactivate() override { return snapshot(); }

    Snapshot snapshot() const override {
        Snapshot state;
        put_i64(state.payload, counter_);
        return state;
    }

  private:
    std::int64_t start_ = 0;
    std::int64_t step_ = 1;
    std::size_t payload_bytes_ = 8;
    std::int64_t counter_ = 0;
};

class Consumer final : public Component {
  public:
    LifecycleResult configure(const ComponentContext& context) override {
        if (context.inputs.empty()) {
            return LifecycleResult::failed("task '" + context.task +
                                           "': a consumer needs at least one input");
        }
        return LifecycleResult::ok();
    }

    LifecycleResult activate(const std::optional<Snapshot>& snapshot) override {
        total_ = 0;
        received_ = 0;
        last_ = 0;
        if (!snapshot) return LifecycleResult::ok();
        if (snapshot->format_version != 1) {
            return LifecycleResult::failed("consumer snapshot format " +
                                           std::to_string(snapshot->format_version) + " is not 1");
        }
        ByteReader reader(snapshot->payload);
        const std::int64_t total = reader.i64();
        const std::uint64_t received = reader.u64();
        const std::int64_t last = reader.i64();
        if (reader.fail() || !reader.at_end()) {
            return LifecycleResult::failed("consumer snapshot is corrupt");
        }
        total_ = total;
        received_ = received;
        last_ = last;
        return LifecycleResult::ok();
    }

    PortTypes port_types() const override { return {{counter_type_id}, {counter_type_id}}; }

    ExecutionResult execute(const Inputs& inputs, Outputs& outputs) override {
        bool any = false;
        for (std::size_t index = 0; index < inputs.size(); ++index) {
            const Sample* sample = inputs.get(index);
            if (sample == nullptr) continue;
            const auto value = read_counter(*sample);
            if (!value) return {Outcome::failure, std::nullopt};
            total_ += *value;
            last_ = *value;
            ++received_;
            any = true;
        }
        if (!any) return {Outcome::success, std::nullopt};
        outputs.emit(counter_type_id, counter_payload(total_));
        return {Outcome::success, static_cast<double>(last_)};
    }

    Snapshot deactivate() override { return snapshot(); }

    Snapshot snapshot() const override {
        Snapshot state;
        put_i64(state.payload, total_);
        put_u64(state.payload, received_);
        put_i64(state.payload, last_);
        return state;
    }

  private:
    std::int64_t total_ = 0;
    std::uint64_t received_ = 0;
    std::int64_t last_ = 0;
};

class Passthrough final : public Component {
  public:
    LifecycleResult configure(const ComponentContext&) override { return LifecycleResult::ok(); }
    LifecycleResult activate(const std::optional<Snapshot>&) override {
        return LifecycleResult::ok();
    }
    ExecutionResult execute(const Inputs& inputs, Outputs& outputs) override {
        for (std::size_t index = 0; index < inputs.size(); ++index) {
            if (const Sample* sample = inputs.get(index)) {
                outputs.emit(sample->type_id, sample->payload);
            }
        }
        return {Outcome::success, std::nullopt};
    }
    Snapshot deactivate() override { return {}; }
    Snapshot snapshot() const override { return {}; }
};

}  // namespace

std::optional<std::int64_t> read_counter(const Sample& sample) {
    if (sample.type_id != counter_type_id || sample.payload == nullptr ||
        sample.payload->size() < 8) {
        return std::nullopt;
    }
    ByteReader reader(std::span<const std::uint8_t>(sample.payload->data(), 8));
    return reader.i64();
}

std::vector<std::uint8_t> counter_payload(std::int64_t value, std::size_t payload_bytes) {
    KEEL_TASKING_ASSERT(payload_bytes >= 8);
    std::vector<std::uint8_t> bytes;
    bytes.reserve(payload_bytes);
    put_i64(bytes, value);
    bytes.resize(payload_bytes, 0);
    return bytes;
}

ComponentPtr make_producer() {
    return std::make_unique<Producer>();
}
ComponentPtr make_consumer() {
    return std::make_unique<Consumer>();
}
ComponentPtr make_passthrough() {
    return std::make_unique<Passthrough>();
}

bool register_builtin_components(ComponentRegistry& registry) {
    bool all = registry.add("producer", make_producer);
    all = registry.add("consumer", make_consumer) && all;
    all = registry.add("passthrough", make_passthrough) && all;
    return all;
}

}  // namespace keel::tasking
