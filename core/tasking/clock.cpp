#include "core/tasking/clock.hpp"

#include <cassert>
#include <chrono>

namespace keel::tasking {

std::int64_t SteadyClock::now_ns() const {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

void ManualClock::set_ns(std::int64_t now_ns) {
    assert(now_ns >= now_ns_.load() && "a monotonic clock never goes backwards");
    now_ns_.store(now_ns, std::memory_order_release);
}

void ManualClock::advance_ms(std::int64_t delta_ms) {
    assert(delta_ms >= 0);
    now_ns_.fetch_add(delta_ms * 1'000'000, std::memory_order_acq_rel);
}

}  // namespace keel::tasking
