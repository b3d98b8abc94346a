#include "core/net/fault_transport.hpp"

#include <gtest/gtest.h>

#include <future>

#include "core/net/endpoint.hpp"
#include "core/net/loopback_transport.hpp"

namespace keel::net {
namespace {

using std::chrono::milliseconds;
using std::chrono::nanoseconds;

// A hand-driven clock: faults are a function of the seed and of these readings only.
struct FakeClock {
    nanoseconds now{0};
    Clock source() {
        return [this] { return now; };
    }
};

struct Pair {
    FakeClock clock;
    std::shared_ptr<FaultPlan> plan = std::make_shared<FaultPlan>();
    std::shared_ptr<LoopbackHub> hub = LoopbackHub::create(100000);
    std::unique_ptr<LoopbackTransport> sender = hub->attach(1);
    std::unique_ptr<FaultTransport> receiver;

    explicit Pair(FaultConfig config) {
        config.plan = plan;
        config.clock = clock.source();
        receiver = std::make_unique<FaultTransport>(hub->attach(2), config);
    }

    void send(Sequence sequence, NodeAddress destination = 2) {
        Envelope envelope;
        envelope.kind = MessageKind::unreliable_data;
        envelope.source = 1;
        envelope.destination = destination;
        envelope.sequence = sequence;
        ASSERT_EQ(sender->send(envelope), SendResult::sent);
    }

    std::vector<Sequence> receive() {
        std::vector<Inbound> items;
        receiver->receive(items, 100000);
        std::vector<Sequence> sequences;
        for (const Inbound& item : items) sequences.push_back(item.envelope.sequence);
        return sequences;
    }
};

std::vector<Sequence> run(std::uint64_t seed) {
    Pair pair(FaultConfig{.seed = seed,
                          .loss_probability = 0.2,
                          .duplicate_probability = 0.1,
                          .delay_min = milliseconds(1),
                          .delay_max = milliseconds(20)});
    std::vector<Sequence> delivered;
    for (Sequence sequence = 0; sequence < 500; ++sequence) {
        pair.send(sequence);
        pair.clock.now += milliseconds(1);
        for (Sequence got : pair.receive()) delivered.push_back(got);
    }
    pair.clock.now += milliseconds(100);
    for (Sequence got : pair.receive()) delivered.push_back(got);
    return delivered;
}

TEST(FaultTransport, SameSeedSameDeliveries) {
    const auto first = run(7);
    EXPECT_EQ(first, run(7));
    EXPECT_NE(first, run(8));
}

TEST(FaultTransport, LossDuplicationAndDelayHappenAtTheConfiguredRates) {
    Pair pair(FaultConfig{.seed = 11,
                          .loss_probability = 0.25,
                          .duplicate_probability = 0.10,
                          .delay_min = milliseconds(5),
                          .delay_max = milliseconds(5)});
    for (Sequence sequence = 0; sequence < 4000; ++sequence) pair.send(sequence);
    EXPECT_TRUE(pair.receive().empty()) << "nothing is due before the delay";
    EXPECT_EQ(pair.receiver->held(), 4000 - pair.receiver->counters().fault_lost +
                                         pair.receiver->counters().fault_duplicated);
    pair.clock.now += milliseconds(5);
    const auto delivered = pair.receive();
    const TransportCounters counters = pair.receiver->counters();
    EXPECT_NEAR(static_cast<double>(counters.fault_lost), 1000.0, 120.0);
    EXPECT_NEAR(static_cast<double>(counters.fault_duplicated), 300.0, 80.0);
    EXPECT_EQ(delivered.size(), 4000 - counters.fault_lost + counters.fault_duplicated);
    EXPECT_TRUE(std::is_sorted(delivered.begin(), delivered.end()))
        << "equal delays keep arrival order";
}

TEST(FaultTransport, DelayedMessagesWaitForTheClock) {
    Pair pair(FaultConfig{.seed = 3, .delay_min = milliseconds(10), .delay_max = milliseconds(10)});
    pair.send(1);
    EXPECT_TRUE(pair.receive().empty());
    pair.clock.now = milliseconds(9);
    EXPECT_TRUE(pair.receive().empty());
    EXPECT_TRUE(pair.receiver->wait(nanoseconds(0))) << "a held message is pending";
    pair.clock.now = milliseconds(10);
    EXPECT_EQ(pair.receive(), std::vector<Sequence>{1});
    EXPECT_EQ(pair.receiver->counters().fault_delayed, 1u);
}

TEST(FaultTransport, OneWayPartitionBlocksOnlyThatDirection) {
    Pair pair(FaultConfig{});
    auto third = pair.hub->attach(3);
    pair.plan->block(1, 2);
    EXPECT_TRUE(pair.plan->blocked(1, 2));
    EXPECT_FALSE(pair.plan->blocked(2, 1));
    pair.send(1);
    Envelope from_third;
    from_third.source = 3;
    from_third.destination = 2;
    from_third.sequence = 30;
    ASSERT_EQ(third->send(from_third), SendResult::sent);
    EXPECT_EQ(pair.receive(), std::vector<Sequence>{30}) << "only 1 -> 2 is blocked";
    EXPECT_EQ(pair.receiver->counters().fault_partitioned, 1u);
    pair.plan->unblock(1, 2);
    pair.send(2);
    EXPECT_EQ(pair.receive(), std::vector<Sequence>{2});
}

TEST(FaultTransport, SymmetricPartitionBlocksBothWaysUntilHealed) {
    FakeClock clock;
    auto plan = std::make_shared<FaultPlan>();
    auto hub = LoopbackHub::create();
    const FilterConfig filter{.known_nodes = {1, 2, 3}};
    auto wrap = [&](NodeAddress address) {
        return std::make_unique<FaultTransport>(
            hub->attach(address), FaultConfig{.plan = plan, .clock = clock.source()});
    };
    Endpoint a(wrap(1), filter), b(wrap(2), filter), c(wrap(3), filter);
    plan->partition({1}, {2, 3});
    auto broadcast_from = [](Endpoint& endpoint) {
        endpoint.send(endpoint.make_envelope(MessageKind::heartbeat, broadcast_address, 0, {}));
    };
    auto count = [](Endpoint& endpoint) {
        return endpoint.poll([](Envelope&&) {});
    };
    broadcast_from(a);
    broadcast_from(b);
    EXPECT_EQ(count(a), 0u);
    EXPECT_EQ(count(b), 0u);
    EXPECT_EQ(count(c), 1u) << "2 and 3 are on the same side";
    EXPECT_EQ(a.counters().fault_partitioned, 1u);
    plan->heal();
    broadcast_from(a);
    EXPECT_EQ(count(b), 1u);
    EXPECT_EQ(count(c), 1u);
}

TEST(FaultTransport, RejectsNonsenseConfiguration) {
    auto hub = LoopbackHub::create();
    EXPECT_THROW(FaultTransport(hub->attach(1), FaultConfig{.loss_probability = 1.5}),
                 std::invalid_argument);
    EXPECT_THROW(FaultTransport(hub->attach(2), FaultConfig{.delay_min = milliseconds(2),
                                                            .delay_max = milliseconds(1)}),
                 std::invalid_argument);
}

TEST(FaultTransport, MalformedItemsPassThroughToTheFilter) {
    FakeClock clock;
    auto hub = LoopbackHub::create();
    auto sender = hub->attach(1);
    Endpoint endpoint(std::make_unique<FaultTransport>(
                          hub->attach(2), FaultConfig{.seed = 1,
                                                      .loss_probability = 1.0,
                                                      .clock = clock.source()}),
                      FilterConfig{.known_nodes = {1, 2}});
    hub->inject_frame(2, {1, 2, 3});
    EXPECT_EQ(endpoint.poll([](Envelope&&) {}), 0u);
    EXPECT_EQ(endpoint.counters().dropped_malformed, 1u);
}

TEST(FaultTransport, ForwardsWakeToTheWrappedTransport) {
    Pair pair(FaultConfig{});
    auto waiting = std::async(std::launch::async, [&] {
        return pair.receiver->wait(std::chrono::seconds(60));
    });
    pair.receiver->wake();
    ASSERT_EQ(waiting.wait_for(std::chrono::seconds(30)), std::future_status::ready)
        << "wait() did not return after wake()";
    EXPECT_TRUE(waiting.get());
}

}  // namespace
}  // namespace keel::net
