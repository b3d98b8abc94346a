#include "core/fsm/heartbeat_monitor.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "test_mission.hpp"

namespace keel::fsm {
namespace {

constexpr TimeNs P = 100 * kNanosecondsPerMillisecond;

class HeartbeatMonitorTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Outbox out{true};

    HeartbeatMonitor monitor(Mutant mutant = Mutant::none) {
        HeartbeatMonitor m(topology, PN1, 1, 0, mutant);
        NodeSet watched = topology.all_nodes();
        m.set_watch(true, watched);
        return m;
    }
    // One heartbeat from `node`: the monitor heard someone in the period (no self-suspicion).
    void hear(HeartbeatMonitor& m, NodeId node) { m.receive_heartbeat(Heartbeat{node, 1, 1, false, 0, {}}, 1, 0, out); }
    // Every other node is heard once, so the miss limit (not the start-up grace) applies.
    void hear_everyone(HeartbeatMonitor& m) {
        for (NodeId n : {PN2, PN3, ST1}) m.receive_heartbeat(Heartbeat{n, 1, 1, false, 0, {}}, 1, 0, out);
    }
    // The i-th message sent (traces skipped).
    const Message& sent(int index) {
        for (const auto& action : out.actions()) {
            if (const auto* send = std::get_if<act::Send>(&action); send != nullptr && index-- == 0) {
                return send->message;
            }
        }
        throw std::out_of_range("fewer messages sent");
    }
    int sends() {
        int count = 0;
        for (const auto& action : out.actions()) count += std::holds_alternative<act::Send>(action);
        return count;
    }
};

TEST_F(HeartbeatMonitorTest, SendsToEveryOtherProcessingNodeEachPeriod) {
    HeartbeatMonitor worker(topology, PN1, 1, 0, Mutant::none);  // not monitoring
    worker.period_boundary(0, 1, false, out);
    EXPECT_EQ(sends(), 2);  // PN2, PN3 (not itself, not the storage node)
    EXPECT_EQ(worker.next_boundary_ns(), P);
    out.actions().clear();
    // A monitor's heartbeat carries its acknowledgements, so it goes to every node.
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(sends(), 3);  // PN2, PN3, ST1
}

// The lease's acknowledgements (spec/Lease.tla): a monitor acknowledges the last heartbeat
// it heard from each node it watches, in its own heartbeats and at once in a reply; a
// node records the send time of its own heartbeat that was acknowledged.
TEST_F(HeartbeatMonitorTest, AcknowledgesTheLastHeartbeatHeardAndRepliesAtOnce) {
    auto m = monitor();
    m.receive_heartbeat(Heartbeat{PN2, 1, 1, false, 7, {}, false}, 1, 0, out);
    // The reply: to PN2 alone, acknowledging seq 7; a reply is never answered.
    ASSERT_EQ(sends(), 1);
    const auto& reply = std::get<Heartbeat>(sent(0));
    EXPECT_TRUE(reply.reply);
    ASSERT_EQ(reply.acks.size(), 1u);
    EXPECT_EQ(reply.acks[0], (HeartbeatAck{PN2, 1, 7}));
    m.receive_heartbeat(Heartbeat{PN3, 1, 1, false, 4, {}, true}, 1, 0, out);
    EXPECT_EQ(sends(), 1);
    out.actions().clear();
    // The periodic heartbeat acknowledges every node heard and not declared.
    m.period_boundary(0, 1, false, out);
    const auto& heartbeat = std::get<Heartbeat>(sent(0));
    EXPECT_EQ(heartbeat.seq, 1u);
    EXPECT_FALSE(heartbeat.reply);
    EXPECT_EQ(heartbeat.acks.size(), 2u);  // PN2 and PN3; ST1 never heard
}

TEST_F(HeartbeatMonitorTest, RecordsWhenItsOwnHeartbeatWasAcknowledged) {
    auto m = monitor();
    EXPECT_EQ(m.acked_at(PN2), HeartbeatMonitor::kNever);
    m.period_boundary(0, 1, false, out);       // seq 1, sent at 0
    m.period_boundary(P, 1, false, out);       // seq 2, sent at P
    m.receive_heartbeat(Heartbeat{PN2, 3, 1, false, 5, {HeartbeatAck{PN1, 1, 2}}, false}, 1, P + 5, out);
    EXPECT_EQ(m.acked_at(PN2), P);
    EXPECT_EQ(m.acked_epoch(PN2), 3u);
    // An older acknowledgement does not move it back; another incarnation's is ignored.
    m.receive_heartbeat(Heartbeat{PN2, 3, 1, false, 6, {HeartbeatAck{PN1, 1, 1}}, false}, 1, P + 6, out);
    m.receive_heartbeat(Heartbeat{PN3, 3, 1, false, 6, {HeartbeatAck{PN1, 2, 2}}, false}, 1, P + 7, out);
    EXPECT_EQ(m.acked_at(PN2), P);
    EXPECT_EQ(m.acked_at(PN3), HeartbeatMonitor::kNever);
    // A seq this node never sent acknowledges nothing.
    m.receive_heartbeat(Heartbeat{PN3, 3, 1, false, 7, {HeartbeatAck{PN1, 1, 9}}, false}, 1, P + 8, out);
    EXPECT_EQ(m.acked_at(PN3), HeartbeatMonitor::kNever);
}

TEST_F(HeartbeatMonitorTest, DeclaresAfterMissLimitPeriods) {
    auto m = monitor();
    hear_everyone(m);
    m.period_boundary(0, 1, false, out);  // the partial first period is not counted
    for (int k = 1; k <= 2; ++k) {
        for (NodeId n : {PN2, PN3}) m.receive_heartbeat(Heartbeat{n, 1, 1, false, 0, {}}, 1, 0, out);
        EXPECT_TRUE(m.period_boundary(k * P, 1, false, out).empty());
    }
    // ST1 never sent: it was missed in periods 1 and 2; the third makes it.
    for (NodeId n : {PN2, PN3}) m.receive_heartbeat(Heartbeat{n, 1, 1, false, 0, {}}, 1, 0, out);
    NodeSet declared = m.period_boundary(3 * P, 1, false, out);
    EXPECT_TRUE(declared.contains(ST1));
    EXPECT_EQ(declared.size(), 1);
    EXPECT_TRUE(m.failed().contains(ST1));
    EXPECT_FALSE(m.watched().contains(ST1));
}

TEST_F(HeartbeatMonitorTest, OneHeartbeatResetsTheCount) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    hear(m, PN3);
    m.period_boundary(P, 1, false, out);
    hear(m, PN3);
    m.period_boundary(2 * P, 1, false, out);
    EXPECT_EQ(m.missed(PN2), 2);
    m.receive_heartbeat(Heartbeat{PN2, 1, 1, false, 0, {}}, 1, 0, out);
    m.period_boundary(3 * P, 1, false, out);
    EXPECT_EQ(m.missed(PN2), 0);
    EXPECT_FALSE(m.failed().contains(PN2));
}

TEST_F(HeartbeatMonitorTest, RestartIsAFailure) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN2, 1, 1, false, 0, {}}, 1, 0, out), kNoNode);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN2, 1, 2, false, 0, {}}, 1, 0, out), PN2);
    EXPECT_TRUE(m.failed().contains(PN2));
}

TEST_F(HeartbeatMonitorTest, NodeFirstHeardAfterItRestartedIsAFailure) {
    // This monitor booted after PN2 had already restarted once.
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN3, 1, 1, false, 0, {}}, 1, 0, out), kNoNode);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN2, 1, 2, false, 0, {}}, 1, 0, out), PN2);
    EXPECT_TRUE(m.failed().contains(PN2));
    EXPECT_FALSE(m.forgettable(PN2));
}

// A heartbeat from PN2 of incarnation `incarnation`, boot `boot`, number `seq`.
Heartbeat of_boot(NodeId from, std::uint32_t incarnation, std::uint32_t boot, std::uint32_t seq,
                  bool waiting = false, std::uint32_t previous = 0) {
    Heartbeat heartbeat{from, 1, incarnation, false, seq, {}, false, boot, waiting, previous};
    return heartbeat;
}

TEST_F(HeartbeatMonitorTest, TheBootBeforeIsRetiredEvenUnheard) {
    // This monitor never heard PN2's boot 0xA: PN2's next boot 0xB names it as its
    // previous one, so a late heartbeat of 0xA is stale, not a newer boot (which would
    // retire the live 0xB and silence PN2 here).
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(of_boot(PN2, 2, 0xB, 1, true, 0xA), 1, 0, out), PN2);
    EXPECT_TRUE(m.retired_boot(of_boot(PN2, 1, 0xA, 90)));
    EXPECT_FALSE(m.retired_boot(of_boot(PN2, 2, 0xB, 2, true, 0xA)));
}

TEST_F(HeartbeatMonitorTest, ARestartWhoseIncarnationWentBackIsSeenByItsBoot) {
    // PN2's saved incarnation was lost: it boots again with the incarnation it had (1),
    // and later, readmitted, with one below the one heard (its state file restored from an
    // earlier boot). Each new boot is a restart, whatever its incarnation; the ignore_boot
    // mutant sees neither.
    for (const Mutant mutant : {Mutant::none, Mutant::ignore_boot}) {
        if (mutant != Mutant::none && !kMutantsCompiled) continue;
        const NodeId expected = mutant == Mutant::none ? PN2 : kNoNode;
        auto m = monitor(mutant);
        m.period_boundary(0, 1, false, out);
        EXPECT_EQ(m.receive_heartbeat(of_boot(PN2, 1, 0xA, 40), 1, 0, out), kNoNode);
        EXPECT_EQ(m.receive_heartbeat(of_boot(PN2, 1, 0xB, 1), 1, 0, out), expected) << to_string(mutant);
        EXPECT_EQ(m.failed().contains(PN2), mutant == Mutant::none) << to_string(mutant);
        if (mutant == Mutant::none) {
            EXPECT_FALSE(m.forgettable(PN2));
        }
        m.receive_heartbeat(of_boot(PN2, 2, 0xC, 1), 1, 0, out);  // a restart by its incarnation
        EXPECT_TRUE(m.failed().contains(PN2));
        m.readmit(PN2, 2, out);
        m.set_watch(true, topology.all_nodes());
        EXPECT_EQ(m.receive_heartbeat(of_boot(PN2, 1, 0xD, 1), 1, 0, out), expected) << to_string(mutant);
    }
}

TEST_F(HeartbeatMonitorTest, AReadmittedNodeStillOutInAnOlderEpochIsOutByItsOwnWordAfterAWhile) {
    // PN2 resigned and was excluded in epoch 1; the cluster readmitted it in epoch 4, which
    // PN2, deaf, never heard (keel-sim --loss 5%, prototype3 seed 9386): its heartbeats
    // still say it is excluded, in epoch 1. That is stale at first (a readmitted node says
    // `excluded` until it adopts the view), and its own word once it has said so for 3
    // miss_limit periods after the readmission.
    const int wait = 3 * topology.miss_limit();
    auto m = monitor();
    m.period_boundary(0, 4, false, out);
    m.readmit(PN2, 4, out);
    m.set_watch(true, topology.all_nodes());
    Heartbeat out_in_1{PN2, 1, 1, true, 0, {}};
    for (int k = 1; k < wait; ++k) {
        m.period_boundary(k * P, 4, false, out);
        out_in_1.seq = static_cast<std::uint32_t>(k);
        EXPECT_EQ(m.receive_heartbeat(out_in_1, 4, k * P + 1, out), kNoNode) << k;
    }
    EXPECT_FALSE(m.failed().contains(PN2));
    m.period_boundary(wait * P, 4, false, out);
    out_in_1.seq = static_cast<std::uint32_t>(wait);
    EXPECT_EQ(m.receive_heartbeat(out_in_1, 4, wait * P + 1, out), PN2);
    EXPECT_TRUE(m.failed().contains(PN2));

    // A node heard in the readmitting epoch has adopted it: a later heartbeat of epoch 1
    // that says excluded (sent before, delivered late) stays stale, however late.
    auto n = monitor();
    n.period_boundary(0, 4, false, out);
    n.readmit(PN2, 4, out);
    n.set_watch(true, topology.all_nodes());
    EXPECT_EQ(n.receive_heartbeat(Heartbeat{PN2, 4, 1, false, 1, {}}, 4, 1, out), kNoNode);
    for (int k = 1; k <= wait + 1; ++k) n.period_boundary(k * P, 4, false, out);
    EXPECT_EQ(n.receive_heartbeat(Heartbeat{PN2, 1, 1, true, 2, {}}, 4, (wait + 1) * P + 1, out), kNoNode);
    EXPECT_FALSE(n.failed().contains(PN2));
}

TEST_F(HeartbeatMonitorTest, AHeartbeatOfABootThatEndedIsDroppedUnheard) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    m.receive_heartbeat(of_boot(PN2, 1, 0xA, 7), 1, 0, out);
    EXPECT_EQ(m.receive_heartbeat(of_boot(PN2, 2, 0xB, 1), 1, 0, out), PN2);
    // Boot 0xA's last heartbeat, overtaken on the way by 0xB's first: stale.
    const Heartbeat stale = of_boot(PN2, 1, 0xA, 8);
    EXPECT_TRUE(m.retired_boot(stale));
    EXPECT_FALSE(m.retired_boot(of_boot(PN2, 2, 0xB, 2)));
    EXPECT_FALSE(m.retired_boot(of_boot(PN3, 1, 0xA, 8)));  // another node's boot
    m.period_boundary(P, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(stale, 1, P + 1, out), kNoNode);
    m.period_boundary(2 * P, 1, false, out);
    EXPECT_FALSE(m.heard_last_period().contains(PN2));
    // Only the boots heard end are retired: a third boot is a restart again.
    EXPECT_EQ(m.retired_boot(of_boot(PN2, 1, 0xC, 1)), false);
}

TEST_F(HeartbeatMonitorTest, ANodeFirstHeardWaitingForACommandRestarted) {
    // PN2 booted from a state file that went back to before its first boot (incarnation 1)
    // before this monitor ever heard it; it says it waits for a Command.
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(of_boot(PN3, 1, 0xC, 1), 1, 0, out), kNoNode);
    EXPECT_EQ(m.receive_heartbeat(of_boot(PN2, 1, 0xB, 1, true), 1, 0, out), PN2);
    EXPECT_FALSE(m.forgettable(PN2));
    // Once heard, the same boot saying it again is nothing new.
    out.actions().clear();
    EXPECT_EQ(m.receive_heartbeat(of_boot(PN2, 1, 0xB, 2, true), 1, 0, out), kNoNode);
}

// This monitor's heartbeats carry its boot and whether it waits for a Command.
TEST_F(HeartbeatMonitorTest, HeartbeatsCarryTheBootAndWaiting) {
    HeartbeatMonitor m(topology, PN1, 4, 0, Mutant::none, 0xBEEF);
    m.set_watch(true, topology.all_nodes());
    m.set_waiting(true);
    m.period_boundary(0, 1, false, out);
    const auto& heartbeat = std::get<Heartbeat>(sent(0));
    EXPECT_EQ(heartbeat.boot, 0xBEEFu);
    EXPECT_TRUE(heartbeat.waiting);
    EXPECT_EQ(heartbeat.incarnation, 4u);
}

TEST_F(HeartbeatMonitorTest, AnExcludedNodeSayingSoIsDeclaredAtOnce) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN3, 1, 1, true, 0, {}}, 1, 0, out), PN3);
    EXPECT_TRUE(m.failed().contains(PN3));
}

TEST_F(HeartbeatMonitorTest, NotMonitoringCountsNothing) {
    HeartbeatMonitor m(topology, PN1, 1, 0, Mutant::none);
    for (int k = 0; k < 10; ++k) EXPECT_TRUE(m.period_boundary(k * P, 1, false, out).empty());
    EXPECT_TRUE(m.failed().empty());
}

TEST_F(HeartbeatMonitorTest, ForgetRestartsTheCount) {
    auto m = monitor();
    hear_everyone(m);
    for (int k = 0; k <= 3; ++k) {
        hear(m, PN3);
        m.period_boundary(k * P, 1, false, out);
    }
    EXPECT_TRUE(m.failed().contains(PN2));
    m.forget(PN2, out);
    m.set_watch(true, topology.all_nodes());
    EXPECT_FALSE(m.failed().contains(PN2));
    EXPECT_EQ(m.missed(PN2), 0);
}

TEST_F(HeartbeatMonitorTest, MutantsMoveTheThreshold) {
    EXPECT_EQ(monitor(Mutant::declare_on_first_miss).declare_at(), 1);
    EXPECT_EQ(monitor(Mutant::late_declare).declare_at(), 6);
}

TEST_F(HeartbeatMonitorTest, TraceUsesSpecNames) {
    auto m = monitor();
    hear_everyone(m);
    for (int k = 0; k <= 3; ++k) {
        hear(m, PN3);
        m.period_boundary(k * P, 1, false, out);
    }
    bool declared = false;
    for (const auto& action : out.actions()) {
        if (const auto* trace = std::get_if<act::Trace>(&action)) {
            EXPECT_STREQ(trace->fsm, "heartbeat");
            if (std::string(trace->action) == "DeclareFailed") {
                declared = true;
                EXPECT_NE(trace->vars.find("\"missed\""), std::string::npos);
                EXPECT_NE(trace->vars.find("\"heardOnce\":[\"PN2\",\"PN3\",\"ST1\"]"),
                          std::string::npos)
                    << trace->vars;
            }
        }
    }
    EXPECT_TRUE(declared);
}

TEST_F(HeartbeatMonitorTest, NeverHeardNodeIsGivenTheStartupGrace) {
    auto m = monitor();
    const int grace = topology.startup_grace_periods();
    ASSERT_EQ(grace, 20);
    m.period_boundary(0, 1, false, out);
    // PN2 is heard once, then never again; PN3 every period; ST1 never.
    m.receive_heartbeat(Heartbeat{PN2, 1, 1, false, 0, {}}, 1, 0, out);
    for (int k = 1; k < grace; ++k) {
        m.receive_heartbeat(Heartbeat{PN3, 1, 1, false, 0, {}}, 1, 0, out);
        const NodeSet declared = m.period_boundary(k * P, 1, false, out);
        // Once heard, PN2 is counted with the miss limit: period 1 heard, 2..4 missed.
        EXPECT_EQ(declared.contains(PN2), k == 4) << "period " << k;
        EXPECT_FALSE(declared.contains(ST1)) << "period " << k;
    }
    EXPECT_EQ(m.missed(ST1), grace - 1);
    EXPECT_EQ(m.declare_after(ST1), grace);
    EXPECT_EQ(m.declare_after(PN3), topology.miss_limit());
    m.receive_heartbeat(Heartbeat{PN3, 1, 1, false, 0, {}}, 1, 0, out);
    const NodeSet declared = m.period_boundary(grace * P, 1, false, out);
    EXPECT_TRUE(declared.contains(ST1));
    EXPECT_EQ(declared.size(), 1);
}

TEST_F(HeartbeatMonitorTest, LateBootingNodeHeardWithinTheGraceIsNeverDeclared) {
    auto m = monitor();
    hear_everyone(m);  // PN2, ST1 heard; PN3 is the late one below
    HeartbeatMonitor fresh(topology, PN1, 1, 0, Mutant::none);
    fresh.set_watch(true, topology.all_nodes());
    for (int k = 0; k <= 15; ++k) {
        for (NodeId n : {PN2, ST1}) fresh.receive_heartbeat(Heartbeat{n, 1, 1, false, 0, {}}, 1, 0, out);
        if (k >= 5) fresh.receive_heartbeat(Heartbeat{PN3, 1, 1, false, 0, {}}, 1, 0, out);  // boots at 470 ms
        EXPECT_TRUE(fresh.period_boundary(k * P, 1, false, out).empty()) << "period " << k;
    }
    EXPECT_TRUE(fresh.heard_once().contains(PN3));
    EXPECT_EQ(fresh.missed(PN3), 0);
}

TEST_F(HeartbeatMonitorTest, WatchingLaterKeepsWhatWasHeardSinceBoot) {
    // A Worker hears heartbeats (every processing node gets them) before a view makes it a
    // monitor, e.g. an Observer's take-over: a node it heard is counted with the miss limit.
    HeartbeatMonitor m(topology, PN3, 1, 0, Mutant::none);
    m.period_boundary(0, 1, false, out);
    m.receive_heartbeat(Heartbeat{PN2, 1, 1, false, 0, {}}, 1, 0, out);
    m.period_boundary(P, 1, false, out);
    EXPECT_TRUE(m.heard_once().contains(PN2));
    m.set_watch(true, topology.all_nodes());
    EXPECT_EQ(m.declare_after(PN2), topology.miss_limit());
    EXPECT_EQ(m.declare_after(PN1), topology.startup_grace_periods());
    NodeSet declared;
    for (int k = 2; k <= 5; ++k) {
        hear(m, ST1);
        declared = declared | m.period_boundary(k * P, 1, false, out);
    }
    EXPECT_TRUE(declared.contains(PN2));
    EXPECT_FALSE(declared.contains(PN1));
}

TEST_F(HeartbeatMonitorTest, ForgetCountsAsHeard) {
    auto m = monitor();
    for (int k = 0; k <= topology.startup_grace_periods(); ++k) {
        hear(m, ST1);
        m.period_boundary(k * P, 1, false, out);
    }
    ASSERT_TRUE(m.failed().contains(PN2));
    EXPECT_FALSE(m.heard_once().contains(PN2));
    m.forget(PN2, out);  // a Command proved it alive
    EXPECT_TRUE(m.heard_once().contains(PN2));
    EXPECT_EQ(m.declare_after(PN2), topology.miss_limit());
}

TEST_F(HeartbeatMonitorTest, MutantWithoutStartupGrace) {
    auto m = monitor(Mutant::no_startup_grace);
    EXPECT_EQ(m.declare_after(PN2), topology.miss_limit());
    NodeSet declared;
    for (int k = 0; k <= 3; ++k) {
        hear(m, PN3);
        declared = declared | m.period_boundary(k * P, 1, false, out);
    }
    EXPECT_TRUE(declared.contains(PN2));
}

TEST_F(HeartbeatMonitorTest, SilentPeriodsCountNoMiss) {
    // A deaf monitor hears no one: it suspects itself, not the others (Exclusion.tla rule 1).
    auto m = monitor();
    hear_everyone(m);
    m.period_boundary(0, 1, false, out);
    for (int k = 1; k <= 10; ++k) EXPECT_TRUE(m.period_boundary(k * P, 1, false, out).empty());
    EXPECT_TRUE(m.failed().empty());
    EXPECT_EQ(m.missed(PN2), 0);
    EXPECT_EQ(m.self_suspected_periods(), 10u);
    bool suspect_line = false;
    for (const auto& action : out.actions()) {
        const auto* trace = std::get_if<act::Trace>(&action);
        if (trace != nullptr && std::string(trace->action) == "Tick" &&
            trace->args.find("\"suspect\":true") != std::string::npos &&
            trace->args.find("\"silent\":true") != std::string::npos) {
            suspect_line = true;
        }
    }
    EXPECT_TRUE(suspect_line);
}

TEST_F(HeartbeatMonitorTest, LateBoundaryCountsNoMissButHeardNodesReset) {
    // A starved monitor reaches its boundaries late: it counts no miss, yet a node it
    // heard restarts from zero.
    auto m = monitor();
    hear_everyone(m);
    m.period_boundary(0, 1, false, out);
    hear(m, PN3);
    m.period_boundary(P, 1, false, out);  // on time: PN2 and ST1 missed once
    ASSERT_EQ(m.missed(PN2), 1);
    for (int k = 2; k <= 8; ++k) {
        hear(m, PN3);
        hear(m, ST1);
        EXPECT_TRUE(m.period_boundary(k * P + 6 * P / 10, 1, false, out).empty()) << k;
    }
    EXPECT_EQ(m.missed(PN2), 1);
    EXPECT_EQ(m.missed(ST1), 0);
    EXPECT_EQ(m.self_suspected_periods(), 7u);
}

TEST_F(HeartbeatMonitorTest, MutantWithoutSelfSuspicionDeclaresWhenDeaf) {
    auto m = monitor(Mutant::no_self_suspicion);
    hear_everyone(m);
    NodeSet declared;
    for (int k = 0; k <= 3; ++k) declared = declared | m.period_boundary(k * P, 1, false, out);
    EXPECT_TRUE(declared.contains(PN2));
    EXPECT_EQ(m.self_suspected_periods(), 0u);
}

TEST_F(HeartbeatMonitorTest, AnotherMessageEndsTheGraceAndRestartsTheCount) {
    // PN3 acks the boot switch in period 5 (it booted late) but its first heartbeat is
    // lost: the ack proves it alive, so from then on the miss limit applies, counted from
    // zero (not from the 5 periods it was counted against the grace).
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    for (int k = 1; k <= 5; ++k) {
        for (NodeId n : {PN2, ST1}) m.receive_heartbeat(Heartbeat{n, 1, 1, false, 0, {}}, 1, 0, out);
        EXPECT_TRUE(m.period_boundary(k * P, 1, false, out).empty()) << "period " << k;
    }
    EXPECT_EQ(m.missed(PN3), 5);
    m.heard_from(PN3);
    EXPECT_TRUE(m.heard_once().contains(PN3));
    EXPECT_FALSE(m.heard().contains(PN3));  // not a heartbeat
    EXPECT_EQ(m.missed(PN3), 0);
    EXPECT_EQ(m.declare_after(PN3), topology.miss_limit());
    NodeSet declared;
    for (int k = 6; k <= 8; ++k) {
        for (NodeId n : {PN2, ST1}) m.receive_heartbeat(Heartbeat{n, 1, 1, false, 0, {}}, 1, 0, out);
        declared = m.period_boundary(k * P, 1, false, out);
        EXPECT_EQ(declared.contains(PN3), k == 8) << "period " << k;
    }
    // Only the first message resets the count; itself and unknown ids are ignored.
    m.heard_from(PN1);
    m.heard_from(200);
    EXPECT_FALSE(m.heard_once().contains(PN1));
}

}  // namespace
}  // namespace keel::fsm
