#include "core/net/endpoint.hpp"

#include <gtest/gtest.h>

#include <future>

#include "core/net/loopback_transport.hpp"

namespace keel::net {
namespace {

struct Cluster {
    std::shared_ptr<LoopbackHub> hub = LoopbackHub::create(64, EnvelopeLimits{1024});
    FilterConfig config{.known_nodes = {1, 2, 3}, .limits = EnvelopeLimits{1024}};
    Endpoint node1{hub->attach(1), config};
    Endpoint node2{hub->attach(2), config};

    std::vector<Envelope> drain(Endpoint& endpoint) {
        std::vector<Envelope> got;
        endpoint.poll([&](Envelope&& envelope) { got.push_back(std::move(envelope)); });
        return got;
    }
};

TEST(Endpoint, DeliversUnicastAndBroadcastInOrder) {
    Cluster cluster;
    for (MessageKind kind : all_message_kinds) {
        ASSERT_EQ(cluster.node1.send(cluster.node1.make_envelope(kind, 2, 7, {1, 2, 3})),
                  SendResult::sent);
    }
    ASSERT_EQ(cluster.node1.send(cluster.node1.make_envelope(MessageKind::heartbeat,
                                                             broadcast_address, 0, {})),
              SendResult::sent);
    ASSERT_TRUE(cluster.node2.wait(std::chrono::milliseconds(0)));
    const auto got = cluster.drain(cluster.node2);
    ASSERT_EQ(got.size(), std::size(all_message_kinds) + 1);
    for (std::size_t i = 0; i < std::size(all_message_kinds); ++i) {
        EXPECT_EQ(got[i].kind, all_message_kinds[i]);
        EXPECT_EQ(got[i].source, 1);
        EXPECT_EQ(got[i].port, 7);
        EXPECT_EQ(got[i].sequence, i + 1);
        EXPECT_EQ(got[i].payload, (std::vector<std::uint8_t>{1, 2, 3}));
    }
    EXPECT_EQ(got.back().destination, broadcast_address);
    EXPECT_TRUE(cluster.drain(cluster.node1).empty()) << "a broadcast does not return to its sender";
    EXPECT_EQ(cluster.node2.counters().received, std::size(all_message_kinds) + 1);
    EXPECT_EQ(cluster.node1.counters().sent, std::size(all_message_kinds) + 1);
}

TEST(Endpoint, UnknownSenderIsCountedAndDropped) {
    Cluster cluster;
    Endpoint stranger{cluster.hub->attach(9), cluster.config};
    ASSERT_EQ(stranger.send(stranger.make_envelope(MessageKind::reconfiguration_command, 2, 1, {})),
              SendResult::sent);
    EXPECT_TRUE(cluster.drain(cluster.node2).empty());
    EXPECT_EQ(cluster.node2.counters().dropped_unknown_sender, 1u);
    EXPECT_EQ(cluster.node2.counters().received, 0u);

    cluster.node2.set_known_nodes({1, 2, 3, 9});
    stranger.send(stranger.make_envelope(MessageKind::reconfiguration_command, 2, 1, {}));
    EXPECT_EQ(cluster.drain(cluster.node2).size(), 1u);
}

TEST(Endpoint, StaleEpochIsCountedAndDropped) {
    Cluster cluster;
    cluster.node1.set_local_epoch(4);
    cluster.node2.set_epoch_floor(5);
    cluster.node1.send(cluster.node1.make_envelope(MessageKind::reconfiguration_command, 2, 0, {}));
    EXPECT_TRUE(cluster.drain(cluster.node2).empty());
    EXPECT_EQ(cluster.node2.counters().dropped_stale_epoch, 1u);

    cluster.node1.set_local_epoch(5);
    cluster.node1.send(cluster.node1.make_envelope(MessageKind::reconfiguration_command, 2, 0, {}));
    cluster.node1.set_local_epoch(6);
    cluster.node1.send(cluster.node1.make_envelope(MessageKind::reconfiguration_command, 2, 0, {}));
    const auto got = cluster.drain(cluster.node2);
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0].epoch, 5u);
    EXPECT_EQ(got[1].epoch, 6u);
    EXPECT_EQ(cluster.node2.counters().dropped_stale_epoch, 1u);
}

TEST(Endpoint, HeartbeatsAreNeverStale) {
    Cluster cluster;
    cluster.node1.set_local_epoch(2);
    cluster.node2.set_epoch_floor(5);
    cluster.node1.send(cluster.node1.make_envelope(MessageKind::heartbeat, 2, 0, {}));
    EXPECT_EQ(cluster.drain(cluster.node2).size(), 1u);
    EXPECT_EQ(cluster.node2.counters().dropped_stale_epoch, 0u);
}

TEST(Endpoint, MalformedAndOversizedFramesAreCountedAndDropped) {
    Cluster cluster;
    cluster.hub->inject_frame(2, {0x23, 1, 2});  // truncated header
    std::vector<std::uint8_t> bad_kind =
        encode(cluster.node1.make_envelope(MessageKind::request, 2, 1, {}));
    bad_kind[0] = static_cast<std::uint8_t>((envelope_version << 4) | 0x0F);
    cluster.hub->inject_frame(2, bad_kind);
    Envelope big = cluster.node1.make_envelope(MessageKind::large, 2, 1, {});
    big.payload.resize(2048);
    cluster.hub->inject_frame(2, encode(big));
    cluster.node1.send(cluster.node1.make_envelope(MessageKind::request, 2, 1, {42}));

    const auto got = cluster.drain(cluster.node2);
    ASSERT_EQ(got.size(), 1u) << "the good message after the bad ones still arrives";
    EXPECT_EQ(got[0].payload, std::vector<std::uint8_t>{42});
    const TransportCounters counters = cluster.node2.counters();
    EXPECT_EQ(counters.dropped_malformed, 2u);
    EXPECT_EQ(counters.dropped_oversized, 1u);
    EXPECT_EQ(counters.received, 1u);
}

TEST(Endpoint, RefusesToSendWhatCannotTravel) {
    Cluster cluster;
    Envelope big = cluster.node1.make_envelope(MessageKind::large, 2, 1, {});
    big.payload.resize(1025);
    EXPECT_EQ(cluster.node1.send(big), SendResult::rejected_oversized);
    Envelope forged = cluster.node1.make_envelope(MessageKind::request, 2, 1, {});
    forged.source = 3;
    EXPECT_EQ(cluster.node1.send(forged), SendResult::rejected_invalid);
    Envelope future = cluster.node1.make_envelope(MessageKind::request, 2, 1, {});
    future.epoch = max_epoch + 1;
    EXPECT_EQ(cluster.node1.send(future), SendResult::rejected_invalid);
    EXPECT_EQ(cluster.node1.counters().send_failed, 3u);
    EXPECT_EQ(cluster.node1.counters().sent, 0u);
    EXPECT_TRUE(cluster.drain(cluster.node2).empty());
}

TEST(Endpoint, MessagesForOtherNodesAreIgnoredNotCountedAsErrors) {
    Cluster cluster;
    cluster.hub->inject_frame(
        2, encode(cluster.node1.make_envelope(MessageKind::unreliable_data, 3, 1, {})));
    EXPECT_TRUE(cluster.drain(cluster.node2).empty());
    const TransportCounters counters = cluster.node2.counters();
    EXPECT_EQ(counters.ignored_not_addressed, 1u);
    EXPECT_EQ(counters.dropped_malformed + counters.dropped_unknown_sender, 0u);
}

TEST(Endpoint, FullInboxMakesSendFail) {
    Cluster cluster;
    std::size_t sent = 0;
    for (int i = 0; i < 100; ++i) {
        if (cluster.node1.send(cluster.node1.make_envelope(MessageKind::reliable_data, 2, 1, {})) ==
            SendResult::sent) {
            ++sent;
        }
    }
    EXPECT_EQ(sent, 64u);
    EXPECT_EQ(cluster.node1.counters().send_failed, 36u);
}

TEST(Endpoint, PollTakesAtMostTheRequestedNumber) {
    Cluster cluster;
    for (int i = 0; i < 10; ++i) {
        cluster.node1.send(cluster.node1.make_envelope(MessageKind::reliable_data, 2, 1, {}));
    }
    std::size_t seen = 0;
    EXPECT_EQ(cluster.node2.poll([&](Envelope&&) { ++seen; }, 4), 4u);
    EXPECT_EQ(cluster.node2.poll([&](Envelope&&) { ++seen; }, 100), 6u);
    EXPECT_EQ(seen, 10u);
}

TEST(Endpoint, NodeStateIsPublishedToTheHub) {
    Cluster cluster;
    const NodeState state{.node = 1,
                          .name = "PN1",
                          .role = Role::master,
                          .epoch = 3,
                          .configuration_id = 2,
                          .configuration = "C2",
                          .phase = "observation"};
    cluster.node1.publish_node_state(state);
    EXPECT_EQ(cluster.hub->node_states().at(1), state);
}

TEST(LoopbackHub, RejectsDuplicateAndBroadcastAddresses) {
    auto hub = LoopbackHub::create();
    auto first = hub->attach(1);
    EXPECT_THROW(hub->attach(1), std::invalid_argument);
    EXPECT_THROW(hub->attach(broadcast_address), std::invalid_argument);
    first.reset();
    EXPECT_NO_THROW(hub->attach(1));
}

// wake() ends a wait from another thread: the loop sees control commands at once. The
// waits below have a minute's timeout; the test only checks that they end well before.
TEST(Endpoint, WakeEndsAWaitFromAnotherThreadAndIsConsumed) {
    Cluster cluster;
    auto waiting = std::async(std::launch::async, [&] {
        return cluster.node2.wait(std::chrono::seconds(60));
    });
    cluster.node2.wake();
    ASSERT_EQ(waiting.wait_for(std::chrono::seconds(30)), std::future_status::ready)
        << "wait() did not return after wake()";
    EXPECT_TRUE(waiting.get());
    EXPECT_FALSE(cluster.node2.wait(std::chrono::milliseconds(0)))
        << "one wake-up ends one wait";
    EXPECT_TRUE(cluster.drain(cluster.node2).empty());

    // A wake-up given while no wait is under way ends the next one; other nodes sleep on.
    cluster.node2.wake();
    EXPECT_FALSE(cluster.node1.wait(std::chrono::milliseconds(0)));
    auto next = std::async(std::launch::async, [&] {
        return cluster.node2.wait(std::chrono::seconds(60));
    });
    ASSERT_EQ(next.wait_for(std::chrono::seconds(30)), std::future_status::ready);
    EXPECT_TRUE(next.get());
}

}  // namespace
}  // namespace keel::net
