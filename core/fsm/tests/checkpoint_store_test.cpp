#include "core/fsm/checkpoint_store.hpp"

#include <gtest/gtest.h>

#include "core/fsm/codec.hpp"

#include "test_mission.hpp"

namespace keel::fsm {
namespace {

// The Storage node's own view at switch <<epoch, seq>> (receive_request reads no more).
View view_at(Epoch epoch, Seq seq) {
    View view;
    view.epoch = epoch;
    view.seq = seq;
    return view;
}

class CheckpointStoreTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    TaskId taskB = 1;
    Outbox out{false};
    CheckpointStore store{topology, ST1};

    std::vector<Message> sent() {
        std::vector<Message> result;
        for (const auto& action : out.actions()) {
            if (const auto* send = std::get_if<act::Send>(&action)) result.push_back(send->message);
        }
        return result;
    }
};

// A state of a newer lineage (opened by a start without the Storage node) replaces more
// steps of an abandoned one, and the abandoned lineage's later writes change nothing.
TEST_F(CheckpointStoreTest, ANewerLineageReplacesMoreStepsOfAnOlderOne) {
    EXPECT_TRUE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 107}, false, {107}}, out));
    EXPECT_TRUE(store.receive_write(
        CheckpointWrite{PN1, 1, taskB, {lineage_of(1, 3), 12}, true, {12}}, out));
    EXPECT_EQ(store.latest_version(taskB), (Version{lineage_of(1, 3), 12}));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 108}, false, {108}}, out));
    EXPECT_EQ(store.records()[0].state, std::vector<std::uint8_t>{12});
    // The final write's acknowledgement names the version now stored: PN1's own.
    EXPECT_EQ(std::get<CheckpointAck>(sent().back()).version, (Version{lineage_of(1, 3), 12}));
}

TEST_F(CheckpointStoreTest, KeepsTheLatestVersionOnly) {
    EXPECT_FALSE(store.latest_version(taskB));
    EXPECT_TRUE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 5}, false, {5}}, out));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 4}, false, {4}}, out));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 5}, false, {5}}, out));
    EXPECT_EQ(store.latest_version(taskB), (Version{0, 5}));
    EXPECT_TRUE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 6}, false, {6}}, out));
    EXPECT_EQ(store.records().size(), 1u);
    EXPECT_EQ(store.records()[0].state, std::vector<std::uint8_t>{6});
}

TEST_F(CheckpointStoreTest, AcknowledgesFinalWritesWithTheStoredVersion) {
    store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 8}, false, {8}}, out);
    store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 7}, true, {7}}, out);
    auto messages = sent();
    ASSERT_EQ(messages.size(), 1u);
    EXPECT_EQ(std::get<CheckpointAck>(messages[0]).version, (Version{0, 8}));
}

// Fault model 3: PN2, which the mission may place taskB on but whose view does not, writes
// a version far above the host's; the host's next write, in the view's epoch, replaces it.
// A write from another epoch does not, nor one over the state the host of the view before
// handed over (the honest hand-off), nor, of course, a node that is not the host.
TEST_F(CheckpointStoreTest, TheHostsWriteReplacesAForeignPin) {
    View view = topology.initial_view();
    store.set_view(view);
    const NodeId host = topology.host(view, taskB);
    const NodeId liar = host == PN2 ? PN1 : PN2;
    ASSERT_TRUE(topology.may_host(taskB).contains(liar));
    const Version pin{0, std::uint64_t{1} << 62};
    EXPECT_TRUE(store.receive_write(CheckpointWrite{liar, view.epoch, taskB, pin, false, {66}}, out));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{host, view.epoch + 1, taskB, {0, 9}, false, {9}}, out));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{ST1, view.epoch, taskB, {0, 9}, false, {9}}, out));
    EXPECT_EQ(store.overridden(), 0u);
    // A final write (a hand-off flushed) does not replace it: it may be older than another
    // node's hand-off (see AHandOffFlushedLateDoesNotReplaceANewerOne); its ack names the
    // version stored.
    EXPECT_FALSE(store.receive_write(CheckpointWrite{host, view.epoch, taskB, {0, 10}, true, {10}}, out));
    EXPECT_EQ(std::get<CheckpointAck>(sent().back()).version, pin);
    EXPECT_EQ(store.overridden(), 0u);
    EXPECT_TRUE(store.receive_write(CheckpointWrite{host, view.epoch, taskB, {0, 10}, false, {10}}, out));
    EXPECT_EQ(store.overridden(), 1u);
    EXPECT_EQ(store.latest_version(taskB), (Version{0, 10}));
    // The liar's next pin is replaced again by the host's next write.
    EXPECT_TRUE(store.receive_write(CheckpointWrite{liar, view.epoch, taskB, pin, false, {66}}, out));
    EXPECT_TRUE(store.receive_write(CheckpointWrite{host, view.epoch, taskB, {0, 11}, false, {11}}, out));
    EXPECT_EQ(store.overridden(), 2u);
    // The honest hand-off: the task moves to another node in the next view; a late write
    // of the old host with the same count or less does not replace the new host's.
    View next = view;
    next.seq += 1;
    for (ConfigId config = 0; config < topology.config_count(); ++config) {
        next.config = next.base = config;
        if (topology.phase_of(next) == topology.phase_of(view) && topology.host(next, taskB) != host &&
            topology.host(next, taskB) != kNoNode) {
            break;
        }
    }
    const NodeId new_host = topology.host(next, taskB);
    ASSERT_NE(new_host, host);
    store.set_view(next);
    EXPECT_TRUE(store.receive_write(CheckpointWrite{host, view.epoch, taskB, {0, 12}, true, {12}}, out));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{new_host, view.epoch, taskB, {0, 11}, false, {11}}, out));
    EXPECT_EQ(store.latest_version(taskB), (Version{0, 12}));
    EXPECT_EQ(store.overridden(), 2u);
}

// The honest case a final write must not override: with the Storage node excluded, taskB
// moved from X to Y, which opened a lineage, and then away from Y; the view readmitting
// the Storage node places taskB on X again, and X and Y both flush their hand-offs in it.
// Y's (the newer lineage) arrives first; X's older one, though X hosts taskB, changes
// nothing.
TEST_F(CheckpointStoreTest, AHandOffFlushedLateDoesNotReplaceANewerOne) {
    View view = topology.initial_view();
    view.epoch = 5;
    store.set_view(view);
    const NodeId x = topology.host(view, taskB);
    const NodeId y = x == PN2 ? PN1 : PN2;
    const Version newer{lineage_of(4, 2), 3};
    EXPECT_TRUE(store.receive_write(CheckpointWrite{y, view.epoch, taskB, newer, true, {3}}, out));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{x, view.epoch, taskB, {0, 40}, true, {40}}, out));
    EXPECT_EQ(store.latest_version(taskB), newer);
    EXPECT_EQ(store.overridden(), 0u);
}

// A pin read back from disk has no known writer: the host's next periodic write replaces it.
TEST_F(CheckpointStoreTest, APinReadBackFromDiskIsReplacedByTheHostsWrite) {
    store.restore({StoredCheckpoint{taskB, {0, std::uint64_t{1} << 62}, {66}}});
    const View view = topology.initial_view();
    store.set_view(view);
    const NodeId host = topology.host(view, taskB);
    EXPECT_TRUE(store.receive_write(CheckpointWrite{host, view.epoch, taskB, {0, 7}, false, {7}}, out));
    EXPECT_EQ(store.latest_version(taskB), (Version{0, 7}));
    EXPECT_EQ(store.overridden(), 1u);
}

TEST_F(CheckpointStoreTest, RefusesExcludedWriters) {
    NodeSet failed;
    failed.insert(PN3);
    View view = topology.initial_view();
    view.failed = failed;
    store.set_view(view);
    EXPECT_FALSE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 5}, true, {5}}, out));
    EXPECT_TRUE(sent().empty()) << "no ack either";
}

// No honest node writes a checkpoint of a task that is not checkpointed (taskA), or of a
// task the mission never places on it (ST1 runs nothing): refused, counted, not
// acknowledged. taskB is essential, so any node that may become Master may write it.
TEST_F(CheckpointStoreTest, RefusesWritesNoHonestNodeMakes) {
    const TaskId taskA = 0;
    EXPECT_FALSE(store.receive_write(CheckpointWrite{PN2, 1, taskA, {0, 5}, true, {5}}, out));
    EXPECT_FALSE(store.receive_write(CheckpointWrite{ST1, 1, taskB, {0, 5}, true, {5}}, out));
    EXPECT_EQ(store.refused_writes(), 2u);
    EXPECT_FALSE(store.latest_version(taskA));
    EXPECT_FALSE(store.latest_version(taskB));
    EXPECT_TRUE(sent().empty()) << "no ack either";
    // The witness: the nodes that may run taskB are heard.
    for (NodeId node : {PN1, PN2, PN3}) {
        EXPECT_TRUE(store.receive_write(
            CheckpointWrite{node, 1, taskB, {0, 6u + node}, false, {1}}, out));
    }
    EXPECT_EQ(store.refused_writes(), 2u);
}

// prototype3 with one phase, which never places taskA (not essential) on PN3, and taskA
// checkpointed.
Topology taskA_checkpointed_in_one_phase() {
    mission::Mission m = testing::prototype3();
    m.tasks[0].checkpoint = true;
    m.phases.resize(1);
    m.phases[0].on_phase.clear();
    return testing::topology_of(m);
}

// In a mission whose only phase never places checkpointed taskA on PN3 (and where taskA is
// not essential), PN3's write of it is refused; its hosts' are taken.
TEST(CheckpointStoreHosts, AWriteFromANodeTheMissionNeverPlacesTheTaskOnIsRefused) {
    const Topology topology = taskA_checkpointed_in_one_phase();
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    const TaskId taskA = 0;
    EXPECT_TRUE(topology.may_host(taskA).contains(PN1));
    EXPECT_TRUE(topology.may_host(taskA).contains(PN2));
    EXPECT_FALSE(topology.may_host(taskA).contains(PN3));
    Outbox out{false};
    CheckpointStore store{topology, ST1};
    EXPECT_FALSE(store.receive_write(CheckpointWrite{PN3, 1, taskA, {0, 9}, false, {9}}, out));
    EXPECT_EQ(store.refused_writes(), 1u);
    EXPECT_TRUE(store.receive_write(CheckpointWrite{PN2, 1, taskA, {0, 3}, false, {3}}, out));
    EXPECT_TRUE(store.receive_write(CheckpointWrite{PN1, 1, taskA, {0, 4}, false, {4}}, out));
    EXPECT_EQ(store.latest_version(taskA), (Version{0, 4}));
}

// Nor asks for it: a request from a node the mission never places the task on is refused
// and counted; a host's is answered.
TEST(CheckpointStoreHosts, ARequestFromANodeTheMissionNeverPlacesTheTaskOnIsRefused) {
    const Topology topology = taskA_checkpointed_in_one_phase();
    const NodeId PN2 = 1, PN3 = 2, ST1 = 3;
    const TaskId taskA = 0;
    Outbox out{false};
    CheckpointStore store{topology, ST1};
    store.receive_request(CheckpointRequest{PN3, 1, 1, taskA}, view_at(1, 1), 0, out);
    EXPECT_EQ(store.request_budget().refused(), 1u);
    EXPECT_TRUE(out.actions().empty());
    store.receive_request(CheckpointRequest{PN2, 1, 1, taskA}, view_at(1, 1), 0, out);
    EXPECT_EQ(store.request_budget().refused(), 1u);
    EXPECT_EQ(out.actions().size(), 1u);
}

// A state above the task's max_state_bytes (plus the snapshot header) is refused; one at
// the bound is stored.
TEST(CheckpointStoreHosts, AStateAboveTheTasksBoundIsRefused) {
    mission::Mission m = testing::prototype3();
    m.tasks[1].max_state_bytes = 24;
    const Topology topology = testing::topology_of(m);
    const NodeId PN3 = 2, ST1 = 3;
    const TaskId taskB = 1;
    Outbox out{false};
    CheckpointStore store{topology, ST1};
    const std::vector<std::uint8_t> at_bound(kSnapshotHeaderBytes + 24, 1);
    std::vector<std::uint8_t> above = at_bound;
    above.push_back(2);
    EXPECT_FALSE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 2}, true, above}, out));
    EXPECT_EQ(store.refused_writes(), 1u);
    EXPECT_TRUE(store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 1}, false, at_bound}, out));
    EXPECT_EQ(store.latest_version(taskB), (Version{0, 1}));
}

// Records kept under an earlier mission are restored only if this mission checkpoints the
// task and admits the state.
TEST(CheckpointStoreHosts, RestoreLeavesOutWhatThisMissionDoesNotAdmit) {
    mission::Mission m = testing::prototype3();
    m.tasks[1].max_state_bytes = 4;
    const Topology topology = testing::topology_of(m);
    CheckpointStore store{topology, 3};
    const std::vector<std::uint8_t> at_bound(kSnapshotHeaderBytes + 4, 1);
    std::vector<std::uint8_t> above = at_bound;
    above.push_back(2);
    store.restore({{0, {0, 9}, at_bound}, {1, {0, 8}, above}});
    EXPECT_FALSE(store.latest_version(0));  // taskA is not checkpointed
    EXPECT_FALSE(store.latest_version(1));  // above taskB's bound
    store.restore({{1, {0, 7}, at_bound}});
    EXPECT_EQ(store.latest_version(1), (Version{0, 7}));
}

TEST_F(CheckpointStoreTest, RepliesWithTheLatestOrNotFound) {
    const View view = view_at(1, 3);
    store.receive_request(CheckpointRequest{PN2, 1, 3, taskB}, view, 0, out);
    store.receive_write(CheckpointWrite{PN3, 1, taskB, {0, 5}, false, {5}}, out);
    // PN2 asks again (it retransmits each period while it waits).
    store.receive_request(CheckpointRequest{PN2, 1, 3, taskB}, view, topology.heartbeat_period_ns(), out);
    auto messages = sent();
    ASSERT_EQ(messages.size(), 2u);
    EXPECT_FALSE(std::get<CheckpointReply>(messages[0]).found);
    const auto& reply = std::get<CheckpointReply>(messages[1]);
    EXPECT_TRUE(reply.found);
    EXPECT_EQ(reply.version.count, 5u);
    EXPECT_EQ(reply.seq, 3u);
}

// A reply carries a whole state for a request of a few bytes. Per node and task, the first
// request of the store's own switch is answered at once; anything else (a repeat, a switch
// the store has not adopted, any key the requester invents) from a budget of 4 that
// refills one per half period.
TEST_F(CheckpointStoreTest, RequestsAreAnsweredOnceASwitchThenTwiceAPeriod) {
    const TimeNs half = topology.heartbeat_period_ns() / 2;
    View view = view_at(1, 3);
    auto replies = [&] { return sent().size(); };
    store.receive_request(CheckpointRequest{PN2, 1, 3, taskB}, view, 0, out);
    EXPECT_EQ(replies(), 1u);
    for (Seq seq = 3; seq < 200; ++seq) {  // a flood: the same switch, and invented ones
        store.receive_request(CheckpointRequest{PN2, 1, seq, taskB}, view, 1'000, out);
        store.receive_request(CheckpointRequest{PN2, 7, seq, taskB}, view, 1'000, out);
    }
    EXPECT_EQ(replies(), 5u);  // the budget
    EXPECT_EQ(store.request_budget().limited(), 390u);
    // Another node's request of the same task is its own: answered.
    store.receive_request(CheckpointRequest{PN1, 1, 3, taskB}, view, 1'000, out);
    EXPECT_EQ(replies(), 6u);
    // Half a period on, one more of PN2's is answered, not two.
    store.receive_request(CheckpointRequest{PN2, 1, 3, taskB}, view, half + 1'000, out);
    store.receive_request(CheckpointRequest{PN2, 1, 3, taskB}, view, half + 1'000, out);
    EXPECT_EQ(replies(), 7u);
    // The store adopts the next switch: PN2's first request of it is answered at once, a
    // second one is not (the budget is spent).
    view = view_at(1, 4);
    store.receive_request(CheckpointRequest{PN2, 1, 4, taskB}, view, half + 1'001, out);
    EXPECT_EQ(replies(), 8u);
    store.receive_request(CheckpointRequest{PN2, 1, 4, taskB}, view, half + 1'002, out);
    EXPECT_EQ(replies(), 8u);
}

// An honest node's requests fit the budget: the first of a switch, then (the lease held and
// released) the request to resume the task, and a retransmission a period later.
TEST_F(CheckpointStoreTest, AnHonestNodesRequestsAreAllAnswered) {
    const View view = view_at(1, 1);
    store.receive_request(CheckpointRequest{PN3, 1, 1, taskB}, view, 19'000'000, out);
    store.receive_request(CheckpointRequest{PN3, 1, 1, taskB}, view, 26'000'000, out);
    store.receive_request(CheckpointRequest{PN3, 1, 1, taskB}, view, 29'000'000, out);
    store.receive_request(CheckpointRequest{PN3, 1, 1, taskB}, view, 125'000'000, out);
    EXPECT_EQ(sent().size(), 4u);
    EXPECT_EQ(store.request_budget().limited(), 0u);
}

TEST_F(CheckpointStoreTest, RestoreKeepsMonotonicity) {
    store.restore({{taskB, {0, 9}, {9}}, {taskB, {0, 3}, {3}}});
    EXPECT_EQ(store.latest_version(taskB)->count, 9u);
}

}  // namespace
}  // namespace keel::fsm
