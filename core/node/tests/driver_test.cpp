// NodeDriver's three rules (driver.hpp), each with a scripted protocol and a host that
// records its effects; each rule's mutant (keel_node_driver_mutants) shows the test fails
// without it.
#include "core/node/driver.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

namespace keel::node {
namespace {

using fsm::Action;
using fsm::Mutant;

// What the protocol emits, call by call; a resignation emits a Send to node 9.
class ScriptedProtocol final : public ActionSource {
public:
    std::vector<Action> next;
    int resigned = 0;
    void take_ready(std::vector<Action>& into) override {
        into = std::move(next);
        next.clear();
    }
    void resign(fsm::TimeNs) override {
        ++resigned;
        next.resize(next.size() + 1);
        next.back() = fsm::act::Send{9, fsm::Heartbeat{}};
    }
};

// Every effect as one line, in order.
class RecordingHost final : public DriverHost {
public:
    std::vector<std::string> effects;
    bool save_ok = true;
    std::uint64_t tickets = 0;
    bool has_disk = true;
    std::string failed;

    void send(fsm::NodeId to, const fsm::Message& message) override {
        effects.push_back("send " + std::string(fsm::kind_name(message)) + " to " + std::to_string(to));
    }
    void send_to_each(const std::vector<fsm::NodeId>& to, const fsm::Message& message) override {
        std::string nodes;
        for (const fsm::NodeId node : to) nodes += " " + std::to_string(node);
        effects.push_back("send " + std::string(fsm::kind_name(message)) + " to each of" + nodes);
    }
    void activate(const fsm::act::Activate& action) override {
        effects.push_back("activate " + std::to_string(action.task));
    }
    void deactivate(fsm::TaskId task) override { effects.push_back("deactivate " + std::to_string(task)); }
    void write_trace(const fsm::act::Trace& line) override { effects.push_back(std::string("trace ") + line.action); }
    bool save_state() override {
        effects.push_back(save_ok ? "save" : "save failed");
        return save_ok;
    }
    std::optional<std::uint64_t> store_checkpoint(fsm::act::StoreCheckpoint& store) override {
        if (!has_disk) return std::nullopt;
        effects.push_back("store " + std::to_string(store.task) + " v" + std::to_string(store.version.count));
        return ++tickets;
    }
    void disk_failed(std::string_view what) override {
        failed = std::string(what);
        effects.push_back("stop");
    }
};

fsm::act::Send ack(fsm::TaskId task, std::uint64_t count) {
    fsm::CheckpointAck message;
    message.task = task;
    message.version = fsm::Version{1, count};
    return fsm::act::Send{3, message};
}

// A Storage node's step that stores a final checkpoint of task 2 and acknowledges it.
std::vector<Action> store_and_ack(std::uint64_t count) {
    return {fsm::act::StoreCheckpoint{2, fsm::Version{1, count}, {1, 2, 3}, false},
            fsm::act::Trace{"switch", "StoreCheckpoint", "{}", "{}"}, ack(2, count)};
}

struct DriverTest : testing::Test {
    ScriptedProtocol protocol;
    RecordingHost host;
    std::vector<std::string> run(Mutant mutant, const std::function<void(NodeDriver&)>& steps) {
        NodeDriver driver(protocol, host, DriverOptions{false, mutant});
        steps(driver);
        return host.effects;
    }
};

TEST_F(DriverTest, TheStateIsSavedBeforeTheStepsMessagesLeave) {
    protocol.next = {fsm::act::Send{1, fsm::Heartbeat{}}, fsm::act::Activate{}};
    const auto effects = run(Mutant::none, [](NodeDriver& driver) { driver.drive(0); });
    EXPECT_EQ(effects, (std::vector<std::string>{"save", "send Heartbeat to 1", "activate 0"}));
}

TEST_F(DriverTest, AStateThatCannotBeSavedDropsTheStepsMessagesAndTheNodeLeaves) {
    host.save_ok = false;
    protocol.next = {fsm::act::Send{1, fsm::Heartbeat{}}, fsm::act::Activate{}};
    NodeDriver driver(protocol, host);
    driver.drive(0);
    // The step's message is dropped, its other actions carried out; the resignation
    // (which changes no saved state) goes, then nothing more.
    EXPECT_EQ(host.effects,
              (std::vector<std::string>{"save failed", "activate 0", "send Heartbeat to 9", "stop"}));
    EXPECT_EQ(protocol.resigned, 1);
    EXPECT_TRUE(driver.stopped());
    EXPECT_EQ(driver.counters().state_save_errors, 1u);
    host.effects.clear();
    protocol.next = {fsm::act::Send{1, fsm::Heartbeat{}}};
    driver.drive(1);
    EXPECT_EQ(host.effects, std::vector<std::string>{});
}

TEST_F(DriverTest, MutantSaveAfterSendLetsTheMessagesGoFirst) {
    host.save_ok = false;
    protocol.next = {fsm::act::Send{1, fsm::Heartbeat{}}};
    const auto effects = run(Mutant::save_after_send, [](NodeDriver& driver) { driver.drive(0); });
    ASSERT_GE(effects.size(), 2u);
    EXPECT_EQ(effects[0], "send Heartbeat to 1");
    EXPECT_EQ(effects[1], "save failed");
}

TEST_F(DriverTest, AnAcknowledgementWaitsUntilItsCheckpointIsWritten) {
    protocol.next = store_and_ack(7);
    NodeDriver driver(protocol, host);
    driver.drive(0);
    EXPECT_EQ(host.effects, (std::vector<std::string>{"save", "store 2 v7"}));
    EXPECT_EQ(driver.held(), 2u);
    driver.checkpoint_written(2, 1);
    EXPECT_EQ(host.effects, (std::vector<std::string>{"save", "store 2 v7", "trace StoreCheckpoint",
                                                      "send CheckpointAck to 3"}));
    EXPECT_EQ(driver.held(), 0u);
}

TEST_F(DriverTest, WhatConcernsATaskWithNothingUnwrittenGoesAtOnce) {
    protocol.next = {ack(4, 1), fsm::act::Trace{"switch", "Other", "{}", "{}"}};
    const auto effects = run(Mutant::none, [](NodeDriver& driver) { driver.drive(0); });
    EXPECT_EQ(effects, (std::vector<std::string>{"save", "send CheckpointAck to 3", "trace Other"}));
}

TEST_F(DriverTest, MutantReleaseHeldEarlyAcknowledgesBeforeTheDisk) {
    protocol.next = store_and_ack(7);
    const auto effects = run(Mutant::release_held_early, [](NodeDriver& driver) { driver.drive(0); });
    EXPECT_EQ(effects, (std::vector<std::string>{"save", "store 2 v7", "trace StoreCheckpoint",
                                                 "send CheckpointAck to 3"}));
}

TEST_F(DriverTest, AFailedWriteReleasesNothingAndTheStorageNodeLeaves) {
    protocol.next = store_and_ack(7);
    NodeDriver driver(protocol, host);
    driver.drive(0);
    driver.checkpoint_failed(2, 1, 5);
    EXPECT_EQ(host.effects, (std::vector<std::string>{"save", "store 2 v7", "save", "send Heartbeat to 9",
                                                      "stop"}));
    EXPECT_EQ(host.failed, "a checkpoint write failed");
    EXPECT_TRUE(driver.storage_failed());
    EXPECT_EQ(driver.counters().checkpoint_write_errors, 1u);
    EXPECT_EQ(driver.counters().dropped_for_disk, 2u);
    // Later acknowledgements stand for no durable write either.
    host.effects.clear();
    protocol.next = {ack(2, 8)};
    driver.drive(6);
    EXPECT_EQ(host.effects, std::vector<std::string>{"save"});
}

TEST_F(DriverTest, MutantIgnoreFailedWriteReleasesAndFliesOn) {
    protocol.next = store_and_ack(7);
    NodeDriver driver(protocol, host, DriverOptions{false, Mutant::ignore_failed_write});
    driver.drive(0);
    driver.checkpoint_failed(2, 1, 5);
    EXPECT_EQ(host.effects, (std::vector<std::string>{"save", "store 2 v7", "trace StoreCheckpoint",
                                                      "send CheckpointAck to 3"}));
    EXPECT_FALSE(driver.stopped());
}

TEST_F(DriverTest, HeartbeatsToEveryMonitorGoOnceWhenCoalesced) {
    fsm::Heartbeat reply;
    reply.reply = true;
    protocol.next = {fsm::act::Send{1, fsm::Heartbeat{}}, fsm::act::Send{2, fsm::Heartbeat{}},
                     fsm::act::Send{2, reply}};
    NodeDriver driver(protocol, host, DriverOptions{true, Mutant::none});
    driver.drive(0);
    EXPECT_EQ(host.effects, (std::vector<std::string>{"save", "send Heartbeat to 65535", "send Heartbeat to 2"}));
}

TEST_F(DriverTest, WithLinesBeforeSendsAStepsLinesAreWrittenBeforeItsMessagesLeave) {
    // keel-node: a checkpoint is sent, then traced (the protocol's order); a node killed
    // between the two must not have sent what its trace lacks.
    fsm::CheckpointWrite write;
    write.task = 1;
    const std::vector<Action> step = {fsm::act::Send{3, write}, fsm::act::Trace{"switch", "FlushCheckpoint", "{}", "{}"},
                                      fsm::act::Send{2, fsm::Heartbeat{}}, fsm::act::Activate{}};
    protocol.next = step;
    NodeDriver ordered(protocol, host, DriverOptions{.coalesce_heartbeats = false, .lines_before_sends = true});
    ordered.drive(0);
    EXPECT_EQ(host.effects, (std::vector<std::string>{"save", "trace FlushCheckpoint", "activate 0",
                                                      "send CheckpointWrite to 3", "send Heartbeat to 2"}));
    // Off (keel-sim): the protocol's order.
    host.effects.clear();
    protocol.next = step;
    NodeDriver as_emitted(protocol, host);
    as_emitted.drive(0);
    EXPECT_EQ(host.effects, (std::vector<std::string>{"save", "send CheckpointWrite to 3", "trace FlushCheckpoint",
                                                      "send Heartbeat to 2", "activate 0"}));
}

// keel-node: a switch's Command (and its Activate) to every member goes to the host as one
// send, which the DDS transport writes as one sample for all of them. Only a run of the same
// Command is one: another Command, or the same one after another message, is sent apart, and
// other messages (an Ack to several nodes) never are grouped.
TEST_F(DriverTest, ASwitchsCommandToEveryMemberIsOneSend) {
    const fsm::Command command(1, fsm::View{}, {});
    fsm::Command handed = command;
    handed.boot = 7;  // a hand-over's Command names its receiver's boot: another message
    const fsm::ActivateCommand activate{1, 3, 2};
    const fsm::Ack ack{1, 3, 2, fsm::AckKind::Prepared};
    const std::vector<Action> step = {
        fsm::act::Send{2, command},  fsm::act::Send{3, command}, fsm::act::Send{4, command},
        fsm::act::Send{5, handed},   fsm::act::Send{6, ack},     fsm::act::Send{7, ack},
        fsm::act::Send{2, activate}, fsm::act::Send{3, activate}, fsm::act::Send{4, command}};
    protocol.next = step;
    NodeDriver grouped(protocol, host,
                       DriverOptions{.lines_before_sends = true, .one_send_per_command = true});
    grouped.drive(0);
    EXPECT_EQ(host.effects, (std::vector<std::string>{
                                "save", "send Command to each of 2 3 4", "send Command to 5",
                                "send Ack to 6", "send Ack to 7", "send Activate to each of 2 3",
                                "send Command to 4"}));
    // Off (keel-sim's network, and the default): one send per node.
    host.effects.clear();
    protocol.next = step;
    NodeDriver apart(protocol, host, DriverOptions{.lines_before_sends = true});
    apart.drive(0);
    EXPECT_EQ(std::ranges::count_if(host.effects, [](const std::string& effect) {
                  return effect.find("each of") != std::string::npos;
              }),
              0);
    EXPECT_EQ(host.effects.size(), 1 + step.size());
}

TEST_F(DriverTest, ANodeWithoutADiskTracesItsStoreAtOnce) {
    host.has_disk = false;
    protocol.next = store_and_ack(7);
    const auto effects = run(Mutant::none, [](NodeDriver& driver) { driver.drive(0); });
    EXPECT_EQ(effects, (std::vector<std::string>{"save", "trace StoreCheckpoint", "send CheckpointAck to 3"}));
}

TEST_F(DriverTest, ASaveThatFailsBeforeAGroundCommandActsStopsTheNode) {
    NodeDriver driver(protocol, host);
    host.save_ok = false;
    EXPECT_FALSE(driver.save_state(0));
    EXPECT_TRUE(driver.stopped());
    EXPECT_EQ(host.failed, "its state cannot be saved");
    EXPECT_FALSE(driver.save_state(1));
}

}  // namespace
}  // namespace keel::node
