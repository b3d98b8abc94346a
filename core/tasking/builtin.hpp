// Built-in components for tests, benchmarks and the prototype3 mission (config/):
//
//   producer     a periodic counter. Each execution adds `step` (default 1) to its counter,
//                starting from `start` (default 0), and emits it as a counter sample
//                (`payload_bytes`, default 8, pads the sample for throughput tests). Its
//                control value is the counter; its output carries counter samples.
//                Checkpointable: the counter.
//   consumer     an adder. Each execution adds the counter values of the samples it
//                receives to a running total and emits the total. Its control value is the
//                last value received. Its ports carry counter samples only (a foreign sample
//                handed to execute() directly makes the execution a failure).
//                Checkpointable: total, samples received, last value.
//   passthrough  forwards every sample it receives, unchanged and uncopied.
#pragma once

#include <cstdint>
#include <optional>

#include "core/tasking/registry.hpp"
#include "core/tasking/sample.hpp"

namespace keel::tasking {

// Type id of a counter sample: a little-endian int64 in the first 8 payload bytes.
inline constexpr TypeId counter_type_id = 1;

// The counter value of `sample`, or nothing when it is not a counter sample.
std::optional<std::int64_t> read_counter(const Sample& sample);
std::vector<std::uint8_t> counter_payload(std::int64_t value, std::size_t payload_bytes = 8);

ComponentPtr make_producer();
ComponentPtr make_consumer();
ComponentPtr make_passthrough();

// Registers producer, consumer and passthrough. False if any name was taken.
bool register_builtin_components(ComponentRegistry& registry);

}  // namespace keel::tasking
