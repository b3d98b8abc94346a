#include "limit_checker.hpp"

#include <spdlog/spdlog.h>

#include <limits>
#include <memory>
#include <string>

#include "core/tasking/builtin.hpp"  // counter samples: tasking::read_counter
#include "core/tasking/bytes.hpp"    // little-endian helpers: put_u64, ByteReader

namespace limit_checker {

namespace tasking = keel::tasking;

namespace {

constexpr std::uint32_t state_format = 1;
constexpr std::uint32_t status_format = 1;
constexpr std::int64_t persistence_max = 1'000'000;

const char* to_string(Verdict verdict) {
    switch (verdict) {
        case Verdict::within: return "within";
        case Verdict::below: return "below";
        case Verdict::above: return "above";
    }
    return "unknown";
}

class LimitChecker final : public tasking::Component {
  public:
    // The executor refuses other sample types at the input (counted, never delivered) and
    // drops outputs of a type not declared here.
    tasking::PortTypes port_types() const override {
        return {{tasking::counter_type_id}, {status_type_id}};
    }

    // Called before the first activation and again when a phase change brings other
    // parameters: the context holds the task's params merged with the phase's.
    tasking::LifecycleResult configure(const tasking::ComponentContext& context) override {
        const auto low = context.int_param("low", std::numeric_limits<std::int64_t>::min());
        const auto high = context.int_param("high", std::numeric_limits<std::int64_t>::max());
        const auto persistence = context.int_param("persistence", 1);
        if (!low || !high || !persistence) {
            return tasking::LifecycleResult::failed(context.task +
                                                    ": low, high and persistence must be integers");
        }
        if (*low > *high) {
            return tasking::LifecycleResult::failed(context.task + ": low " + std::to_string(*low) +
                                                    " is above high " + std::to_string(*high));
        }
        if (*persistence < 1 || *persistence > persistence_max) {
            return tasking::LifecycleResult::failed(context.task + ": persistence must be within 1.." +
                                                    std::to_string(persistence_max));
        }
        if (context.inputs.size() != 1) {
            return tasking::LifecycleResult::failed(context.task + ": checks one input, not " +
                                                    std::to_string(context.inputs.size()));
        }
        task_ = context.task;
        input_ = context.inputs.front();
        phase_ = context.phase.empty() ? "(none)" : context.phase;
        low_ = *low;
        high_ = *high;
        persistence_ = static_cast<std::uint64_t>(*persistence);
        return tasking::LifecycleResult::ok();
    }

    // Starts the task, from its checkpoint when the node has one (the task moved here from a
    // failed node, or its phase changed): the counts go on where they were.
    tasking::LifecycleResult activate(const std::optional<tasking::Snapshot>& snapshot) override {
        checked_ = 0;
        consecutive_ = 0;
        alarms_ = 0;
        last_ = 0;
        alarm_ = false;
        if (!snapshot || snapshot->payload.empty()) {
            spdlog::info("{}: started in phase {}: {} within [{}, {}], persistence {}", task_, phase_,
                         input_, low_, high_, persistence_);
            return tasking::LifecycleResult::ok();
        }
        if (snapshot->format_version != state_format) {
            return tasking::LifecycleResult::failed(task_ + ": checkpoint format " +
                                                    std::to_string(snapshot->format_version) +
                                                    " is not " + std::to_string(state_format));
        }
        tasking::ByteReader reader(snapshot->payload);
        const std::uint64_t checked = reader.u64();
        const std::uint64_t consecutive = reader.u64();
        const std::uint64_t alarms = reader.u64();
        const std::int64_t last = reader.i64();
        const std::uint32_t alarm = reader.u32();
        if (reader.fail() || !reader.at_end() || alarm > 1) {
            return tasking::LifecycleResult::failed(task_ + ": checkpoint is corrupt");
        }
        checked_ = checked;
        consecutive_ = consecutive;
        alarms_ = alarms;
        last_ = last;
        alarm_ = alarm == 1;
        spdlog::info("{}: resumed from checkpoint: {} samples checked, {} alarms raised; phase {}: "
                     "{} within [{}, {}], persistence {}",
                     task_, checked_, alarms_, phase_, input_, low_, high_, persistence_);
        return tasking::LifecycleResult::ok();
    }

    tasking::ExecutionResult execute(const tasking::Inputs& inputs,
                                     tasking::Outputs& outputs) override {
        const tasking::Sample* sample = inputs.get(0);
        // The task runs when its input has a sample; an event (no sample) has nothing to check.
        if (sample == nullptr) return {tasking::Outcome::success, std::nullopt};
        const std::optional<std::int64_t> value = tasking::read_counter(*sample);
        // The port types keep other samples out; one handed to execute() directly is an
        // unusable input: a failure, and the component stays sound.
        if (!value) return {tasking::Outcome::failure, std::nullopt};

        ++checked_;
        last_ = *value;
        const Verdict verdict = *value < low_ ? Verdict::below
                                : *value > high_ ? Verdict::above
                                                 : Verdict::within;
        if (verdict == Verdict::within) {
            if (alarm_) {
                spdlog::info("{}: {} {} back within [{}, {}] after {} samples out: alarm cleared",
                             task_, input_, *value, low_, high_, consecutive_);
            }
            consecutive_ = 0;
            alarm_ = false;
        } else {
            ++consecutive_;
            if (!alarm_ && consecutive_ >= persistence_) {
                alarm_ = true;
                ++alarms_;
                spdlog::warn("{}: {} {} {} {} for {} samples: alarm {} raised", task_, input_, *value,
                             to_string(verdict), verdict == Verdict::above ? high_ : low_,
                             consecutive_, alarms_);
            }
        }
        outputs.emit(status_type_id, encode({*value, verdict, consecutive_, alarms_, alarm_}));
        return {tasking::Outcome::success, static_cast<double>(*value)};
    }

    tasking::Snapshot deactivate() override { return snapshot(); }

    // The executor takes a snapshot after every successful execution of a task with
    // `checkpoint: true` and stamps it with the task's name and execution count.
    tasking::Snapshot snapshot() const override {
        tasking::Snapshot state;
        state.format_version = state_format;
        tasking::put_u64(state.payload, checked_);
        tasking::put_u64(state.payload, consecutive_);
        tasking::put_u64(state.payload, alarms_);
        tasking::put_i64(state.payload, last_);
        tasking::put_u32(state.payload, alarm_ ? 1 : 0);
        return state;
    }

  private:
    // Configuration (configure()).
    std::string task_ = "limit_checker";
    std::string input_;
    std::string phase_;
    std::int64_t low_ = std::numeric_limits<std::int64_t>::min();
    std::int64_t high_ = std::numeric_limits<std::int64_t>::max();
    std::uint64_t persistence_ = 1;
    // State (checkpointed).
    std::uint64_t checked_ = 0;
    std::uint64_t consecutive_ = 0;
    std::uint64_t alarms_ = 0;
    std::int64_t last_ = 0;
    bool alarm_ = false;
};

}  // namespace

std::vector<std::uint8_t> encode(const LimitStatus& status) {
    std::vector<std::uint8_t> bytes;
    bytes.reserve(36);
    tasking::put_u32(bytes, status_format);
    tasking::put_i64(bytes, status.value);
    tasking::put_u32(bytes, static_cast<std::uint32_t>(status.verdict));
    tasking::put_u64(bytes, status.consecutive);
    tasking::put_u64(bytes, status.alarms);
    tasking::put_u32(bytes, status.alarm ? 1 : 0);
    return bytes;
}

std::optional<LimitStatus> decode_status(std::span<const std::uint8_t> bytes) {
    tasking::ByteReader reader(bytes);
    const std::uint32_t format = reader.u32();
    LimitStatus status;
    status.value = reader.i64();
    const std::uint32_t verdict = reader.u32();
    status.consecutive = reader.u64();
    status.alarms = reader.u64();
    const std::uint32_t alarm = reader.u32();
    if (reader.fail() || !reader.at_end() || format != status_format || verdict > 2 || alarm > 1) {
        return std::nullopt;
    }
    status.verdict = static_cast<Verdict>(verdict);
    status.alarm = alarm == 1;
    return status;
}

keel::tasking::ComponentPtr make_limit_checker() {
    return std::make_unique<LimitChecker>();
}

bool register_components(keel::tasking::ComponentRegistry& registry) {
    return registry.add("limit_checker", make_limit_checker);
}

}  // namespace limit_checker
