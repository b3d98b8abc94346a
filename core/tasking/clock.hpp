// Clock: where the tasking framework reads time. Injected, so that tests and the
// simulator are deterministic (ManualClock) while the node runtime uses SteadyClock.
#pragma once

#include <atomic>
#include <cstdint>

namespace keel::tasking {

class Clock {
  public:
    virtual ~Clock() = default;
    // Monotonic nanoseconds since an arbitrary origin. Callable from any thread.
    virtual std::int64_t now_ns() const = 0;
    std::int64_t now_ms() const { return now_ns() / 1'000'000; }
};

// std::chrono::steady_clock.
class SteadyClock final : public Clock {
  public:
    std::int64_t now_ns() const override;
};

// A clock that moves only when told to. Thread-safe: tests may advance it while the
// threaded executor reads it.
class ManualClock final : public Clock {
  public:
    explicit ManualClock(std::int64_t start_ns = 0) : now_ns_(start_ns) {}
    std::int64_t now_ns() const override { return now_ns_.load(std::memory_order_acquire); }
    void set_ns(std::int64_t now_ns);  // never backwards (asserted)
    void advance_ms(std::int64_t delta_ms);

  private:
    std::atomic<std::int64_t> now_ns_;
};

}  // namespace keel::tasking
