#include "core/fsm/heartbeat_monitor.hpp"

#include <gtest/gtest.h>

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
    int sends() {
        int count = 0;
        for (const auto& action : out.actions()) count += std::holds_alternative<act::Send>(action);
        return count;
    }
};

TEST_F(HeartbeatMonitorTest, SendsToEveryOtherProcessingNodeEachPeriod) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(sends(), 2);  // PN2, PN3 (not itself, not the storage node)
    EXPECT_EQ(m.next_boundary_ns(), P);
}

TEST_F(HeartbeatMonitorTest, DeclaresAfterMissLimitPeriods) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);  // the partial first period is not counted
    for (int k = 1; k <= 2; ++k) {
        for (NodeId n : {PN2, PN3}) m.receive_heartbeat(Heartbeat{n, 1, 1}, 1, 0, out);
        EXPECT_TRUE(m.period_boundary(k * P, 1, false, out).empty());
    }
    // ST1 never sent: it was missed in periods 1 and 2; the third makes it.
    for (NodeId n : {PN2, PN3}) m.receive_heartbeat(Heartbeat{n, 1, 1}, 1, 0, out);
    NodeSet declared = m.period_boundary(3 * P, 1, false, out);
    EXPECT_TRUE(declared.contains(ST1));
    EXPECT_EQ(declared.size(), 1);
    EXPECT_TRUE(m.failed().contains(ST1));
    EXPECT_FALSE(m.watched().contains(ST1));
}

TEST_F(HeartbeatMonitorTest, OneHeartbeatResetsTheCount) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    m.period_boundary(P, 1, false, out);
    m.period_boundary(2 * P, 1, false, out);
    EXPECT_EQ(m.missed(PN2), 2);
    m.receive_heartbeat(Heartbeat{PN2, 1, 1}, 1, 0, out);
    m.period_boundary(3 * P, 1, false, out);
    EXPECT_EQ(m.missed(PN2), 0);
    EXPECT_FALSE(m.failed().contains(PN2));
}

TEST_F(HeartbeatMonitorTest, RestartIsAFailure) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN2, 1, 1}, 1, 0, out), kNoNode);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN2, 1, 2}, 1, 0, out), PN2);
    EXPECT_TRUE(m.failed().contains(PN2));
}

TEST_F(HeartbeatMonitorTest, AnExcludedNodeSayingSoIsDeclaredAtOnce) {
    auto m = monitor();
    m.period_boundary(0, 1, false, out);
    EXPECT_EQ(m.receive_heartbeat(Heartbeat{PN3, 1, 1, true}, 1, 0, out), PN3);
    EXPECT_TRUE(m.failed().contains(PN3));
}

TEST_F(HeartbeatMonitorTest, NotMonitoringCountsNothing) {
    HeartbeatMonitor m(topology, PN1, 1, 0, Mutant::none);
    for (int k = 0; k < 10; ++k) EXPECT_TRUE(m.period_boundary(k * P, 1, false, out).empty());
    EXPECT_TRUE(m.failed().empty());
}

TEST_F(HeartbeatMonitorTest, ForgetRestartsTheCount) {
    auto m = monitor();
    for (int k = 0; k <= 3; ++k) m.period_boundary(k * P, 1, false, out);
    EXPECT_TRUE(m.failed().contains(PN2));
    m.forget(PN2);
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
    for (int k = 0; k <= 3; ++k) m.period_boundary(k * P, 1, false, out);
    bool declared = false;
    for (const auto& action : out.actions()) {
        if (const auto* trace = std::get_if<act::Trace>(&action)) {
            EXPECT_STREQ(trace->fsm, "heartbeat");
            if (std::string(trace->action) == "DeclareFailed") {
                declared = true;
                EXPECT_NE(trace->vars.find("\"missed\""), std::string::npos);
            }
        }
    }
    EXPECT_TRUE(declared);
}

}  // namespace
}  // namespace keel::fsm
