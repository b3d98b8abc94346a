// PiMutex (pi_mutex.hpp): a holder of lower priority is lent the waiter's priority. The
// inversion is staged on one processor: a holder at normal scheduling takes the lock, a
// real-time hog (FIFO 10) starts spinning for 400 ms, and a real-time waiter (FIFO 20) asks
// for the lock. With inheritance the holder runs at 20, above the hog, finishes and unlocks:
// the waiter has the lock while the hog still spins. With a plain mutex the holder gets no
// processor until the hog stops: the waiter has it only after. The verdict is the order of
// two events, not a duration. Needs real-time priorities (root, or CAP_SYS_NICE): skipped
// where the process may not have them.
#include "core/tasking/pi_mutex.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <ctime>
#include <mutex>
#include <thread>

namespace keel::tasking {
namespace {

using Clock = std::chrono::steady_clock;

// The first processor this process may run on, or -1.
int first_allowed_cpu() {
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (sched_getaffinity(0, sizeof allowed, &allowed) != 0) return -1;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
        if (CPU_ISSET(cpu, &allowed)) return cpu;
    }
    return -1;
}

// The priority first: a thread that moved at normal scheduling onto the processor where
// the hog spins would not run again to raise it.
bool pin_and_schedule(int cpu, int policy, int priority) {
    sched_param param{};
    param.sched_priority = priority;
    if (pthread_setschedparam(pthread_self(), policy, &param) != 0) return false;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    return pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0;
}

bool may_use_real_time() {
    bool allowed = false;
    std::thread probe([&] {
        sched_param param{};
        param.sched_priority = 20;  // the highest the staging uses (RLIMIT_RTPRIO may cap it)
        allowed = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
    });
    probe.join();
    return allowed;
}

// Spins until this thread has had `cpu` of processor time.
void work_for(std::chrono::milliseconds cpu) {
    timespec start{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &start);
    for (;;) {
        timespec now{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
        const auto used = std::chrono::seconds(now.tv_sec - start.tv_sec) +
                          std::chrono::nanoseconds(now.tv_nsec - start.tv_nsec);
        if (used >= cpu) return;
    }
}

struct Outcome {
    bool staged = false;           // every thread got its processor and priority
    bool hog_done_at_lock = true;  // the hog had stopped when the waiter got the lock
};

// The inversion above, with `Mutex` as the lock.
template <typename Mutex>
Outcome stage_inversion() {
    const int cpu = first_allowed_cpu();
    Outcome outcome;
    if (cpu < 0) return outcome;
    Mutex mutex;
    std::atomic<bool> held{false};
    std::atomic<bool> hog_started{false};
    std::atomic<bool> hog_done{false};
    std::atomic<int> failures{0};

    std::thread holder([&] {
        if (!pin_and_schedule(cpu, SCHED_OTHER, 0)) ++failures;
        std::lock_guard lock(mutex);
        held = true;
        while (!hog_started.load()) std::this_thread::yield();
        work_for(std::chrono::milliseconds(20));  // preempted by the hog unless lent 20
    });
    while (!held.load()) std::this_thread::yield();

    std::thread hog([&] {
        if (!pin_and_schedule(cpu, SCHED_FIFO, 10)) ++failures;
        hog_started = true;
        const auto until = Clock::now() + std::chrono::milliseconds(400);
        while (Clock::now() < until) {
        }
        hog_done = true;
    });
    std::thread waiter([&] {
        while (!hog_started.load()) std::this_thread::yield();
        if (!pin_and_schedule(cpu, SCHED_FIFO, 20)) ++failures;
        std::lock_guard lock(mutex);
        outcome.hog_done_at_lock = hog_done.load();
    });
    waiter.join();
    hog.join();
    holder.join();
    outcome.staged = failures.load() == 0;
    return outcome;
}

TEST(PiMutex, LocksUnlocksAndWaitsWithConditionVariableAny) {
    PiMutex mutex;
    std::condition_variable_any ready;
    bool flag = false;
    EXPECT_TRUE(mutex.try_lock());
    mutex.unlock();
    std::thread setter([&] {
        std::lock_guard lock(mutex);
        flag = true;
        ready.notify_one();
    });
    {
        std::unique_lock lock(mutex);
        ready.wait(lock, [&] { return flag; });
        EXPECT_TRUE(flag);
    }
    setter.join();
    std::lock_guard lock(mutex);
    std::thread other([&] { EXPECT_FALSE(mutex.try_lock()); });
    other.join();
}

TEST(PiMutex, LendsItsHolderTheWaitersPriority) {
    if (!may_use_real_time()) GTEST_SKIP() << "no real-time priorities for this process";
    const Outcome outcome = stage_inversion<PiMutex>();
    ASSERT_TRUE(outcome.staged);
    EXPECT_FALSE(outcome.hog_done_at_lock)
        << "the waiter got the lock only after the hog stopped: no priority inheritance";
}

// The witness that the staging tells the two apart: a plain mutex inverts.
TEST(PiMutex, APlainMutexLeavesTheWaiterBehindTheHog) {
    if (!may_use_real_time()) GTEST_SKIP() << "no real-time priorities for this process";
    const Outcome outcome = stage_inversion<std::mutex>();
    ASSERT_TRUE(outcome.staged);
    EXPECT_TRUE(outcome.hog_done_at_lock)
        << "the waiter got a plain mutex before the hog stopped: the staging shows nothing";
}

}  // namespace
}  // namespace keel::tasking
