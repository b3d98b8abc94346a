// A mutex with priority inheritance, for every lock the node's protocol loop shares with a
// thread of lower priority (the executor's workers and timer, the data plane's thread, the
// control and status threads; and the checkpoint writer where the loop is not real-time).
//
// Under `--realtime` the loop runs at a SCHED_FIFO priority (core/node/scheduling.hpp) and
// those threads at normal scheduling. With an ordinary mutex, a lower thread that holds the
// lock and is preempted by the machine's other work (four CPU hogs on two cores, say) keeps
// the loop waiting for as long as the scheduler leaves it without a core: a priority
// inversion, and the loop's heartbeats stop with it (a 30-minute detector cell,
// docs/benchmarks.md, saw the Storage node's real-time loop blocked for 242 ms and the node
// excluded while alive; what blocked it the run does not say). With PTHREAD_PRIO_INHERIT
// the kernel lends the holder the waiter's priority until it unlocks (a PI futex), so the
// loop waits for the holder's critical section, not for the hogs. (A
// std::condition_variable_any keeps a short internal lock of its own, an ordinary mutex.)
//
// A standard Lockable: use it with std::lock_guard, std::unique_lock and
// std::condition_variable_any. Priority inheritance needs no privilege; without a
// real-time loop it changes nothing.
#pragma once

#include <pthread.h>

#include <system_error>

namespace keel::tasking {

class PiMutex {
public:
    PiMutex() {
        pthread_mutexattr_t attributes;
        int result = pthread_mutexattr_init(&attributes);
        if (result == 0) {
            result = pthread_mutexattr_setprotocol(&attributes, PTHREAD_PRIO_INHERIT);
            if (result == 0) result = pthread_mutex_init(&mutex_, &attributes);
            pthread_mutexattr_destroy(&attributes);
        }
        if (result != 0) {
            throw std::system_error(result, std::generic_category(),
                                    "a priority-inheriting mutex could not be made");
        }
    }
    ~PiMutex() { pthread_mutex_destroy(&mutex_); }
    PiMutex(const PiMutex&) = delete;
    PiMutex& operator=(const PiMutex&) = delete;

    void lock() {
        const int result = pthread_mutex_lock(&mutex_);
        if (result != 0) throw std::system_error(result, std::generic_category(), "PiMutex::lock");
    }
    bool try_lock() noexcept { return pthread_mutex_trylock(&mutex_) == 0; }
    void unlock() noexcept { pthread_mutex_unlock(&mutex_); }

private:
    pthread_mutex_t mutex_{};
};

}  // namespace keel::tasking
