// Helpers shared by the DDS transport's tests.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

#include "core/net/dds/dds_transport.hpp"

namespace keel::net::dds::testing {

// A participant for node `address` in `domain_id` with a fast heartbeat deadline (20 ms);
// `miss_limit` periods of silence make a writer's liveliness lapse.
inline DdsConfig config_for(NodeAddress address, std::uint32_t domain_id,
                            std::uint32_t miss_limit = 2) {
    DdsConfig config;
    config.address = address;
    config.domain_id = domain_id;
    config.heartbeat_period = std::chrono::milliseconds(20);
    config.heartbeat_miss_limit = miss_limit;
    return config;
}

// "Suite.Name" of the running test: each test takes a DDS domain of its own from it.
inline std::string test_name() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    return std::string(info->test_suite_name()) + "." + info->name();
}

// Polls `predicate` every 5 ms until it holds (true) or `timeout` passes (false).
template <class Predicate>
bool eventually(Predicate predicate,
                std::chrono::milliseconds timeout = std::chrono::milliseconds(10'000)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!predicate()) {
        if (std::chrono::steady_clock::now() >= deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
}

}  // namespace keel::net::dds::testing
