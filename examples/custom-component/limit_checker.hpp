// limit_checker: a Keel component that checks a telemetry value against limits that depend
// on the mission phase. A value out of its limits for `persistence` samples in a row raises
// an alarm; back within them, the alarm clears.
//
//   input          counter samples (Keel's built-in sample type, tasking::counter_type_id),
//                  e.g. from the built-in `producer`; one value checked per execution
//   output         one status sample per execution (status_type_id, LimitStatus below)
//   parameters     low, high: the limits (integers, inclusive; default: unbounded);
//                  persistence: samples out of limits in a row that raise an alarm (1..10^6,
//                  default 1). A phase of the mission may set other values for the task
//                  (phases.PHASE.params.TASK), which win over the task's own.
//   control value  the value checked last: the mission's health.min/max bound it, so a value
//                  no sensor can produce is reported to the Master like a failing task
//   state          samples checked, samples out of limits in a row, alarms raised, the last
//                  value and whether an alarm is raised: checkpointed (format 1), so the task
//                  goes on counting where a failed node left it
//
// The framework never calls one component from two threads at once: no locks here.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/tasking/component.hpp"
#include "core/tasking/registry.hpp"

namespace limit_checker {

// The type id of a status sample. A component family picks ids of its own (Keel's
// built-in counter samples are 1, the earth-observation ones 0x454F0001...).
inline constexpr keel::tasking::TypeId status_type_id = 0x4C434B01;

enum class Verdict : std::uint8_t { within = 0, below = 1, above = 2 };

// What the checker says about one value. Encoded little-endian, 36 bytes:
//   u32 format (1) | i64 value | u32 verdict | u64 consecutive | u64 alarms | u32 alarm
struct LimitStatus {
    std::int64_t value = 0;
    Verdict verdict = Verdict::within;
    std::uint64_t consecutive = 0;  // samples out of limits in a row, this one included
    std::uint64_t alarms = 0;       // alarms raised since the task first started
    bool alarm = false;             // an alarm is raised

    friend bool operator==(const LimitStatus&, const LimitStatus&) = default;
};

std::vector<std::uint8_t> encode(const LimitStatus& status);
// Nothing when `bytes` is not a status of format 1.
std::optional<LimitStatus> decode_status(std::span<const std::uint8_t> bytes);

keel::tasking::ComponentPtr make_limit_checker();

// Registers the component under the name missions give it (`component: limit_checker`).
// The node binary calls it at start-up (keel_add_node's REGISTER in CMakeLists.txt).
bool register_components(keel::tasking::ComponentRegistry& registry);

}  // namespace limit_checker
