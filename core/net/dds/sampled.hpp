// Sampled data with a real-time switch to a backup publisher (the paper's tasks A, B, C:
// A and B publish the same sampled data, C subscribes; when A dies, C gets B's samples).
//
// DDS does the switch itself: every publisher of a stream writes one instance (keyed by
// stream) on the KeelSampled topic with EXCLUSIVE ownership and its own ownership
// strength; liveliness is MANUAL_BY_TOPIC with a lease a little longer than the sampling
// period, so every write asserts it. A subscriber receives only the samples of the
// strongest publisher whose lease has not expired: when A stops (crash, hang), its lease
// expires and B's next sample is delivered; when A comes back, it takes the stream back.
// Best-effort, keep-last 1: sampled data is only worth its latest value.
//
// Each object owns a DDS participant pinned like DdsTransport (domain_config_xml: the
// given interface, multicast off, unicast peers). Threading: one thread per object.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/net/dds/dds_transport.hpp"

namespace keel::net::dds {

inline constexpr const char* sampled_topic_name = "KeelSampled";

struct SampledConfig {
    NodeAddress address = 0;  // written into every sample (who published it)
    std::uint32_t domain_id = 0;
    std::string network_interface = "lo";
    std::vector<std::string> peers = {"127.0.0.1"};
    // Liveliness lease: a publisher that has not written for this long loses the stream.
    // Must exceed the sampling period, or the stream would flap between writes.
    std::chrono::microseconds lease{std::chrono::milliseconds(25)};
};

struct SampledSample {
    std::uint16_t stream = 0;
    NodeAddress writer = 0;
    std::uint64_t sequence = 0;
    std::int64_t timestamp_ns = 0;
    std::vector<std::uint8_t> payload;
};

class SampledPublisher {
public:
    // `strength`: the higher one owns the stream while alive (the primary).
    SampledPublisher(const SampledConfig& config, std::uint16_t stream, std::int32_t strength);
    ~SampledPublisher();
    SampledPublisher(const SampledPublisher&) = delete;
    SampledPublisher& operator=(const SampledPublisher&) = delete;

    // Writes one sample (sequence and timestamp given by the caller). False if DDS refused.
    bool write(std::uint64_t sequence, std::int64_t timestamp_ns, std::span<const std::uint8_t> payload);
    // Readers of the stream matched so far.
    std::size_t matched_readers() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

class SampledSubscriber {
public:
    explicit SampledSubscriber(const SampledConfig& config);
    ~SampledSubscriber();
    SampledSubscriber(const SampledSubscriber&) = delete;
    SampledSubscriber& operator=(const SampledSubscriber&) = delete;

    // Blocks until a sample may be available or `timeout` passes.
    bool wait(std::chrono::nanoseconds timeout);
    // Moves up to max_items samples into `out` (appended); returns how many. Never blocks.
    std::size_t take(std::vector<SampledSample>& out, std::size_t max_items = 64);
    // Publishers matched so far (alive or not).
    std::size_t matched_writers() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace keel::net::dds
