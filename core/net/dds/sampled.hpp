// Sampled data with a real-time switch to a backup publisher (the paper's tasks A, B, C:
// A and B publish the same sampled data, C subscribes; when A dies, C follows B).
//
// DDS detects the death: every publisher writes its own instance of the stream (keyed by
// stream and writer) on the KeelSampled topic under a MANUAL_BY_TOPIC liveliness lease a
// little longer than the sampling period, so every write asserts it. The subscriber keeps
// the latest sample of every publisher (keep-last 1 per instance) and delivers those of the
// strongest live one. When that publisher stops (crash, hang), its lease expires, DDS turns
// its instance NOT_ALIVE_NO_WRITERS, and the subscriber switches to the next strongest at
// once, delivering that publisher's latest sample (at most one period old) instead of
// waiting for its next one: the switch takes at most the lease after the last sample of the
// dead publisher. (With EXCLUSIVE ownership DDS would drop the backup's samples until the
// switch, so the subscriber would also wait up to a period for the backup's next write.)
// When a stronger publisher comes back, the subscriber follows it again. Best-effort:
// sampled data is only worth its latest value.
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
    SecurityFiles security{};  // DDS Security for the participant (none: insecure)
};

struct SampledSample {
    std::uint16_t stream = 0;
    NodeAddress writer = 0;
    std::int32_t strength = 0;
    bool switched = false;  // the first sample delivered after a switch of publisher
    std::uint64_t sequence = 0;
    std::int64_t timestamp_ns = 0;
    std::vector<std::uint8_t> payload;
};

class SampledPublisher {
public:
    // `strength`: the subscriber follows the strongest live publisher (the primary).
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
    // Moves the followed publisher's new samples into `out` (appended), switching publisher
    // first when DDS reports the followed one dead; returns how many. Never blocks.
    std::size_t take(std::vector<SampledSample>& out);
    // Publishers matched so far (alive or not).
    std::size_t matched_writers() const;
    // The followed publisher's address, or -1 while none is alive.
    int following() const;
    std::uint64_t switches() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace keel::net::dds
