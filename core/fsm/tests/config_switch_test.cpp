#include "core/fsm/config_switch.hpp"

#include <gtest/gtest.h>

#include "core/fsm/admission.hpp"
#include "test_mission.hpp"

namespace keel::fsm {
namespace {

class ConfigSwitchTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    TaskId taskA = 0, taskB = 1;
    View initial = topology.initial_view();
    Outbox out{true};

    // The initial Master's boot switch: the initial configuration at seq 1.
    View boot_switch() {
        View view = initial;
        view.seq = 1;
        return view;
    }
    // `n`'s Prepared for `view` (rule 4: with the view's digest).
    static Ack prepared(NodeId n, const View& view) {
        return Ack{n, view.epoch, view.seq, AckKind::Prepared, view_digest(view)};
    }
    // Every member's Prepared for `node`'s view (its own is ignored), then its Master's
    // Activate: the node starts its new tasks.
    void activate(ConfigSwitch& node, Epoch epoch = 1) {
        const View view = node.view();
        topology.all_nodes().minus(view.failed).for_each(
            [&](NodeId n) { node.receive_prepared(prepared(n, view), out); });
        node.receive_activate(ActivateCommand{view.master, view.epoch, view.seq}, epoch, out);
    }
    // Runs the boot switch on a participant: afterwards it runs its initial tasks.
    void boot(ConfigSwitch& node) {
        ASSERT_TRUE(node.receive_command(Command{PN1, boot_switch()}, 1, out));
        activate(node);
        const TaskSet restoring = node.restoring();  // the replies change it
        restoring.for_each([&](TaskId task) {
            node.receive_checkpoint_reply(CheckpointReply{ST1, 1, 1, task, false, {0, 0}, {}}, 1, out);
        });
        ASSERT_EQ(node.stage(), Stage::Stable);
    }
    // Configuration `name` in switch <<epoch, seq>>, without the nodes `failed`.
    View view_of(const char* name, Epoch epoch, Seq seq, std::initializer_list<NodeId> failed) {
        View view = initial;
        view.epoch = epoch;
        view.seq = seq;
        view.config = *topology.config_id(name);
        view.base = view.config;
        for (NodeId node : failed) view.failed.insert(node);
        return view;
    }
    View science() {
        const View view = view_of("S1", 1, 2, {});
        return view;
    }
    template <typename T>
    std::vector<T> sent() {
        std::vector<T> result;
        for (const auto& action : out.actions()) {
            if (const auto* send = std::get_if<act::Send>(&action)) {
                if (const auto* message = std::get_if<T>(&send->message)) result.push_back(*message);
            }
        }
        return result;
    }
    template <typename T>
    int count() {
        int n = 0;
        for (const auto& action : out.actions()) n += std::holds_alternative<T>(action);
        return n;
    }
};

TEST_F(ConfigSwitchTest, FirstBootRunsNothingUntilTheBootSwitchActivates) {
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    node.boot_activate_mutant(out);
    EXPECT_TRUE(node.active().empty());
    EXPECT_EQ(count<act::Activate>(), 0);
    EXPECT_EQ(node.stage(), Stage::Stable);
    EXPECT_EQ(node.view().seq, 0u);
    ASSERT_TRUE(node.receive_command(Command{PN1, boot_switch()}, 1, out));
    // Nothing to deactivate: Prepared at once, and still nothing runs.
    EXPECT_EQ(node.stage(), Stage::Prepared);
    EXPECT_TRUE(node.active().empty());
    ASSERT_EQ(sent<Ack>().size(), 3u);  // to every other member (rule 4)
    EXPECT_EQ(sent<Ack>()[0].kind, AckKind::Prepared);
    activate(node);
    // taskB is checkpointed: it starts from the Storage node's latest (none: version 0).
    ASSERT_EQ(sent<CheckpointRequest>().size(), 1u);
    EXPECT_TRUE(node.active().empty());
    node.receive_checkpoint_reply(CheckpointReply{ST1, 1, 1, taskB, false, {0, 0}, {}}, 1, out);
    EXPECT_TRUE(node.active().contains(taskB));
    EXPECT_EQ(count<act::Activate>(), 1);
    EXPECT_EQ(node.stage(), Stage::Stable);
    EXPECT_EQ(sent<Ack>().back().kind, AckKind::Activated);
}

TEST_F(ConfigSwitchTest, BootSwitchResumesCheckpointsTheStorageNodeKept) {
    // A whole-cluster power cycle whose Storage node kept its checkpoints.
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    boot(node);
    out.actions().clear();
    ConfigSwitch again(topology, PN3, initial, false, Mutant::none);
    again.receive_command(Command{PN1, boot_switch()}, 1, out);
    activate(again);
    again.receive_checkpoint_reply(CheckpointReply{ST1, 1, 1, taskB, true, {0, 42}, {42}}, 1, out);
    EXPECT_EQ(again.version(taskB), (Version{0, 42}));
}

TEST_F(ConfigSwitchTest, ARestartedNodeDoesNotAckAnActivateOfItsSavedView) {
    // PN3 prepared the boot switch and went down before its Activate (earth-observation
    // seed 24, on the Storage node): restarted with that view saved, it runs nothing, and
    // an Activated ack would tell the Master the view's tasks run here.
    ConfigSwitch node(topology, PN3, boot_switch(), true, Mutant::none);
    ASSERT_EQ(node.stage(), Stage::Stable);
    out.actions().clear();
    node.receive_activate(ActivateCommand{PN1, 1, 1}, 1, out);
    EXPECT_TRUE(sent<Ack>().empty());
    EXPECT_TRUE(node.active().empty());
    // Once it ran the switch itself, a duplicate Activate is acked again (the Master
    // missed the ack).
    ConfigSwitch booted(topology, PN3, initial, false, Mutant::none);
    boot(booted);
    out.actions().clear();
    booted.receive_activate(ActivateCommand{PN1, 1, 1}, 1, out);
    ASSERT_FALSE(sent<Ack>().empty());
    for (const Ack& ack : sent<Ack>()) EXPECT_EQ(ack.kind, AckKind::Activated);
}

TEST_F(ConfigSwitchTest, MutantActivatesAtBootWithoutCommand) {
    ConfigSwitch node(topology, PN3, initial, false, Mutant::boot_activates);
    node.boot_activate_mutant(out);
    EXPECT_TRUE(node.active().contains(taskB));
    EXPECT_EQ(node.version(taskB).count, 0u);
}

TEST_F(ConfigSwitchTest, ResignDeactivatesAndFlushesEverything) {
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    boot(node);
    node.task_stepped(taskB, {3}, 1, out);
    out.actions().clear();
    node.resign(out);
    EXPECT_TRUE(node.active().empty());
    EXPECT_EQ(count<act::Deactivate>(), 1);
    EXPECT_TRUE(node.unflushed().contains(taskB));
    ASSERT_EQ(sent<CheckpointWrite>().size(), 1u);
    EXPECT_TRUE(sent<CheckpointWrite>()[0].final);
    EXPECT_EQ(sent<CheckpointWrite>()[0].version.count, 1u);
    EXPECT_TRUE(sent<Ack>().empty());
    out.actions().clear();
    node.tick(1, out);  // retransmitted until acked
    EXPECT_EQ(sent<CheckpointWrite>().size(), 1u);
    node.receive_checkpoint_ack(CheckpointAck{ST1, 1, taskB, {0, 1}}, out);
    EXPECT_TRUE(node.unflushed().empty());
    EXPECT_EQ(node.stage(), Stage::Stable);
    EXPECT_TRUE(sent<Ack>().empty()) << "a resigning node acks no switch";
}

TEST_F(ConfigSwitchTest, LeavingCheckpointedTaskIsFlushedBeforePrepared) {
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    boot(node);
    node.task_stepped(taskB, {7}, 1, out);
    EXPECT_EQ(node.version(taskB).count, 1u);
    out.actions().clear();
    ASSERT_TRUE(node.receive_command(Command{PN1, science()}, 1, out));
    // In S1 taskB moves to PN2 and taskA arrives on PN3.
    EXPECT_FALSE(node.active().contains(taskB));
    EXPECT_EQ(node.stage(), Stage::Deactivating);
    EXPECT_TRUE(node.unflushed().contains(taskB));
    auto writes = sent<CheckpointWrite>();
    ASSERT_FALSE(writes.empty());
    EXPECT_TRUE(writes.back().final);
    EXPECT_EQ(writes.back().version.count, 1u);
    EXPECT_TRUE(sent<Ack>().empty());
    node.receive_checkpoint_ack(CheckpointAck{ST1, 1, taskB, {0, 1}}, out);
    EXPECT_EQ(node.stage(), Stage::Prepared);
    ASSERT_EQ(sent<Ack>().size(), 3u);  // to every other member (rule 4)
    EXPECT_EQ(sent<Ack>()[0].kind, AckKind::Prepared);
    // Activate: taskA is not checkpointed, it starts at once.
    activate(node);
    EXPECT_TRUE(node.active().contains(taskA));
    EXPECT_EQ(node.stage(), Stage::Stable);
    EXPECT_EQ(sent<Ack>().back().kind, AckKind::Activated);
}

TEST_F(ConfigSwitchTest, ArrivingCheckpointedTaskResumesFromStorage) {
    ConfigSwitch node(topology, PN2, initial, false, Mutant::none);
    boot(node);
    out.actions().clear();
    node.receive_command(Command{PN1, science()}, 1, out);
    EXPECT_EQ(node.stage(), Stage::Prepared);  // taskA leaves, nothing to flush
    activate(node);
    EXPECT_EQ(node.stage(), Stage::Activating);
    ASSERT_EQ(sent<CheckpointRequest>().size(), 1u);
    // A reply for another switch is ignored.
    node.receive_checkpoint_reply(CheckpointReply{ST1, 1, 1, taskB, true, {0, 5}, {5}}, 1, out);
    EXPECT_FALSE(node.active().contains(taskB));
    node.receive_checkpoint_reply(CheckpointReply{ST1, 1, 2, taskB, true, {0, 9}, {9}}, 1, out);
    EXPECT_TRUE(node.active().contains(taskB));
    EXPECT_EQ(node.version(taskB).count, 9u);
    EXPECT_EQ(node.stage(), Stage::Stable);
}

// Fault model 2, item 4: P4 moves taskB from PN3 to PN1 while the Storage node is
// excluded. PN3 hands off its state (nothing to flush), PN1 asks every member for it.
TEST_F(ConfigSwitchTest, WithoutTheStorageNodeAMovedTaskStartsFromItsOldHostsState) {
    const View p4 = view_of("P4", 1, 2, {ST1});

    ConfigSwitch old_host(topology, PN3, initial, false, Mutant::none);
    boot(old_host);
    old_host.task_stepped(taskB, {1}, 1, out);
    old_host.task_stepped(taskB, {2}, 1, out);
    EXPECT_FALSE(old_host.handed_off_version(taskB));  // it runs it: nothing handed off
    out.actions().clear();
    old_host.receive_command(Command{PN1, p4}, 1, out);
    EXPECT_EQ(old_host.stage(), Stage::Prepared);  // no Storage node to flush to
    EXPECT_TRUE(sent<CheckpointWrite>().empty());
    ASSERT_TRUE(old_host.handed_off_version(taskB));
    EXPECT_EQ(old_host.handed_off_version(taskB)->count, 2u);

    ConfigSwitch new_host(topology, PN1, initial, false, Mutant::none);
    boot(new_host);
    out.actions().clear();
    new_host.receive_command(Command{PN1, p4}, 1, out);
    activate(new_host);
    int to_members = 0;  // one request per member but itself: PN2, PN3
    for (const auto& action : out.actions()) {
        if (const auto* send = std::get_if<act::Send>(&action)) {
            if (std::holds_alternative<CheckpointRequest>(send->message)) {
                EXPECT_NE(send->to, ST1);
                ++to_members;
            }
        }
    }
    EXPECT_EQ(to_members, 2);
    EXPECT_EQ(new_host.stage(), Stage::Activating);

    // The old host's answer, and a member that never ran it.
    Outbox answers{true};
    old_host.answer_checkpoint_request(CheckpointRequest{PN1, 1, 2, taskB}, 0, answers);
    ASSERT_EQ(answers.actions().size(), 1u);
    const auto reply = std::get<CheckpointReply>(std::get<act::Send>(answers.actions()[0]).message);
    EXPECT_TRUE(reply.found);
    EXPECT_EQ(reply.version.count, 2u);
    // A holder answers within a request budget too (request_budget.hpp): a flood of PN1's
    // requests gets the budget's 4 replies, not 100; a node never placed on taskB none.
    Outbox flood{false};
    for (int i = 0; i < 100; ++i) {
        old_host.answer_checkpoint_request(CheckpointRequest{PN1, 1, 2, taskB}, 1'000, flood);
    }
    EXPECT_EQ(flood.actions().size(), 4u);
    EXPECT_EQ(old_host.request_budget().limited(), 96u);
    old_host.answer_checkpoint_request(CheckpointRequest{ST1, 1, 2, taskB}, 1'000, flood);
    EXPECT_EQ(flood.actions().size(), 4u);
    EXPECT_EQ(old_host.request_budget().refused(), 1u);
    new_host.receive_checkpoint_reply(reply, 1, out);
    EXPECT_FALSE(new_host.active().contains(taskB));  // PN2 has not answered yet
    // The excluded Storage node's word does not count.
    new_host.receive_checkpoint_reply(CheckpointReply{ST1, 1, 2, taskB, true, {0, 1}, {1}}, 1, out);
    EXPECT_FALSE(new_host.active().contains(taskB));
    new_host.receive_checkpoint_reply(CheckpointReply{PN2, 1, 2, taskB, false, {0, 0}, {}}, 1, out);
    EXPECT_TRUE(new_host.active().contains(taskB));
    EXPECT_EQ(new_host.version(taskB).count, 2u);
    // A start without the Storage node opens a lineage named by its view (<<1, 2>>): the
    // state it goes on with is newer than any the excluded Storage node may hold.
    EXPECT_EQ(new_host.version(taskB), (Version{lineage_of(1, 2), 2}));
    EXPECT_GT(new_host.version(taskB), (Version{0, 1000}));
    EXPECT_EQ(new_host.stage(), Stage::Stable);
    EXPECT_EQ(new_host.holder_restores(), 1u);
    EXPECT_EQ(new_host.unrecoverable_starts(), 0u);
}

TEST_F(ConfigSwitchTest, WithTheStateOutOfReachATaskStartsAfreshAndIsCounted) {
    // The Storage node and taskB's host PN3 both excluded: P4 places taskB on PN1.
    const View p4 = view_of("P4", 1, 2, {ST1, PN3});
    ConfigSwitch new_host(topology, PN1, initial, false, Mutant::none);
    boot(new_host);
    out.actions().clear();
    new_host.receive_command(Command{PN1, p4}, 1, out);
    activate(new_host);
    new_host.receive_checkpoint_reply(CheckpointReply{PN2, 1, 2, taskB, false, {0, 0}, {}}, 1, out);
    EXPECT_TRUE(new_host.active().contains(taskB));
    EXPECT_EQ(new_host.version(taskB), (Version{lineage_of(1, 2), 0}));
    EXPECT_EQ(new_host.unrecoverable_starts(), 1u);
}

TEST_F(ConfigSwitchTest, ANodeFencedOutHoldsNoStateAndAnswersNothing) {
    // PN3 excluded while it runs taskB: what it holds may be a lineage the cluster has
    // abandoned (the task ran on elsewhere from an older checkpoint).
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    boot(node);
    node.task_stepped(taskB, {1}, 1, out);
    const View next = view_of("P4", 1, 2, {PN3, ST1});
    node.receive_command(Command{PN1, next}, 1, out);
    EXPECT_FALSE(node.handed_off_version(taskB));
    Outbox answers{true};
    node.answer_checkpoint_request(CheckpointRequest{PN1, 1, 2, taskB}, 0, answers);
    EXPECT_TRUE(answers.actions().empty());
}

// A hand-off made while the Storage node was excluded reaches it as soon as a view
// includes it again, before the node acks Prepared: whoever restores from the Storage
// node later gets it (Handoff.tla; the mutant handoff-not-flushed skips it).
TEST_F(ConfigSwitchTest, AHandOffMadeWithoutTheStorageNodeIsFlushedWhenItReturns) {
    for (const Mutant mutant : {Mutant::none, Mutant::handoff_not_flushed}) {
        ConfigSwitch node(topology, PN3, initial, false, mutant);
        boot(node);
        node.task_stepped(taskB, {1}, 1, out);
        node.task_stepped(taskB, {2}, 1, out);
        // P4 moves taskB to PN1, the Storage node excluded; then it is readmitted, in an
        // epoch of PN1's own.
        const View without = view_of("P4", 1, 2, {ST1});
        node.receive_command(Command{PN1, without}, 1, out);
        ASSERT_EQ(node.stage(), Stage::Prepared);
        const View back = view_of("P4", 4, 1, {});
        out.actions().clear();
        node.receive_command(Command{PN1, back}, 4, out);
        const auto writes = sent<CheckpointWrite>();
        if (mutant == Mutant::none) {
            ASSERT_EQ(writes.size(), 1u);
            EXPECT_TRUE(writes[0].final);
            EXPECT_EQ(writes[0].version.count, 2u);
            EXPECT_EQ(node.stage(), Stage::Deactivating);  // waits for the Storage node
            node.receive_checkpoint_ack(CheckpointAck{ST1, 4, taskB, {0, 2}}, out);
            EXPECT_EQ(node.stage(), Stage::Prepared);
        } else {
            EXPECT_TRUE(writes.empty());
            EXPECT_EQ(node.stage(), Stage::Prepared);
        }
    }
}

TEST_F(ConfigSwitchTest, AFlushPendingWhenTheStorageNodeIsExcludedWaitsForItsReturn) {
    // S1 moves taskB away from PN3 while the Storage node is in the view: its final flush
    // is pending when the next view excludes the Storage node. The hand-off goes to the
    // Storage node when a view includes it again.
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    boot(node);
    node.task_stepped(taskB, {1}, 1, out);
    node.receive_command(Command{PN1, science()}, 1, out);
    ASSERT_TRUE(node.unflushed().contains(taskB));
    View without = science();
    without.seq = 3;
    without.failed.insert(ST1);
    node.receive_command(Command{PN1, without}, 1, out);
    EXPECT_TRUE(node.unflushed().empty());
    View back = science();
    back.epoch = 4;
    back.seq = 1;
    out.actions().clear();
    node.receive_command(Command{PN1, back}, 4, out);
    const auto writes = sent<CheckpointWrite>();
    ASSERT_EQ(writes.size(), 1u);
    EXPECT_EQ(writes[0].task, taskB);
    EXPECT_EQ(writes[0].version.count, 1u);
    EXPECT_TRUE(writes[0].final);
    EXPECT_TRUE(node.unflushed().contains(taskB));
}

TEST_F(ConfigSwitchTest, AnExcludedNodeDropsItsHandOffs) {
    // PN3 hands taskB off as a member, then a view excludes PN3: what it holds may be a
    // lineage the cluster abandoned (it ran on, cut off, past what the others restored).
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    boot(node);
    node.task_stepped(taskB, {1}, 1, out);
    const View p4 = view_of("P4", 1, 2, {ST1});
    node.receive_command(Command{PN1, p4}, 1, out);
    ASSERT_TRUE(node.handed_off_version(taskB));
    View fenced = p4;
    fenced.seq = 3;
    fenced.failed.insert(PN3);
    node.receive_command(Command{PN1, fenced}, 1, out);
    EXPECT_FALSE(node.handed_off_version(taskB));
}

TEST_F(ConfigSwitchTest, DuplicateCommandIsReAcked) {
    ConfigSwitch node(topology, PN2, initial, false, Mutant::none);
    node.receive_command(Command{PN1, science()}, 1, out);
    EXPECT_FALSE(node.receive_command(Command{PN1, science()}, 1, out));
    EXPECT_EQ(sent<Ack>().size(), 6u);  // to each of the 3 other members, twice
}

TEST_F(ConfigSwitchTest, OlderSwitchIsIgnored) {
    ConfigSwitch node(topology, PN2, initial, false, Mutant::none);
    View later = science();
    later.seq = 5;
    node.receive_command(Command{PN1, later}, 1, out);
    EXPECT_FALSE(node.receive_command(Command{PN1, science()}, 1, out));
    EXPECT_EQ(node.view().seq, 5u);
}

TEST_F(ConfigSwitchTest, ExcludedNodeStopsEverything) {
    ConfigSwitch node(topology, PN3, initial, false, Mutant::none);
    boot(node);
    out.actions().clear();
    const View next = view_of("P4", 1, 2, {PN3});
    node.receive_command(Command{PN1, next}, 1, out);
    EXPECT_TRUE(node.excluded());
    EXPECT_TRUE(node.active().empty());
    EXPECT_TRUE(sent<Ack>().empty());
}

TEST_F(ConfigSwitchTest, MasterWaitsForEveryPreparedBeforeActivate) {
    ConfigSwitch master(topology, PN1, initial, false, Mutant::none);
    master.boot_as_master();
    const View target = science();
    master.start_switch(target, out);
    EXPECT_EQ(sent<Command>().size(), 4u);
    for (NodeId n : {PN1, PN2, PN3}) {
        EXPECT_FALSE(master.receive_ack(prepared(n, master.master_view()), out));
    }
    EXPECT_EQ(master.master_stage(), MasterStage::Preparing);
    EXPECT_TRUE(sent<ActivateCommand>().empty());
    master.receive_ack(prepared(ST1, master.master_view()), out);
    EXPECT_EQ(master.master_stage(), MasterStage::Activating);
    EXPECT_EQ(sent<ActivateCommand>().size(), 4u);
    for (NodeId n : {PN1, PN2, PN3}) EXPECT_FALSE(master.receive_ack(Ack{n, 1, 2, AckKind::Activated}, out));
    EXPECT_TRUE(master.receive_ack(Ack{ST1, 1, 2, AckKind::Activated}, out));
    EXPECT_EQ(master.master_stage(), MasterStage::Idle);
}

TEST_F(ConfigSwitchTest, MasterRetransmitsToNodesThatHaveNotAcked) {
    ConfigSwitch master(topology, PN1, initial, false, Mutant::none);
    master.boot_as_master();
    master.start_switch(science(), out);
    for (NodeId n : {PN1, PN2, PN3}) master.receive_ack(prepared(n, master.master_view()), out);
    out.actions().clear();
    master.tick(1, out);
    auto commands = sent<Command>();
    ASSERT_EQ(commands.size(), 1u);
    ConfigSwitch silent(topology, PN1, initial, false, Mutant::no_retransmit);
    silent.boot_as_master();
    silent.start_switch(science(), out);
    out.actions().clear();
    silent.tick(1, out);
    EXPECT_TRUE(sent<Command>().empty());
}

TEST_F(ConfigSwitchTest, AcksOfOtherSwitchesAndFailedNodesAreIgnored) {
    ConfigSwitch master(topology, PN1, initial, false, Mutant::none);
    master.boot_as_master();
    View target = science();
    target.failed.insert(PN2);
    master.start_switch(target, out);
    master.receive_ack(prepared(PN2, master.master_view()), out);
    EXPECT_FALSE(master.prepared().contains(PN2));
    master.receive_ack(Ack{PN3, 1, 1, AckKind::Prepared}, out);
    EXPECT_FALSE(master.prepared().contains(PN3));
}

TEST_F(ConfigSwitchTest, MutantActivatesBeforeOthersDeactivate) {
    ConfigSwitch node(topology, PN3, initial, false, Mutant::activate_before_deactivate);
    boot(node);
    out.actions().clear();
    node.receive_command(Command{PN1, science()}, 1, out);
    EXPECT_TRUE(node.active().contains(taskA)) << "taskA started before any Activate";
}

}  // namespace
}  // namespace keel::fsm
