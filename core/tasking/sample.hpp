// Sample: one message between tasks, as the Tasking framework's "typed task message".
//
// A sample carries its payload as an immutable shared buffer, so a 16 MB scene produced by
// one task reaches every co-located consumer without a copy: delivery copies the handle,
// never the bytes. The type id names the payload's format (each component family picks its
// own ids); the source port is the producing task's mission port, which is how a consumer
// tells its inputs apart (the paper addresses messages by logical address + port).
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace keel::tasking {

// A mission port number (Task::port).
using PortNumber = std::int64_t;
// The format of a payload; 0 is reserved for "untyped bytes".
using TypeId = std::uint32_t;
using Payload = std::shared_ptr<const std::vector<std::uint8_t>>;

inline Payload make_payload(std::vector<std::uint8_t> bytes) {
    return std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes));
}

struct Sample {
    TypeId type_id = 0;
    // Per producing task, starting at 1; a consumer may detect gaps with it.
    std::uint64_t sequence = 0;
    // The producing task's mission port.
    PortNumber source_port = 0;
    // When the producing execution started, on the executor's clock.
    std::int64_t timestamp_ns = 0;
    // Never null for a sample that went through Outputs::emit.
    Payload payload;

    std::size_t size_bytes() const { return payload ? payload->size() : 0; }
};

}  // namespace keel::tasking
