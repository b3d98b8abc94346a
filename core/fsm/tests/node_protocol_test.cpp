// NodeProtocol end to end on a tiny lossless cluster: messages are delivered in order one
// millisecond after they are sent, and every node ticks at the same period boundaries.
#include "core/fsm/node_protocol.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <memory>
#include <optional>
#include <set>
#include <utility>

#include "core/fsm/admission.hpp"
#include "core/fsm/codec.hpp"
#include "test_mission.hpp"

namespace keel::fsm {
namespace {

constexpr TimeNs P = 100 * kNanosecondsPerMillisecond;

class Cluster {
public:
    // Nodes in `late` have not booted yet (their processes start later: boot()).
    // `kept`: the checkpoints the Storage node's durable store kept from an earlier run.
    explicit Cluster(const Topology& topology, NodeSet late = {},
                     const std::vector<StoredCheckpoint>& kept = {}, Mutant mutant = Mutant::none)
        : topology_(topology) {
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            NodeOptions options;
            options.mutant = mutant;
            if (n == topology.storage_node()) options.kept_checkpoints = kept;
            nodes_.push_back(late.contains(n) ? nullptr
                                              : std::make_unique<NodeProtocol>(topology, n, 0, options));
            alive_.push_back(!late.contains(n));
            if (alive_[n]) drain(n);
        }
    }
    // First boot of a late node (no PersistentState).
    void boot(NodeId n) {
        nodes_[n] = std::make_unique<NodeProtocol>(topology_, n, now_, NodeOptions{});
        alive_[n] = true;
        drain(n);
    }
    void resign(NodeId n) {
        nodes_[n]->resign(now_);
        drain(n);
    }
    bool booted(NodeId n) const { return nodes_[n] != nullptr; }
    // Delivers what is in flight, with no period boundary.
    void deliver() { deliver_all(); }
    // Fault model 3: `to` receives `message` now (whoever it names as sender: a node's
    // credentials stand for it, so a value-faulty node sends under its own name), then
    // everything in flight is delivered.
    void inject(NodeId to, const Message& message) {
        now_ += 1000;
        nodes_[to]->step(message, now_);
        drain(to);
        deliver_all();
    }

    NodeProtocol& node(NodeId n) { return *nodes_[n]; }
    TimeNs now() const { return now_; }
    void crash(NodeId n) { alive_[n] = false; }
    // `epoch`: the saved epoch, if not the node's own (a state file from elsewhere).
    void restart(NodeId n, Mutant mutant = Mutant::none, std::optional<Epoch> epoch = std::nullopt) {
        auto persisted = nodes_[n]->persistent_state();
        if (epoch) persisted.epoch = *epoch;
        NodeOptions options;
        options.mutant = mutant;
        options.boot = ++boots_;
        nodes_[n] = std::make_unique<NodeProtocol>(topology_, n, now_, options, persisted);
        alive_[n] = true;
        running_[n] = TaskSet{};  // a new process runs nothing yet
        drain(n);
    }
    void request_phase(NodeId n, PhaseId phase) {
        nodes_[n]->request_phase(phase, now_);
        drain(n);
        deliver_all();
    }
    // Takes what calls from outside (the ground's commands) left in every node's outbox.
    void settle() {
        for (NodeId n = 0; n < nodes_.size(); ++n) {
            if (alive_[n]) drain(n);
        }
        deliver_all();
    }
    // Runs `periods` heartbeat periods: tick everyone, deliver everything.
    void run(int periods) {
        for (int k = 0; k < periods; ++k) {
            now_ += P;
            for (NodeId n = 0; n < nodes_.size(); ++n) {
                if (!alive_[n] || stopped_.contains(n)) continue;
                for (TaskId t = 0; t < topology_.task_count(); ++t) {
                    if (nodes_[n]->config_switch().active().contains(t)) {
                        nodes_[n]->task_stepped(t, {static_cast<std::uint8_t>(k)}, now_);
                    }
                }
                nodes_[n]->tick(now_);
                drain(n);
            }
            deliver_all();
        }
    }
    // Fault model 2: what `from` sends to `to` is lost until unblock_all().
    void block(NodeId from, NodeId to) { blocked_.insert({from, to}); }
    void unblock_all() {
        blocked_.clear();
        blocked_replies_.clear();
        blocked_commands_.clear();
        blocked_acks_.clear();
    }
    // Only the CheckpointReplies `from` sends `to` are lost until unblock_all().
    void block_replies(NodeId from, NodeId to) { blocked_replies_.insert({from, to}); }
    // Only the Commands `from` sends `to` are lost until unblock_all().
    void block_commands(NodeId from, NodeId to) { blocked_commands_.insert({from, to}); }
    // Only the Acks (Prepared, Activated) `from` sends `to` are lost until unblock_all().
    void block_acks(NodeId from, NodeId to) { blocked_acks_.insert({from, to}); }
    // The node's process is stopped: it takes no step; messages to it wait until resume().
    void stop(NodeId n) { stopped_.insert(n); }
    // The node runs, but reads what it is sent only at resume(): a slow reader.
    void defer(NodeId n) { deferred_.insert(n); }
    void resume(NodeId n) {
        stopped_.erase(n);
        deferred_.erase(n);
        std::deque<InFlight> held;
        held.swap(held_);
        for (auto& item : held) queue_.push_back(std::move(item));
        deliver_all();
    }
    int activations(TaskId task) const { return activations_[task]; }
    // What the node's application runs now (its Activate and Deactivate actions).
    TaskSet running(NodeId n) const { return alive_[n] ? running_[n] : TaskSet{}; }
    // Some task runs on two nodes at once.
    bool task_on_two_nodes() const {
        TaskSet seen;
        for (NodeId n = 0; n < nodes_.size(); ++n) {
            if (!(seen & running(n)).empty()) return true;
            seen = seen | running(n);
        }
        return false;
    }
    // Nodes that act as Master (and have not stepped down).
    int running_masters() const {
        int count = 0;
        for (NodeId n = 0; n < nodes_.size(); ++n) {
            count += alive_[n] && nodes_[n] != nullptr && nodes_[n]->is_master() &&
                     nodes_[n]->resign_state() == NodeProtocol::Resign::none;
        }
        return count;
    }
    TaskSet ever_activated_on(NodeId n) const { return activated_on_[n]; }
    Version last_activation_version(TaskId task) const { return last_version_[task]; }

private:
    std::uint32_t boots_ = 0;  // each restart's boot identifier
    void drain(NodeId n) {
        for (auto& action : nodes_[n]->take_ready()) {
            if (auto* send = std::get_if<act::Send>(&action)) {
                queue_.push_back({n, send->to, std::move(send->message)});
            } else if (auto* deactivate = std::get_if<act::Deactivate>(&action)) {
                running_[n].erase(deactivate->task);
            } else if (auto* activate = std::get_if<act::Activate>(&action)) {
                running_[n].insert(activate->task);
                ++activations_[activate->task];
                last_version_[activate->task] = activate->version;
                activated_on_[n].insert(activate->task);
            }
        }
    }
    void deliver_all() {
        for (int guard = 0; guard < 100000 && !queue_.empty(); ++guard) {
            auto [from, to, message] = std::move(queue_.front());
            queue_.pop_front();
            if (!alive_[to]) continue;
            if (blocked_.contains({from, to})) continue;
            if (blocked_replies_.contains({from, to}) && std::holds_alternative<CheckpointReply>(message)) continue;
            if (blocked_commands_.contains({from, to}) && std::holds_alternative<Command>(message)) continue;
            if (blocked_acks_.contains({from, to}) && std::holds_alternative<Ack>(message)) continue;
            if (stopped_.contains(to) || deferred_.contains(to)) {
                held_.push_back({from, to, std::move(message)});
                continue;
            }
            now_ += 1000;  // a microsecond per delivery keeps time moving forward
            nodes_[to]->step(message, now_);
            drain(to);
        }
    }

    const Topology& topology_;
    std::vector<std::unique_ptr<NodeProtocol>> nodes_;
    std::vector<bool> alive_;
    struct InFlight {
        NodeId from;
        NodeId to;
        Message message;
    };
    std::deque<InFlight> queue_;
    std::deque<InFlight> held_;
    std::set<std::pair<NodeId, NodeId>> blocked_;
    std::set<std::pair<NodeId, NodeId>> blocked_replies_;
    std::set<std::pair<NodeId, NodeId>> blocked_commands_;
    std::set<std::pair<NodeId, NodeId>> blocked_acks_;
    std::set<NodeId> stopped_;
    std::set<NodeId> deferred_;
    TimeNs now_ = 0;
    std::array<int, kMaxTasks> activations_{};
    std::array<Version, kMaxTasks> last_version_{};
    std::array<TaskSet, kMaxNodes> activated_on_{};
    std::array<TaskSet, kMaxNodes> running_{};
};

class NodeProtocolTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    TaskId taskA = 0, taskB = 1;
    ConfigId id(const char* name) { return *topology.config_id(name); }
    // PN3, cut off from both other processing nodes, holds taskB; once they are heard
    // again it resumes, and asks the Storage node first, whose answer is held back.
    void hold_then_resume_pn3(Cluster& cluster) {
        cluster.run(10);
        ASSERT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
        cluster.block(PN1, PN3);
        cluster.block(PN2, PN3);
        cluster.run(topology.miss_limit() + 1);
        ASSERT_TRUE(cluster.node(PN3).holding());
        cluster.unblock_all();
        cluster.block_replies(ST1, PN3);
        cluster.run(1);
        ASSERT_FALSE(cluster.node(PN3).holding());
    }
};

TEST_F(NodeProtocolTest, QuietClusterStaysInItsInitialConfiguration) {
    Cluster cluster(topology);
    cluster.run(50);
    for (NodeId n = 0; n < 4; ++n) {
        EXPECT_EQ(cluster.node(n).view().config, id("P1"));
        EXPECT_EQ(cluster.node(n).view().seq, 1u);  // the boot switch
    }
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_GE(cluster.node(ST1).store()->latest_version(taskB)->count, 49u);
}

TEST_F(NodeProtocolTest, WorkerFailureMovesItsTaskWithItsCheckpoint) {
    Cluster cluster(topology);
    cluster.run(10);
    cluster.crash(PN3);
    cluster.run(10);
    // P1 -> PN3 fails -> P4: taskB moves to PN1 and resumes from the last checkpoint.
    EXPECT_EQ(cluster.node(PN1).view().config, id("P4"));
    EXPECT_EQ(cluster.node(PN1).config_switch().master_stage(), MasterStage::Idle);
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    // taskB started in the boot switch's Activate, one period in: 9 steps checkpointed.
    EXPECT_EQ(cluster.last_activation_version(taskB).count, 9u);
    EXPECT_EQ(cluster.node(PN2).view(), cluster.node(PN1).view());
}

TEST_F(NodeProtocolTest, MasterFailureElectsTheFirstObserver) {
    Cluster cluster(topology);
    cluster.run(10);
    cluster.crash(PN1);
    cluster.run(10);
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN2).epoch(), 2u);
    EXPECT_EQ(cluster.node(PN3).view().config, id("P2"));
    EXPECT_EQ(cluster.node(PN3).election().leader(), PN2);
    EXPECT_FALSE(cluster.node(PN3).is_master());
}

TEST_F(NodeProtocolTest, PhaseChangeMovesBothTasks) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.request_phase(PN2, *topology.phase_id("science"));  // not the Master: nothing
    cluster.run(3);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
    cluster.request_phase(PN1, *topology.phase_id("science"));
    cluster.run(3);
    EXPECT_EQ(cluster.node(PN1).view().config, id("S1"));
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskA));
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskB));
    EXPECT_FALSE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.activations(taskB), 2);
}

// Phase requests come from the Master's timeline or the ground (whose commands each node
// checks itself, core/node/ground.hpp): one from another node is unauthorized.
TEST_F(NodeProtocolTest, APhaseRequestFromAnotherNodeIsNobodysToSend) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.inject(PN1, PhaseRequest{PN2, *topology.phase_id("science")});
    cluster.run(3);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
    EXPECT_EQ(cluster.node(PN1).stats().unauthorized[9], 1u);  // PhaseRequest
    EXPECT_NE(cluster.node(PN1).last_refusal().find("never from another node"), std::string::npos);
}

// Ground commands (core/node/ground.hpp): every node takes the ground's `exclude PN3`
// (checked there by the operator's signature). The Master excludes PN3 by its own switch; although it
// stays up and says it knows itself excluded, no Master readmits it while the ground holds
// it out, until the ground's `readmit PN3`. An exclusion the graph takes to safe mode
// (PN2 while PN3 is out) is refused with the reason, and changes nothing.
TEST_F(NodeProtocolTest, ANodeTheGroundHoldsOutStaysOutUntilTheGroundLetsItBack) {
    Cluster cluster(topology);
    cluster.run(5);
    auto ground = [&](bool exclude, NodeId node) {
        std::string why;
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            why = exclude ? cluster.node(n).ground_exclude(node, cluster.now())
                          : cluster.node(n).ground_readmit(node, cluster.now());
        }
        cluster.run(0);
        return why;
    };
    EXPECT_EQ(ground(true, PN3), "");
    cluster.run(40);
    EXPECT_TRUE(cluster.node(PN1).view().failed.contains(PN3));
    EXPECT_TRUE(cluster.running(PN3).empty());
    EXPECT_EQ(cluster.node(PN1).stats().readmissions, 0u);
    EXPECT_TRUE(cluster.node(PN1).held_out().contains(PN3));
    const ConfigId without_pn3 = cluster.node(PN1).view().config;
    const std::string refused = ground(true, PN2);
    EXPECT_NE(refused.find("lead to safe mode"), std::string::npos) << refused;
    EXPECT_FALSE(cluster.node(PN1).held_out().contains(PN2));
    cluster.run(10);
    EXPECT_EQ(cluster.node(PN1).view().config, without_pn3);
    EXPECT_EQ(ground(false, PN3), "");
    cluster.run(40);
    EXPECT_FALSE(cluster.node(PN1).view().failed.contains(PN3));
    EXPECT_EQ(cluster.node(PN1).stats().readmissions, 1u);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
    EXPECT_FALSE(cluster.task_on_two_nodes());
    EXPECT_NE(ground(false, PN3).find("not held out"), std::string::npos);
    // Two excludes in a row, the second before the first took effect: judged together.
    cluster.run(10);
    EXPECT_EQ(ground(true, PN3), "");
    const std::string second = ground(true, PN2);
    EXPECT_NE(second.find("and the nodes failed or held out already"), std::string::npos) << second;
    EXPECT_FALSE(cluster.node(PN1).held_out().contains(PN2));
}

// The ground's `pause-task` and `resume-task` (core/node/ground.hpp), taken by every node.
// The essential taskB is never paused. taskA stops on PN2 and stays stopped while a phase
// change moves it to PN3 (placed there, not started), until the ground resumes it; a
// restarted node keeps its pauses (PersistentState), and a second resume is refused.
TEST_F(NodeProtocolTest, TheGroundPausesATaskWhereverItIsPlacedUntilItResumes) {
    Cluster cluster(topology);
    cluster.run(5);
    const TaskId task_a = *topology.task_id("taskA");
    const TaskId task_b = *topology.task_id("taskB");
    auto ground = [&](bool pause, TaskId task) {
        std::string why;
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            why = pause ? cluster.node(n).ground_pause(task, cluster.now())
                        : cluster.node(n).ground_resume(task, cluster.now());
        }
        cluster.settle();
        return why;
    };
    ASSERT_TRUE(cluster.running(PN2).contains(task_a));
    const std::string essential = ground(true, task_b);
    EXPECT_NE(essential.find("essential"), std::string::npos) << essential;
    EXPECT_TRUE(cluster.node(PN3).paused().empty());
    EXPECT_EQ(ground(true, task_a), "");
    EXPECT_FALSE(cluster.running(PN2).contains(task_a));
    EXPECT_TRUE(cluster.running(PN3).contains(task_b));  // the rest runs on
    EXPECT_NE(ground(true, task_a).find("paused already"), std::string::npos);
    cluster.request_phase(PN1, *topology.phase_id("science"));
    cluster.run(10);
    ASSERT_EQ(cluster.node(PN3).view().config, id("S1"));
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(task_a));  // placed
    EXPECT_FALSE(cluster.running(PN3).contains(task_a));                       // not started
    EXPECT_TRUE(cluster.running(PN2).contains(task_b));
    EXPECT_TRUE(cluster.node(PN3).persistent_state().paused.contains(task_a));
    cluster.crash(PN2);
    cluster.restart(PN2);
    EXPECT_TRUE(cluster.node(PN2).paused().contains(task_a));  // read back from its state
    cluster.run(40);
    EXPECT_EQ(ground(false, task_a), "");
    EXPECT_TRUE(cluster.running(topology.host(cluster.node(PN1).view(), task_a)).contains(task_a));
    EXPECT_NE(ground(false, task_a).find("not paused"), std::string::npos);
    EXPECT_FALSE(cluster.task_on_two_nodes());
}

// Only the acting Master's walk excludes (spec/Ground.tla): a node's own view may be
// behind the Master's, so the node the ground names does not resign on its own check. The
// exclude reaching PN3 alone holds it out there and changes nothing else; once the Master
// takes it, the Master excludes PN3 by its own switch (`Exclude` with the ground's hold).
TEST_F(NodeProtocolTest, TheGroundsExcludeTakesEffectByTheMastersSwitchOnly) {
    Cluster cluster(topology);
    cluster.run(5);
    EXPECT_EQ(cluster.node(PN3).ground_exclude(PN3, cluster.now()), "");
    cluster.run(20);
    EXPECT_TRUE(cluster.node(PN3).held_out().contains(PN3));
    EXPECT_FALSE(cluster.node(PN1).view().failed.contains(PN3));
    EXPECT_FALSE(cluster.running(PN3).empty());
    EXPECT_EQ(cluster.node(PN1).ground_exclude(PN3, cluster.now()), "");
    cluster.run(10);
    EXPECT_TRUE(cluster.node(PN1).view().failed.contains(PN3));
    EXPECT_TRUE(cluster.running(PN3).empty());
    EXPECT_FALSE(cluster.task_on_two_nodes());
}

// In safe mode (beyond the tolerance already) every node holds the node the ground names
// out, but the Master excludes no one for the ground until a recovery leaves safe mode
// (spec/Ground.tla, MasterWalkOk; trace validation takes no ground exclusion into SAFE).
TEST_F(NodeProtocolTest, InSafeModeTheMasterExcludesNoOneForTheGround) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.crash(ST1);  // prototype3 has no edge for it: safe mode, PN2 and PN3 alive
    cluster.run(20);
    ASSERT_TRUE(cluster.node(PN1).is_master());
    ASSERT_TRUE(cluster.node(PN1).view().is_safe());
    for (NodeId n : {PN1, PN2, PN3}) EXPECT_EQ(cluster.node(n).ground_exclude(PN3, cluster.now()), "");
    cluster.run(20);
    EXPECT_TRUE(cluster.node(PN1).held_out().contains(PN3));
    EXPECT_FALSE(cluster.node(PN1).view().failed.contains(PN3));
    EXPECT_TRUE(cluster.node(PN1).view().is_safe());
}

// A node that held a node out becomes Master in a view where excluding it reaches safe
// mode (PN1, the Master, crashed meanwhile): it leaves it held out and not excluded, and
// counts it. The ground took no node out beyond the tolerance; the real failure did not
// combine with the hold.
TEST_F(NodeProtocolTest, AMasterWhoseWalkReachesSafeModeLeavesAHeldOutNodeIn) {
    Cluster cluster(topology);
    cluster.run(5);
    EXPECT_EQ(cluster.node(PN2).ground_exclude(PN3, cluster.now()), "");
    cluster.crash(PN1);
    cluster.run(40);
    ASSERT_TRUE(cluster.node(PN2).is_master());
    EXPECT_TRUE(cluster.node(PN2).held_out().contains(PN3));
    EXPECT_FALSE(cluster.node(PN2).view().failed.contains(PN3));
    EXPECT_FALSE(cluster.node(PN2).view().is_safe());
    EXPECT_GT(cluster.node(PN2).stats().ground_exclusions_withheld, 0u);
    EXPECT_EQ(cluster.node(PN3).view(), cluster.node(PN2).view());
}

// The nodes held out come back from the disk with the node's state: ids beyond the
// mission are no nodes and are dropped, never used as an index.
// Pauses read back from the disk: tasks of the mission that may be paused only (an id
// beyond the mission, or an essential task, is dropped).
TEST_F(NodeProtocolTest, PausedTasksReadBackFromTheDiskAreThoseThatMayBePaused) {
    Cluster cluster(topology);
    cluster.run(5);
    PersistentState saved = cluster.node(PN2).persistent_state();
    saved.paused.insert(*topology.task_id("taskA"));
    saved.paused.insert(*topology.task_id("taskB"));  // essential
    saved.paused.insert(900);
    NodeProtocol restarted(topology, PN2, cluster.now(), NodeOptions{}, saved);
    TaskSet expected;
    expected.insert(*topology.task_id("taskA"));
    EXPECT_EQ(restarted.paused(), expected);
}

TEST_F(NodeProtocolTest, HeldOutNodesReadBackFromTheDiskAreTheMissionsOnly) {
    Cluster cluster(topology);
    cluster.run(5);
    PersistentState saved = cluster.node(PN2).persistent_state();
    saved.held_out.insert(PN3);
    saved.held_out.insert(200);
    NodeProtocol restarted(topology, PN2, cluster.now(), NodeOptions{}, saved);
    NodeSet expected;
    expected.insert(PN3);
    EXPECT_EQ(restarted.held_out(), expected);
    EXPECT_NE(restarted.ground_exclude(PN2, cluster.now()).find("lead to safe mode"), std::string::npos);
}

TEST_F(NodeProtocolTest, RestartedNodeIsExcluded) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.crash(PN2);
    cluster.restart(PN2);
    cluster.run(5);
    EXPECT_TRUE(cluster.node(PN1).view().failed.contains(PN2));
    EXPECT_TRUE(cluster.node(PN2).view().failed.contains(PN2));
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().empty());
    EXPECT_EQ(cluster.node(PN1).view().config, id("P3"));
}

TEST_F(NodeProtocolTest, AHeartbeatOfABootThatEndedIsCountedAndHeardNoMore) {
    // PN2 is heard under boot 0, then under boot 7 (it restarted: declared); a heartbeat
    // of boot 0 arriving after that is stale, dropped and counted.
    Cluster cluster(topology);
    cluster.run(5);
    const std::uint32_t incarnation = 1;
    cluster.inject(PN1, Heartbeat{PN2, 1, incarnation, false, 50, {}, false, 7});
    EXPECT_TRUE(cluster.node(PN1).monitor().failed().contains(PN2));
    EXPECT_EQ(cluster.node(PN1).stats().retired_boot_heartbeats, 0u);
    cluster.inject(PN1, Heartbeat{PN2, 1, incarnation, false, 51, {}, false, 0});
    EXPECT_EQ(cluster.node(PN1).stats().retired_boot_heartbeats, 1u);
}

TEST_F(NodeProtocolTest, AWholeClusterPowerCycleWarmBootsTheInitialMaster) {
    // Every node crashes and restarts from its saved state: each waits to be commanded.
    // PN1, the master of P1, hears them all waiting for miss_limit periods and warm-boots
    // into epoch 4 (its first above 1); taskB resumes from ST1's checkpoint. Without the
    // warm boot (mutant no_warm_boot) nobody is ever Master again.
    for (const Mutant mutant : {Mutant::none, Mutant::no_warm_boot}) {
        if (mutant != Mutant::none && !kMutantsCompiled) continue;
        Cluster cluster(topology);
        cluster.run(10);
        for (NodeId n : {PN1, PN2, PN3, ST1}) cluster.crash(n);
        for (NodeId n : {PN3, ST1, PN2, PN1}) cluster.restart(n, mutant);
        for (NodeId n : {PN1, PN2, PN3, ST1}) EXPECT_TRUE(cluster.node(n).waiting());
        cluster.run(10);
        if (mutant == Mutant::none) {
            EXPECT_TRUE(cluster.node(PN1).is_master());
            EXPECT_EQ(cluster.node(PN1).epoch(), 4u);
            EXPECT_EQ(cluster.node(PN1).stats().warm_boots, 1u);
            EXPECT_EQ(cluster.node(PN3).view().config, id("P1"));
            EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
            EXPECT_GE(cluster.last_activation_version(taskB).count, 9u);
            for (NodeId n : {PN1, PN2, PN3, ST1}) EXPECT_FALSE(cluster.node(n).waiting());
        } else {
            for (NodeId n : {PN1, PN2, PN3}) EXPECT_FALSE(cluster.node(n).is_master());
            EXPECT_EQ(cluster.node(PN1).stats().warm_boots, 0u);
        }
    }
}

TEST_F(NodeProtocolTest, ANodeTheGroundHoldsOutNeverWarmBoots) {
    // The ground holds PN1, the initial Master, out; then the whole cluster power-cycles.
    // PN1 hears every processing node waiting, as for a warm boot, but no Master it would
    // be may readmit it: it does not warm-boot (docs/operations.md).
    Cluster cluster(topology);
    cluster.run(5);
    for (NodeId n = 0; n < topology.node_count(); ++n) {
        EXPECT_EQ(cluster.node(n).ground_exclude(PN1, cluster.now()), "");
    }
    cluster.run(20);
    ASSERT_TRUE(cluster.node(PN1).held_out().contains(PN1));
    for (NodeId n : {PN1, PN2, PN3, ST1}) cluster.crash(n);
    for (NodeId n : {PN3, ST1, PN2, PN1}) cluster.restart(n);
    ASSERT_TRUE(cluster.node(PN1).held_out().contains(PN1));
    ASSERT_TRUE(cluster.node(PN1).waiting());
    cluster.run(10);
    EXPECT_EQ(cluster.node(PN1).stats().warm_boots, 0u);
    EXPECT_FALSE(cluster.node(PN1).is_master());
}

TEST_F(NodeProtocolTest, APowerCycleOfTheProcessingNodesAloneWarmBoots) {
    // ST1 stays up (its own power), commanded by the Master that went down: it does not
    // wait, and need not; PN1 warm-boots all the same.
    Cluster cluster(topology);
    cluster.run(10);
    for (NodeId n : {PN1, PN2, PN3}) cluster.crash(n);
    for (NodeId n : {PN2, PN3, PN1}) cluster.restart(n);
    EXPECT_FALSE(cluster.node(ST1).waiting());
    cluster.run(10);
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_EQ(cluster.node(PN1).stats().warm_boots, 1u);
    EXPECT_EQ(cluster.node(ST1).view(), cluster.node(PN1).view());
}

TEST_F(NodeProtocolTest, AWarmBootWithNoAdoptableEpochLeftIsRefused) {
    // PN2's saved epoch is at the adoptable bound: no epoch PN1 owns is left above it
    // that a node would adopt. PN1 does not warm-boot, and counts it.
    Cluster cluster(topology);
    cluster.run(10);
    for (NodeId n : {PN1, PN2, PN3, ST1}) cluster.crash(n);
    for (NodeId n : {PN3, ST1, PN1}) cluster.restart(n);
    cluster.restart(PN2, Mutant::none, max_adoptable_epoch(topology));
    cluster.run(10);
    EXPECT_FALSE(cluster.node(PN1).is_master());
    EXPECT_GE(cluster.node(PN1).stats().warm_boots_refused, 1u);
    EXPECT_EQ(cluster.node(PN1).stats().warm_boots, 0u);
}

TEST_F(NodeProtocolTest, ANodeOnAnotherMissionImageTakesNoPart) {
    // PN1 flies image 5. PN2's heartbeats name image 6: from then on everything PN2 sends
    // is dropped and counted, until a heartbeat of PN2 names image 5.
    NodeOptions options;
    options.image = 5;
    NodeProtocol pn1(topology, PN1, 0, options);
    pn1.step(Heartbeat{PN2, 1, 1, false, 1, {}, false, 0, false, 0, 6}, 1000);
    EXPECT_EQ(pn1.foreign_image(PN2), 6u);
    EXPECT_EQ(pn1.stats().foreign_image, 1u);
    EXPECT_FALSE(pn1.monitor().heard_once().contains(PN2));
    pn1.step(ErrorNotification{PN2, 1, PN3}, 2000);
    EXPECT_EQ(pn1.stats().foreign_image, 2u);
    // Its ids are its own mission's: one beyond this mission's is no refusal (an honest
    // node of another image is no value fault, and leaves no Refused line).
    pn1.step(ErrorNotification{PN2, 1, static_cast<NodeId>(topology.node_count() + 1)}, 2500);
    EXPECT_EQ(pn1.stats().foreign_image, 3u);
    EXPECT_EQ(pn1.stats().malformed[4], 0u);
    pn1.step(Heartbeat{PN2, 1, 1, false, 2, {}, false, 0, false, 0, 6}, 2600);
    EXPECT_EQ(pn1.stats().foreign_image, 4u);
    // A heartbeat that names no image (0) changes nothing; one naming PN1's ends it.
    pn1.step(Heartbeat{PN2, 1, 1, false, 2, {}, false, 0, false, 0, 0}, 3000);
    EXPECT_EQ(pn1.stats().foreign_image, 5u);
    pn1.step(Heartbeat{PN2, 1, 1, false, 3, {}, false, 0, false, 0, 5}, 4000);
    EXPECT_EQ(pn1.foreign_image(PN2), 0u);
    EXPECT_EQ(pn1.stats().foreign_image, 5u);
    EXPECT_TRUE(pn1.monitor().heard_once().contains(PN2));
    // A node that knows no image of its own compares none.
    NodeProtocol unknown(topology, PN1, 0, NodeOptions{});
    unknown.step(Heartbeat{PN2, 1, 1, false, 1, {}, false, 0, false, 0, 6}, 1000);
    EXPECT_EQ(unknown.stats().foreign_image, 0u);
}

TEST_F(NodeProtocolTest, NoWarmBootWhileANodeHeardIsCommanded) {
    // PN1 restarts alone in a running cluster: it waits, but PN2 and PN3 do not (PN2
    // commands them): PN1 never warm-boots; it is excluded and readmitted as any restart.
    Cluster cluster(topology);
    cluster.run(10);
    cluster.crash(PN1);
    cluster.restart(PN1);
    cluster.run(30);
    EXPECT_EQ(cluster.node(PN1).stats().warm_boots, 0u);
    EXPECT_FALSE(cluster.node(PN1).waiting());
}

TEST_F(NodeProtocolTest, MasterFailureDuringASwitchIsFinishedByTheObserver) {
    Cluster cluster(topology);
    cluster.run(5);
    // Start the phase change and lose the Master before anything is delivered.
    cluster.node(PN1).request_phase(*topology.phase_id("science"), cluster.now() + 1);
    cluster.crash(PN1);
    cluster.run(10);
    EXPECT_TRUE(cluster.node(PN2).is_master());
    // PN2 never received S1, so it continues from P1: P1 with PN1 failed is P2.
    EXPECT_EQ(cluster.node(PN2).view().config, id("P2"));
    EXPECT_EQ(cluster.node(PN3).view(), cluster.node(PN2).view());
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskA));
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
}

TEST_F(NodeProtocolTest, AnExcludedNodeTellsTheMonitorsAtOnce) {
    Cluster cluster(topology);
    cluster.run(3);
    View view = cluster.node(PN1).view();
    view.seq = 7;
    view.failed.insert(ST1);
    cluster.node(ST1).step(Command{PN1, view}, cluster.now() + 1);
    EXPECT_TRUE(cluster.node(ST1).config_switch().excluded());
    cluster.run(2);
    EXPECT_TRUE(cluster.node(PN1).manager().driving().failed.contains(ST1));
}

TEST_F(NodeProtocolTest, StaleCommandsAreRejectedInStep) {
    Cluster cluster(topology);
    cluster.run(3);
    cluster.crash(PN1);
    cluster.run(8);
    auto& pn3 = cluster.node(PN3);
    const auto before = pn3.stats().stale_rejected;
    View old = topology.initial_view();
    old.seq = 99;
    pn3.step(Command{PN1, old}, cluster.now() + 1);
    EXPECT_EQ(pn3.stats().stale_rejected, before + 1);
    EXPECT_EQ(pn3.view().epoch, 2u);
}

TEST_F(NodeProtocolTest, PersistentStateCarriesEpochAndCheckpoints) {
    Cluster cluster(topology);
    cluster.run(5);
    const auto state = cluster.node(ST1).persistent_state();
    EXPECT_EQ(state.epoch, 1u);
    EXPECT_EQ(state.incarnation, 1u);
    ASSERT_EQ(state.checkpoints.size(), 1u);
    EXPECT_EQ(state.checkpoints[0].task, taskB);
}

TEST_F(NodeProtocolTest, FirstBootRunsNothingUntilTheBootSwitch) {
    Cluster cluster(topology);
    for (NodeId n = 0; n < 4; ++n) {
        EXPECT_TRUE(cluster.node(n).config_switch().active().empty()) << int(n);
        EXPECT_EQ(cluster.node(n).config_switch().stage(), Stage::Stable) << int(n);
    }
    // The initial Master commands nothing before it holds its lease: no Observer has
    // acknowledged one of its heartbeats yet.
    EXPECT_FALSE(cluster.node(PN1).holds_lease());
    EXPECT_FALSE(cluster.node(PN1).is_master());
    EXPECT_EQ(cluster.node(PN1).view().seq, 0u);
    EXPECT_EQ(cluster.activations(taskA) + cluster.activations(taskB), 0);
    // Its first heartbeat is acknowledged at once: the boot switch runs.
    cluster.run(1);
    EXPECT_TRUE(cluster.node(PN1).holds_lease());
    EXPECT_EQ(cluster.node(PN1).view().seq, 1u);
    cluster.run(1);
    EXPECT_EQ(cluster.node(PN1).config_switch().master_stage(), MasterStage::Idle);
    EXPECT_EQ(cluster.node(PN1).stats().switches_completed, 1u);
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskA));
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.activations(taskA), 1);
    EXPECT_EQ(cluster.activations(taskB), 1);
    EXPECT_EQ(cluster.last_activation_version(taskB).count, 0u);
}

TEST_F(NodeProtocolTest, TheBootSwitchWaitsForFreshAcknowledgements) {
    // A slow board (keel-node under qemu-aarch64): PN1 reads its queue late, so the first
    // acknowledgements it reads are of its first heartbeat, two periods old. Its lease
    // holds on them for a quarter period more; a boot switch started on it would lapse
    // before the next acknowledgements and PN1 would resign, handing the cluster on.
    Cluster cluster(topology);
    cluster.defer(PN1);
    cluster.run(1);                   // PN1's first heartbeat, acknowledged at once
    cluster.stop(PN1);
    cluster.run(2);
    cluster.resume(PN1);              // two periods on, PN1 reads the acknowledgements
    EXPECT_TRUE(cluster.node(PN1).holds_lease());
    EXPECT_FALSE(cluster.node(PN1).lease_fresh());
    EXPECT_EQ(cluster.node(PN1).view().seq, 0u);
    EXPECT_FALSE(cluster.node(PN1).is_master());
    // Its next heartbeat is acknowledged at once: the boot switch runs, and holds.
    cluster.run(3);
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_EQ(cluster.node(PN1).view().epoch, 1u);
    EXPECT_EQ(cluster.node(PN1).view().seq, 1u);
    EXPECT_EQ(cluster.node(PN1).stats().lease_step_downs, 0u);
    EXPECT_EQ(cluster.node(PN1).stats().switches_completed, 1u);
    EXPECT_EQ(cluster.running_masters(), 1);
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskA));
}

TEST_F(NodeProtocolTest, APhaseRequestedBeforeTheLeaseFollowsTheBootSwitch) {
    Cluster cluster(topology);
    ASSERT_FALSE(cluster.node(PN1).is_master());
    cluster.request_phase(PN1, *topology.phase_id("science"));
    cluster.run(3);
    EXPECT_EQ(cluster.node(PN1).view().config, id("S1"));
    EXPECT_EQ(cluster.node(PN1).stats().switches_completed, 2u);
}

TEST_F(NodeProtocolTest, BootSwitchResumesWhatTheStorageNodeKeptAcrossAPowerCycle) {
    Cluster cluster(topology, {}, {StoredCheckpoint{taskB, {0, 42}, {42}}});
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().empty());
    cluster.run(1);
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.last_activation_version(taskB).count, 42u);
    EXPECT_EQ(cluster.node(PN1).view().seq, 1u);
}

TEST_F(NodeProtocolTest, NodeBootingLateWithinTheGraceJoinsTheBootSwitch) {
    NodeSet late;
    late.insert(PN3);
    Cluster cluster(topology, late);
    cluster.run(5);
    // The boot switch waits for PN3 (retransmitted every period); nothing is declared.
    EXPECT_EQ(cluster.node(PN1).config_switch().master_stage(), MasterStage::Preparing);
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().empty());
    cluster.boot(PN3);
    cluster.run(3);
    EXPECT_EQ(cluster.node(PN1).config_switch().master_stage(), MasterStage::Idle);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
    EXPECT_TRUE(cluster.node(PN1).view().failed.empty());
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskA));
}

TEST_F(NodeProtocolTest, NodeDeclaredFailedBeforeItBootedIsFencedAndNeverActivates) {
    // The campaign's case: PN3 starts after the grace, the cluster moves taskB to PN1 (P4)
    // and checkpoints it; PN3 then boots fresh and must not run taskB from version 0.
    NodeSet late;
    late.insert(PN3);
    Cluster cluster(topology, late);
    cluster.run(topology.startup_grace_periods() + 3);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P4"));
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    cluster.run(8);
    const Version before = *cluster.node(ST1).store()->latest_version(taskB);
    EXPECT_GE(before.count, 8u);
    cluster.boot(PN3);
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().empty());
    cluster.run(5);
    EXPECT_TRUE(cluster.node(PN3).config_switch().excluded());
    EXPECT_TRUE(cluster.ever_activated_on(PN3).empty());
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    EXPECT_GT(*cluster.node(ST1).store()->latest_version(taskB), before);
}

TEST_F(NodeProtocolTest, MasterThatNeverBootsIsReplacedAfterTheGrace) {
    NodeSet late;
    late.insert(PN1);
    Cluster cluster(topology, late);
    cluster.run(topology.startup_grace_periods() - 2);
    for (NodeId n : {PN2, PN3}) {
        EXPECT_FALSE(cluster.node(n).is_master());
        EXPECT_TRUE(cluster.node(n).config_switch().active().empty());
    }
    cluster.run(5);
    // The take-over walks the graph from the initial view: P1 without PN1 is P2, and its
    // switch activates the tasks although nothing ran before.
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN2).epoch(), 2u);
    EXPECT_EQ(cluster.node(PN3).view().config, id("P2"));
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskA));
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
}

TEST_F(NodeProtocolTest, MasterDyingBeforeTheBootSwitchIsReplaced) {
    Cluster cluster(topology);
    cluster.crash(PN1);  // before its lease: it never commanded anything
    cluster.run(1);
    EXPECT_EQ(cluster.node(PN2).view().seq, 0u);
    cluster.run(topology.startup_grace_periods() + 3);  // PN1 was never heard: the grace
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN2).view().config, id("P2"));
    EXPECT_EQ(cluster.node(PN2).config_switch().master_stage(), MasterStage::Idle);
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskA));
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
}

TEST_F(NodeProtocolTest, WorkerResignAsksTheMasterToExcludeIt) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.resign(PN3);
    EXPECT_EQ(cluster.node(PN3).resign_state(), NodeProtocol::Resign::asked);
    // Its task stops at once: the Master may move it before its Command reaches PN3.
    EXPECT_TRUE(cluster.running(PN3).empty());
    cluster.run(3);
    // P1 -> PN3 fails -> P4: taskB moves to PN1 with its checkpoint.
    EXPECT_EQ(cluster.node(PN1).view().config, id("P4"));
    EXPECT_TRUE(cluster.node(PN3).config_switch().excluded());
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    EXPECT_GE(cluster.last_activation_version(taskB).count, 4u);
}

TEST_F(NodeProtocolTest, ANewlyExcludedNodeIsFencedByTheSwitchItself) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.resign(PN3);
    cluster.deliver();  // no heartbeat from PN3 reaches the Master meanwhile
    EXPECT_EQ(cluster.node(PN1).view().config, id("P4"));
    EXPECT_TRUE(cluster.node(PN3).config_switch().excluded());
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().empty());
}

TEST_F(NodeProtocolTest, MasterResignFlushesThenStepsDownUntilReadmitted) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.crash(PN3);
    cluster.run(8);
    ASSERT_EQ(cluster.node(PN1).view().config, id("P4"));  // taskB on the Master PN1
    ASSERT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    cluster.resign(PN1);
    EXPECT_EQ(cluster.node(PN1).resign_state(), NodeProtocol::Resign::flushing);
    EXPECT_FALSE(cluster.node(PN1).is_master());
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().empty());
    const Version last = cluster.node(PN1).config_switch().version(taskB);
    cluster.run(1);  // the final checkpoint is acked: its heartbeats now say excluded
    EXPECT_EQ(cluster.node(PN1).resign_state(), NodeProtocol::Resign::done);
    EXPECT_EQ(*cluster.node(ST1).store()->latest_version(taskB), last);
    cluster.run(5);
    // PN2 declares it failed at once and takes over: P4 without PN1 is SAFE, where the
    // essential taskB runs on the Master, resumed from PN1's final checkpoint.
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_TRUE(cluster.node(PN2).view().is_safe());
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.last_activation_version(taskB), last);
    EXPECT_TRUE(cluster.node(PN1).config_switch().excluded());
    EXPECT_EQ(cluster.node(PN1).role(), Role::Worker);
    // Heard all along, it is readmitted (spec/Rejoin.tla): P4, the configuration of the
    // smaller failed set, is its own, so PN2 hands it over.
    cluster.run(30);
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_FALSE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN2).view().config, id("P4"));
    EXPECT_EQ(cluster.node(PN2).stats().hand_overs, 1u);
}

TEST_F(NodeProtocolTest, MasterResignGivesUpOnAnUnreachableStorageNode) {
    Cluster cluster(topology);
    cluster.run(5);
    cluster.crash(PN3);
    cluster.run(8);
    ASSERT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    cluster.crash(ST1);
    cluster.resign(PN1);
    cluster.run(topology.miss_limit() - 1);
    EXPECT_EQ(cluster.node(PN1).resign_state(), NodeProtocol::Resign::flushing);
    cluster.run(2);
    EXPECT_EQ(cluster.node(PN1).resign_state(), NodeProtocol::Resign::done);
    EXPECT_TRUE(cluster.node(PN1).config_switch().unflushed().empty());
}

TEST_F(NodeProtocolTest, ResignedMasterIgnoresCommandsThatDoNotExcludeIt) {
    Cluster cluster(topology);
    cluster.run(3);
    cluster.resign(PN1);  // PN1 hosts nothing in P1: nothing to flush, done at once
    ASSERT_EQ(cluster.node(PN1).resign_state(), NodeProtocol::Resign::done);
    View view = cluster.node(PN2).view();
    view.epoch = 2;
    view.seq = 1;
    view.master = PN2;
    // The configuration PN1's failure leads to, in a view that does not exclude PN1 yet.
    view.config = view.base = topology.config(id("P1")).on_failure[PN1];
    ASSERT_EQ(topology.config(view.config).master, PN2);
    cluster.node(PN1).step(Command{PN2, view}, cluster.now() + 1);
    EXPECT_EQ(cluster.node(PN1).epoch(), 1u);
    EXPECT_FALSE(cluster.node(PN1).config_switch().excluded());
    view.failed.insert(PN1);
    cluster.node(PN1).step(Command{PN2, view}, cluster.now() + 2);
    EXPECT_TRUE(cluster.node(PN1).config_switch().excluded());
}

TEST_F(NodeProtocolTest, OneObserverDeafToAWorkerGetsNoOneExcluded) {
    // Fault model 2: PN2 loses ST1's heartbeats; the Master hears ST1 fine. PN2's report is
    // one monitor's word: nothing is excluded, and the withheld exclusion is counted.
    Cluster cluster(topology);
    cluster.run(10);
    cluster.block(ST1, PN2);
    cluster.run(20);
    EXPECT_TRUE(cluster.node(PN2).monitor().failed().contains(ST1));
    EXPECT_TRUE(cluster.node(PN1).view().failed.empty());
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
    EXPECT_GT(cluster.node(PN1).stats().exclusions_withheld, 0u);
}

TEST_F(NodeProtocolTest, TwoMonitorsEvidenceExcludes) {
    Cluster cluster(topology);
    cluster.run(10);
    cluster.block(ST1, PN1);
    cluster.block(ST1, PN2);
    cluster.run(10);
    EXPECT_TRUE(cluster.node(PN1).view().failed.contains(ST1));
}

TEST_F(NodeProtocolTest, TheMastersOwnDeclarationAloneExcludesNoOne) {
    Cluster cluster(topology);
    cluster.run(10);
    cluster.block(PN3, PN1);  // PN2 still hears PN3
    cluster.run(20);
    EXPECT_TRUE(cluster.node(PN1).monitor().failed().contains(PN3));
    EXPECT_TRUE(cluster.node(PN1).view().failed.empty());
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
}

TEST_F(NodeProtocolTest, ADeafObserverSuspectsItselfAndDeclaresNoOne) {
    Cluster cluster(topology);
    cluster.run(10);
    for (NodeId n : {PN1, PN3, ST1}) cluster.block(n, PN2);
    cluster.run(20);
    EXPECT_TRUE(cluster.node(PN2).monitor().failed().empty());
    EXPECT_GE(cluster.node(PN2).monitor().self_suspected_periods(), 19u);
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
}

TEST_F(NodeProtocolTest, ACutOffMasterStepsDownBeforeItIsReplaced) {
    Cluster cluster(topology);
    cluster.run(25);  // past the start-up grace
    for (NodeId n : {PN2, PN3, ST1}) {
        cluster.block(n, PN1);
        cluster.block(PN1, n);
    }
    // The last acknowledged heartbeat was sent at the cut: the lease ends 2.75 periods
    // later, and PN1 steps down at its third boundary; the Observers, which miss it from
    // the first period on, declare it only at the third and take over after it.
    cluster.run(3);
    EXPECT_NE(cluster.node(PN1).resign_state(), NodeProtocol::Resign::none);
    EXPECT_EQ(cluster.node(PN1).stats().lease_step_downs, 1u);
    EXPECT_FALSE(cluster.node(PN2).is_master());
    cluster.run(5);
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().empty());
}

// Fault model 2, the lease (spec/Lease.tla): a Master that can receive but not send is
// replaced; it must have stopped first, although it still hears everyone.
TEST_F(NodeProtocolTest, AMuteMasterStepsDownBeforeItIsReplaced) {
    Cluster cluster(topology);
    cluster.run(25);
    for (NodeId n : {PN2, PN3, ST1}) cluster.block(PN1, n);
    for (int k = 0; k < 10; ++k) {
        cluster.run(1);
        EXPECT_LE(cluster.running_masters(), 1) << "period " << k;
        EXPECT_FALSE(cluster.task_on_two_nodes()) << "period " << k;
    }
    EXPECT_EQ(cluster.node(PN1).stats().lease_step_downs, 1u);
    EXPECT_EQ(cluster.node(PN1).stats().cut_off_step_downs, 0u);  // it heard everyone
    EXPECT_TRUE(cluster.node(PN2).is_master());
}

// A Worker cut off from the cluster holds its task before the Master moves it, and runs it
// again, from the newer stored checkpoint, if it was never excluded.
TEST_F(NodeProtocolTest, ACutOffNodeHoldsItsTasksBeforeTheyMove) {
    Cluster cluster(topology);
    cluster.run(25);
    ASSERT_TRUE(cluster.running(PN3).contains(taskB));
    for (NodeId n : {PN1, PN2, ST1}) {
        cluster.block(PN3, n);
        cluster.block(n, PN3);
    }
    for (int k = 0; k < 10; ++k) {
        cluster.run(1);
        EXPECT_FALSE(cluster.task_on_two_nodes()) << "period " << k;
    }
    EXPECT_EQ(cluster.node(PN3).stats().lease_holds, 1u);
    EXPECT_TRUE(cluster.node(PN3).holding());
    EXPECT_TRUE(cluster.running(PN3).empty());
    EXPECT_TRUE(cluster.running(PN1).contains(taskB));  // P1 -> PN3 fails -> P4
}

TEST_F(NodeProtocolTest, ANodeHeldBrieflyResumesWhereItStood) {
    Cluster cluster(topology);
    cluster.run(25);
    // PN3 hears no one for three periods: its lease lapses (2.75 periods after its last
    // acknowledged heartbeat), but every monitor hears it, so none declares it.
    for (NodeId n : {PN1, PN2, ST1}) cluster.block(n, PN3);
    cluster.run(3);
    cluster.deliver();
    EXPECT_TRUE(cluster.node(PN3).holding());
    EXPECT_TRUE(cluster.running(PN3).empty());
    const Version held_at = cluster.node(PN3).config_switch().version(taskB);
    cluster.unblock_all();
    cluster.run(2);
    EXPECT_FALSE(cluster.node(PN3).holding());
    EXPECT_EQ(cluster.node(PN3).stats().lease_releases, 1u);
    EXPECT_TRUE(cluster.running(PN3).contains(taskB));
    EXPECT_GE(cluster.last_activation_version(taskB), held_at);
    EXPECT_EQ(cluster.node(PN1).view().seq, 1u) << "nothing was reconfigured";
}

// The mutant without the lease: the cut-off Worker keeps running what moves elsewhere.
TEST_F(NodeProtocolTest, WithoutTheLeaseACutOffNodeRunsATaskTwice) {
    Cluster cluster(topology, {}, {}, Mutant::no_lease);
    cluster.run(25);
    for (NodeId n : {PN1, PN2, ST1}) {
        cluster.block(PN3, n);
        cluster.block(n, PN3);
    }
    bool twice = false;
    for (int k = 0; k < 10; ++k) {
        cluster.run(1);
        twice = twice || cluster.task_on_two_nodes();
    }
    EXPECT_TRUE(twice);
}

TEST_F(NodeProtocolTest, AStalledMasterStepsDownBeforeActingOnWhatArrived) {
    Cluster cluster(topology);
    cluster.run(10);
    cluster.stop(PN1);
    cluster.run(8);  // the Observers take over meanwhile
    ASSERT_TRUE(cluster.node(PN2).is_master());
    cluster.resume(PN1);  // held messages first, as a resumed process reads its queue
    EXPECT_EQ(cluster.node(PN1).stats().stall_step_downs, 1u);
    EXPECT_FALSE(cluster.node(PN1).is_master() &&
                 cluster.node(PN1).resign_state() == NodeProtocol::Resign::none);
}

// Reintegration (spec/Rejoin.tla): runs `periods` periods checking, at every boundary,
// that at most one Master runs and no task runs on two nodes.
void run_safely(Cluster& cluster, int periods) {
    for (int k = 0; k < periods; ++k) {
        cluster.run(1);
        ASSERT_LE(cluster.running_masters(), 1) << "period " << k;
        ASSERT_FALSE(cluster.task_on_two_nodes()) << "period " << k;
    }
}

// A restarted Worker comes back: the cluster returns to the configuration of the smaller
// failed set (P1), the Worker runs its task again from the stored checkpoint, and the
// cluster tolerates one more failure.
TEST_F(NodeProtocolTest, ARestartedWorkerIsReadmittedAndTheClusterToleratesAnotherFailure) {
    Cluster cluster(topology);
    cluster.run(25);
    cluster.crash(PN3);
    cluster.restart(PN3);
    run_safely(cluster, 5);
    ASSERT_TRUE(cluster.node(PN1).view().failed.contains(PN3));
    ASSERT_EQ(cluster.node(PN1).view().config, id("P4"));
    const Version before = cluster.last_activation_version(taskB);
    run_safely(cluster, 10);
    EXPECT_EQ(cluster.node(PN1).stats().readmissions, 1u);
    EXPECT_EQ(cluster.node(PN1).stats().hand_overs, 0u);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
    EXPECT_TRUE(cluster.node(PN1).view().failed.empty());
    EXPECT_TRUE(cluster.running(PN3).contains(taskB));
    EXPECT_GE(cluster.last_activation_version(taskB), before);
    cluster.crash(PN2);
    run_safely(cluster, 10);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P3"));
    EXPECT_FALSE(cluster.node(PN1).view().is_safe());
}

// A mission's on_recovery edge decides where a readmission goes: here PN3 readmitted in P4
// leads to P3 (taskA stays on the Master) instead of P1, the smaller failed set's.
TEST_F(NodeProtocolTest, AReadmissionFollowsTheMissionsRecoveryEdge) {
    keel::mission::Mission mission = testing::prototype3();
    mission.phases[0].on_recovery.push_back({"P4", "PN3", "P3", 0});
    std::string error;
    const Topology edged = Topology::build(mission, &error).value();
    Cluster cluster(edged);
    cluster.run(25);
    cluster.crash(PN3);
    cluster.restart(PN3);
    run_safely(cluster, 5);
    ASSERT_EQ(cluster.node(PN1).view().config, *edged.config_id("P4"));
    run_safely(cluster, 10);
    EXPECT_EQ(cluster.node(PN1).stats().readmissions, 1u);
    EXPECT_EQ(cluster.node(PN1).view().config, *edged.config_id("P3"));
    EXPECT_TRUE(cluster.node(PN1).view().failed.empty());
    EXPECT_TRUE(cluster.running(PN1).contains(taskA));
    EXPECT_TRUE(cluster.running(PN3).contains(taskB));
}

// A restarted Master comes back as Master: the configuration of the smaller failed set is
// its own, so PN2 hands the view over (PN1's next epoch) and stops driving at once.
TEST_F(NodeProtocolTest, ARestartedMasterIsHandedItsConfigurationBack) {
    Cluster cluster(topology);
    cluster.run(25);
    cluster.crash(PN1);
    cluster.restart(PN1);
    run_safely(cluster, 3);
    ASSERT_TRUE(cluster.node(PN2).is_master());
    ASSERT_EQ(cluster.node(PN2).view().config, id("P2"));
    run_safely(cluster, 12);
    EXPECT_EQ(cluster.node(PN2).stats().hand_overs, 1u);
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_FALSE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN1).epoch(), 4u);  // PN1's epoch after PN2's 2
    EXPECT_EQ(cluster.node(PN3).view().config, id("P1"));
    EXPECT_EQ(cluster.node(PN3).view().master, PN1);
    EXPECT_TRUE(cluster.node(PN3).view().failed.empty());
    EXPECT_TRUE(cluster.running(PN2).contains(taskA));
    EXPECT_TRUE(cluster.running(PN3).contains(taskB));
    cluster.crash(PN3);
    run_safely(cluster, 10);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P4"));
}

// A hand-over names its receiver's boot. PN2 hands P1 back to PN1, whose copies are
// lost; PN1 restarts, and then PN2's repeat reaches it. It was meant for the boot that
// ended: PN1 refuses it (counted) and is not Master of that epoch. The same repeat naming
// PN1's new boot is taken (the check refuses only the ended boot's). Under the mutant
// hand_over_any_boot the new boot takes the view meant for the old one.
TEST_F(NodeProtocolTest, AHandOverMeantForAnEarlierBootOfItsReceiverIsRefused) {
    for (const bool to_new_boot : {false, true}) {
        for (const Mutant mutant : {Mutant::none, Mutant::hand_over_any_boot}) {
            SCOPED_TRACE(std::string(to_string(mutant)) + (to_new_boot ? ", to the new boot" : ""));
            Cluster cluster(topology);
            cluster.run(25);
            cluster.crash(PN1);
            cluster.restart(PN1);
            for (int k = 0; k < 10 && !cluster.node(PN1).config_switch().excluded(); ++k) cluster.run(1);
            ASSERT_TRUE(cluster.node(PN1).config_switch().excluded());
            ASSERT_TRUE(cluster.node(PN2).is_master());
            cluster.block(PN2, PN1);
            for (int k = 0; k < 20 && cluster.node(PN2).stats().hand_overs == 0; ++k) cluster.run(1);
            ASSERT_EQ(cluster.node(PN2).stats().hand_overs, 1u);
            const View handed = cluster.node(PN2).view();
            ASSERT_EQ(handed.master, PN1);
            ASSERT_EQ(handed.seq, 0u);
            Command repeat{PN2, handed, {}};
            repeat.boot = cluster.node(PN1).monitor().boot();
            cluster.crash(PN1);
            cluster.restart(PN1, mutant);
            if (to_new_boot) repeat.boot = cluster.node(PN1).monitor().boot();
            ASSERT_NE(cluster.node(PN1).epoch(), handed.epoch);
            cluster.inject(PN1, repeat);
            const bool takes = to_new_boot || mutant == Mutant::hand_over_any_boot;
            EXPECT_EQ(cluster.node(PN1).stats().hand_overs_stale, takes ? 0u : 1u);
            EXPECT_EQ(cluster.node(PN1).epoch() == handed.epoch, takes);
            EXPECT_EQ(cluster.node(PN1).role() == Role::Master, takes);  // it drives once it holds its lease
        }
    }
}

// A Worker cut off long enough to be excluded, then heard again, is readmitted (it was
// never faulty for good); it ran nothing while it was out.
TEST_F(NodeProtocolTest, AHealedWorkerIsReadmitted) {
    Cluster cluster(topology);
    cluster.run(25);
    for (NodeId n : {PN1, PN2, ST1}) {
        cluster.block(PN3, n);
        cluster.block(n, PN3);
    }
    run_safely(cluster, 8);
    ASSERT_TRUE(cluster.node(PN1).view().failed.contains(PN3));
    EXPECT_TRUE(cluster.running(PN3).empty());
    cluster.unblock_all();
    run_safely(cluster, 12);
    EXPECT_EQ(cluster.node(PN1).stats().readmissions, 1u);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
    EXPECT_EQ(cluster.node(PN3).resign_state(), NodeProtocol::Resign::none);
    EXPECT_TRUE(cluster.running(PN3).contains(taskB));
}

// Beyond the tolerance the cluster is in safe mode (PN2 crashed, then PN3 restarted: its
// own word, which needs no lease); PN3 coming back takes it out again, to the
// configuration of the smaller failed set.
TEST_F(NodeProtocolTest, ARestartedNodeTakesTheClusterOutOfSafeMode) {
    Cluster cluster(topology);
    cluster.run(25);
    cluster.crash(PN2);
    run_safely(cluster, 10);
    ASSERT_EQ(cluster.node(PN1).view().config, id("P3"));
    cluster.crash(PN3);
    cluster.restart(PN3);
    run_safely(cluster, 3);
    ASSERT_TRUE(cluster.node(PN1).view().is_safe());
    EXPECT_TRUE(cluster.running(PN1).contains(taskB));  // the essential task
    run_safely(cluster, 12);
    EXPECT_EQ(cluster.node(PN1).view().config, id("P3"));
    EXPECT_TRUE(cluster.running(PN3).contains(taskB));
    EXPECT_TRUE(cluster.running(PN1).contains(taskA));
}


// --- Fault model 3: a node that says something wrong harms no one but itself -----------

std::uint64_t total(const std::array<std::uint64_t, std::variant_size_v<Message>>& counts) {
    std::uint64_t sum = 0;
    for (const std::uint64_t count : counts) sum += count;
    return sum;
}

TEST_F(NodeProtocolTest, ACommandNamingAConfigurationTheMissionLacksIsMalformedNotAnAbort) {
    Cluster cluster(topology);
    cluster.run(10);
    const View before = cluster.node(PN2).view();
    View forged = before;
    forged.epoch = 3;  // PN3's
    forged.seq = 1;
    forged.master = PN3;
    forged.config = forged.base = 999;
    for (NodeId n : {PN1, PN2, ST1}) {
        cluster.inject(n, Command{PN3, forged});
        EXPECT_EQ(cluster.node(n).stats().malformed[1], 1u) << cluster.node(n).last_refusal();
        EXPECT_EQ(cluster.node(n).view(), before);
    }
    EXPECT_NE(cluster.node(PN2).last_refusal().find("view.config 999"), std::string::npos);
    // A joint view, a failed set, a task, a phase and a declared node beyond the mission.
    Command joint{PN1, before, {before}};
    joint.joint[0].base = 50;
    cluster.inject(PN2, joint);
    View wide = before;
    wide.failed.insert(200);
    cluster.inject(PN2, Command{PN1, wide});
    cluster.inject(PN2, CheckpointAck{ST1, 1, 77, Version{}});
    cluster.inject(PN1, PhaseRequest{PN2, 9});
    cluster.inject(PN1, ErrorNotification{PN2, 1, 300});
    EXPECT_EQ(total(cluster.node(PN2).stats().malformed), 4u);
    EXPECT_EQ(total(cluster.node(PN1).stats().malformed), 3u);
    cluster.run(10);
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_EQ(cluster.node(PN1).view().config, id("P1"));
}

TEST_F(NodeProtocolTest, AnEpochFarAboveIsNotAdoptedInOneMessage) {
    Cluster cluster(topology);
    cluster.run(10);
    // PN3 owns 3, 6, 9, ...: 3 * 1000 is within the wire's 24 bits and PN3's own.
    View forged = cluster.node(PN2).view();
    forged.epoch = 3000;
    forged.seq = 1;
    forged.master = PN3;
    forged.failed.insert(PN1);
    forged.failed.insert(PN2);
    forged.config = forged.base = kSafeConfig;
    forged.base = id("P1");
    cluster.inject(ST1, Command{PN3, forged});
    EXPECT_EQ(cluster.node(ST1).epoch(), 1u);
    EXPECT_EQ(cluster.node(ST1).stats().ahead_dropped, 1u);
    EXPECT_NE(cluster.node(ST1).last_refusal().find("a lap of the succession"), std::string::npos);
    // Anything else of an epoch beyond the bound is dropped unread, and counted.
    cluster.inject(ST1, Ack{PN3, 3000, 1, AckKind::Prepared});
    EXPECT_EQ(cluster.node(ST1).stats().ahead_dropped, 2u);
    // The next epoch PN3 owns is within a lap and the view is valid, but no node but PN3
    // has declared PN1 or PN2 failed to ST1: not followed yet (rule 5), and no refusal.
    forged.epoch = 3;
    cluster.inject(ST1, Command{PN3, forged});
    EXPECT_EQ(cluster.node(ST1).epoch(), 1u);
    EXPECT_EQ(cluster.node(ST1).stats().commands_unbacked, 1u);
    EXPECT_EQ(cluster.node(ST1).stats().commands_refused, 0u);
    EXPECT_NE(cluster.node(ST1).last_refusal().find("no node but PN3"), std::string::npos);
    // PN2 declares PN1 and asks for its own exclusion: the take-over is backed, adopted.
    cluster.inject(ST1, ErrorNotification{PN2, 1, PN1});
    cluster.inject(ST1, ErrorNotification{PN2, 1, PN2});
    cluster.inject(ST1, Command{PN3, forged});
    EXPECT_EQ(cluster.node(ST1).epoch(), 3u);
}

TEST_F(NodeProtocolTest, AnEpochWithinALapOfTheLargestIsRefusedAsProof) {
    Cluster cluster(topology);
    cluster.run(10);
    View forged = cluster.node(PN2).view();
    forged.master = PN3;
    forged.seq = 1;
    forged.epoch = kMaxEpoch - (kMaxEpoch % 3);  // a multiple of 3: PN3's
    ASSERT_EQ(topology.owner(forged.epoch), PN3);
    forged.config = forged.base = kSafeConfig;
    forged.base = id("P1");
    cluster.inject(PN2, Command{PN3, forged});
    EXPECT_EQ(cluster.node(PN2).epoch(), 1u);
    EXPECT_EQ(cluster.node(PN2).stats().commands_refused, 1u);
    // Proof against its sender: PN2 holds PN3 failed for good.
    EXPECT_TRUE(cluster.node(PN2).monitor().failed().contains(PN3));
    EXPECT_FALSE(cluster.node(PN2).monitor().forgettable(PN3));
}

TEST_F(NodeProtocolTest, TheStorageNodesHeartbeatsCannotRaceTheMastersEpoch) {
    Cluster cluster(topology);
    cluster.run(10);
    cluster.crash(PN3);
    cluster.run(10);
    ASSERT_TRUE(cluster.node(PN1).view().failed.contains(PN3));
    // ST1 says it has seen an epoch of PN3's far above: the Master must not move past it.
    for (int k = 0; k < 20; ++k) {
        Heartbeat heartbeat{ST1, 3 * 4000, cluster.node(ST1).monitor().incarnation(), false, 0, {}, false};
        heartbeat.seq = 1000 + static_cast<std::uint32_t>(k);
        cluster.inject(PN1, heartbeat);
        cluster.run(1);
    }
    EXPECT_LT(cluster.node(PN1).epoch(), 10u);
    EXPECT_GT(cluster.node(PN1).stats().ahead_dropped, 0u);
    EXPECT_TRUE(cluster.node(PN1).is_master());
}

TEST_F(NodeProtocolTest, OnlyTheStorageNodeAcknowledgesACheckpoint) {
    Cluster cluster(topology);
    cluster.run(10);
    // science moves taskB off PN3, which flushes it to ST1; ST1's ack is lost.
    cluster.block(ST1, PN3);
    cluster.request_phase(PN1, *topology.phase_id("science"));
    ASSERT_TRUE(cluster.node(PN3).config_switch().unflushed().contains(taskB));
    const Epoch epoch = cluster.node(PN3).epoch();
    cluster.inject(PN3, CheckpointAck{PN2, epoch, taskB, Version{0xFFFF, 1u << 30}});
    EXPECT_TRUE(cluster.node(PN3).config_switch().unflushed().contains(taskB));
    EXPECT_EQ(cluster.node(PN3).stats().unauthorized[6], 1u);
    cluster.unblock_all();
    cluster.run(3);
    EXPECT_TRUE(cluster.node(PN3).config_switch().unflushed().empty());
    EXPECT_EQ(cluster.node(PN1).view().config, id("S1"));
}

TEST_F(NodeProtocolTest, OnlyTheViewsMasterActivates) {
    Cluster cluster(topology);
    cluster.run(10);
    // ST1's Prepared ack is lost: the Master never activates the phase switch.
    cluster.block(ST1, PN1);
    cluster.request_phase(PN1, *topology.phase_id("science"));
    ASSERT_EQ(cluster.node(PN3).config_switch().stage(), Stage::Prepared);
    const View& view = cluster.node(PN3).view();
    cluster.inject(PN3, ActivateCommand{PN2, view.epoch, view.seq});
    EXPECT_EQ(cluster.node(PN3).config_switch().stage(), Stage::Prepared);
    EXPECT_EQ(cluster.node(PN3).stats().unauthorized[2], 1u);
    EXPECT_TRUE(cluster.running(PN3).empty());
}

TEST_F(NodeProtocolTest, OnlyMonitorsDeclareOtherNodes) {
    Cluster cluster(topology);
    cluster.run(10);
    // ST1 (no monitor) reports PN2 failed, every period: no exclusion, each counted.
    for (int k = 0; k < 10; ++k) {
        cluster.inject(PN1, ErrorNotification{ST1, cluster.node(ST1).epoch(), PN2});
        cluster.run(1);
    }
    EXPECT_TRUE(cluster.node(PN1).view().failed.empty());
    EXPECT_EQ(cluster.node(PN1).stats().unauthorized[4], 10u);
    // Its own exclusion any node may ask for.
    cluster.inject(PN1, ErrorNotification{ST1, cluster.node(ST1).epoch(), ST1});
    EXPECT_TRUE(cluster.node(PN1).view().failed.contains(ST1));
}

TEST_F(NodeProtocolTest, AStateFromALineageOfTheFutureIsNotStored) {
    Cluster cluster(topology);
    cluster.run(10);
    const Version before = *cluster.node(ST1).store()->latest_version(taskB);
    // PN3 may host taskB, but no view of epoch 500 exists: the version would pin the task.
    cluster.inject(ST1, CheckpointWrite{PN3, 1, taskB, {lineage_of(500, 1), 7}, true, {1}});
    EXPECT_EQ(*cluster.node(ST1).store()->latest_version(taskB), before);
    EXPECT_EQ(cluster.node(ST1).stats().unauthorized[5], 1u);
}

// The Storage node fails, and `asking` starts `task` from the holders; `holder`'s answer is
// held back (the test sends its own in its name).
void await_holders(Cluster& cluster, NodeId asking, NodeId holder, NodeId storage, TaskId task) {
    cluster.run(10);
    cluster.crash(storage);
    cluster.block_replies(holder, asking);
    for (int k = 0; k < 8 && !cluster.node(asking).config_switch().restoring().contains(task); ++k) cluster.run(1);
    ASSERT_TRUE(cluster.node(asking).config_switch().restoring().contains(task));
}

TEST(NodeProtocolValueFaults, ATasksStateComesOnlyFromANodeTheMissionMayPlaceItOn) {
    // prototype3 with an interface node IF1, which the mission never places a task on.
    keel::mission::Mission mission = testing::prototype3();
    keel::mission::Node interface;
    interface.name = "IF1";
    interface.kind = keel::mission::NodeKind::interface;
    mission.nodes.push_back(interface);
    const Topology topology = testing::topology_of(mission);
    const NodeId PN1 = 0, ST1 = 3, IF1 = 4;
    const TaskId taskB = 1;
    ASSERT_FALSE(topology.may_host(taskB).contains(IF1));
    Cluster cluster(topology);
    cluster.run(10);
    // ST1 fails: safe mode runs the essential taskB on PN1, from its last holder's state
    // (PN3's hand-off), gathered from every member. IF1's honest answer is lost.
    cluster.crash(ST1);
    cluster.block_replies(IF1, PN1);
    for (int k = 0; k < 8 && !cluster.node(PN1).config_switch().restoring().contains(taskB); ++k) cluster.run(1);
    ASSERT_TRUE(cluster.node(PN1).view().is_safe());
    ASSERT_TRUE(cluster.node(PN1).config_switch().restoring().contains(taskB));
    const View& view = cluster.node(PN1).view();
    const Version forged{lineage_of(view.epoch, view.seq), 1u << 20};
    cluster.inject(PN1, CheckpointReply{IF1, view.epoch, view.seq, taskB, true, forged, {0xEE}});
    EXPECT_EQ(cluster.node(PN1).stats().unauthorized[8], 1u);
    // It answers the request as holding nothing: the restore completes without it.
    cluster.unblock_all();
    cluster.run(2);
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    EXPECT_LT(cluster.last_activation_version(taskB).count, forged.count);
    EXPECT_GT(cluster.last_activation_version(taskB).count, 0u);
}

// The protocol fuzzer's finding: a forged state of the largest step count the codec
// carries, stored by the Storage node (it stores any such count) and taken by a correct
// host, whose next step makes a version no codec decodes; every later write of the task
// refused, a switch waiting for its flush stalls. A count above kMaxAdoptedCount is none a
// correct run reaches: the node it is offered to treats it as lost, on each of the three
// ways a state is taken (spec/ValueFault.tla, Adoptable).
TEST(NodeProtocolValueFaults, AStoredCountNoCorrectRunReachesIsTreatedAsLost) {
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    const TaskId taskB = 1;
    ASSERT_TRUE(topology.may_host(taskB).contains(PN2));
    Cluster cluster(topology);
    cluster.run(10);
    // PN2 (not taskB's host) writes taskB at the width, in the stored state's lineage; its
    // host PN3 fails before its next write could replace the pin (host_wins).
    const auto before = cluster.node(ST1).store()->latest_version(taskB);
    ASSERT_TRUE(before.has_value());
    const Version forged{before->lineage, kMaxVersionCount};
    cluster.inject(ST1, CheckpointWrite{PN2, cluster.node(ST1).epoch(), taskB, forged, false, {0xEE}});
    ASSERT_EQ(cluster.node(ST1).store()->latest_version(taskB), forged);
    cluster.crash(PN3);
    cluster.run(10);
    // P4: taskB on PN1, which starts it from no state in a lineage of its view.
    const View& view = cluster.node(PN1).view();
    ASSERT_EQ(view.config, *topology.config_id("P4"));
    ASSERT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.node(PN1).config_switch().unadoptable_states(), 1u);
    const Version running = cluster.node(PN1).config_switch().version(taskB);
    EXPECT_EQ(running.lineage, lineage_of(view.epoch, view.seq));
    EXPECT_LT(running.count, 20u);
    // Its writes decode, and the Storage node takes them over the forged state.
    const auto write = decode(encode(CheckpointWrite{PN1, view.epoch, taskB, running, false, {0x01}}));
    EXPECT_TRUE(write.ok()) << write.detail;
    const auto stored = cluster.node(ST1).store()->latest_version(taskB);
    ASSERT_TRUE(stored.has_value());
    EXPECT_EQ(stored->lineage, running.lineage);
    EXPECT_GT(stored->count, 0u);
}

TEST(NodeProtocolValueFaults, AHolderOfACountNoCorrectRunReachesCountsAsHoldingNothing) {
    // The same forged count, in a holder's reply while the Storage node is out: at
    // kMaxAdoptedCount it is taken (the bound itself is adoptable), one above it is not.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, ST1 = 3;
    const TaskId taskB = 1;
    for (const std::uint64_t count : {kMaxAdoptedCount, kMaxAdoptedCount + 1}) {
        SCOPED_TRACE(count);
        const bool taken = count <= kMaxAdoptedCount;
        Cluster cluster(topology);
        ASSERT_NO_FATAL_FAILURE(await_holders(cluster, PN1, PN2, ST1, taskB));
        const View& view = cluster.node(PN1).view();
        const Version forged{lineage_of(view.epoch, view.seq), count};
        cluster.inject(PN1, CheckpointReply{PN2, view.epoch, view.seq, taskB, true, forged, {0xEE}});
        EXPECT_EQ(cluster.node(PN1).config_switch().unadoptable_states(), taken ? 0u : 1u);
        cluster.unblock_all();
        cluster.run(2);
        EXPECT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
        const std::uint64_t running = cluster.node(PN1).config_switch().version(taskB).count;
        if (taken) {
            EXPECT_GE(running, kMaxAdoptedCount);
        } else {
            EXPECT_LT(running, 100u);
        }
    }
}

TEST(NodeProtocolValueFaults, AStateOfALineageNewerThanTheRequestIsNotRestored) {
    // keel-sim --liar: a restored state of a lineage of the future makes every later write
    // of its new host one the Storage node refuses. A node the mission may place taskB on
    // answers the restore with such a state: dropped as ahead (an honest node overtaken by
    // a newer Master answers so too), and the restore completes without it.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, ST1 = 3;
    const TaskId taskB = 1;
    ASSERT_TRUE(topology.may_host(taskB).contains(PN2));
    Cluster cluster(topology);
    ASSERT_NO_FATAL_FAILURE(await_holders(cluster, PN1, PN2, ST1, taskB));
    const View& view = cluster.node(PN1).view();
    const Version forged{lineage_of(view.epoch + 3, 1), 1u << 20};
    const auto ahead = cluster.node(PN1).stats().ahead_dropped;
    cluster.inject(PN1, CheckpointReply{PN2, view.epoch, view.seq, taskB, true, forged, {0xEE}});
    EXPECT_EQ(cluster.node(PN1).stats().ahead_dropped, ahead + 1);
    EXPECT_EQ(cluster.node(PN1).stats().unauthorized[8], 0u);
    cluster.unblock_all();
    cluster.run(2);
    EXPECT_TRUE(cluster.node(PN1).config_switch().active().contains(taskB));
    EXPECT_LT(cluster.last_activation_version(taskB).count, forged.count);
}

TEST_F(NodeProtocolTest, TheStorageNodeStoresNoLineageOfAnEpochItHasNotAdopted) {
    // A value-faulty PN3 (the mission may place taskB on it) writes taskB in a lineage two
    // epochs ahead, with its epoch claimed as that one (within the adoptable bound): no
    // view of that epoch opened it here, so the Storage node keeps what it had.
    Cluster cluster(topology);
    cluster.run(10);
    const auto before = cluster.node(ST1).store()->latest_version(taskB);
    ASSERT_TRUE(before.has_value());
    const Epoch ahead = cluster.node(ST1).epoch() + 2;
    const auto dropped = cluster.node(ST1).stats().ahead_dropped;
    cluster.inject(ST1, CheckpointWrite{PN3, ahead, taskB, Version{lineage_of(ahead, 1), 1u << 30}, false, {0x01}});
    EXPECT_EQ(cluster.node(ST1).store()->latest_version(taskB), before);
    EXPECT_EQ(cluster.node(ST1).stats().ahead_dropped, dropped + 1);
}

TEST(NodeProtocolValueFaults, ANodeThatTookOverBoundsTheEpochsItHears) {
    // keel-sim --liar, prototype3 seed 12: the value-faulty PN1 booted late and no Command
    // of its reached PN2; then one heartbeat of PN1's said it was excluded (PN2 took over
    // epoch 2 on that word, within the step) and had seen an epoch of PN1's far above,
    // which PN2, never commanded, noted and reclaimed past: an epoch no node follows, and
    // the cluster never switched again. A node that opened its epoch itself knows it as
    // well as one commanded (mutant unbounded-master-epoch: it does not, and the epoch
    // runs away).
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1;
    const Epoch far = 3 * 4000 + 1;  // PN1's
    ASSERT_EQ(topology.owner(far), PN1);
    for (const Mutant mutant : {Mutant::none, Mutant::unbounded_master_epoch}) {
        NodeSet late;
        late.insert(PN1);
        Cluster cluster(topology, late, {}, mutant);
        cluster.run(topology.miss_limit() + 1);
        ASSERT_FALSE(cluster.node(PN2).is_master());
        Heartbeat lie{PN1, far, 1, true, 1, {}, false};
        cluster.inject(PN2, lie);
        ASSERT_TRUE(cluster.node(PN2).is_master()) << to_string(mutant);
        cluster.run(2 * topology.miss_limit());
        if (mutant == Mutant::none) {
            EXPECT_LT(cluster.node(PN2).epoch(), 20u);
            EXPECT_GT(cluster.node(PN2).stats().ahead_dropped, 0u);
        } else {
            EXPECT_GT(cluster.node(PN2).epoch(), far);
        }
    }
}

TEST(NodeProtocolValueFaults, ARunOfCommandsMovesTheEpochNoFasterThanALapAPeriod) {
    // spec/EpochBound.tla (mutant EpochBoundPerCommand): a value-faulty PN1 sends PN2 a
    // run of Commands within one period, each a lap above the last. Each is within a lap
    // of the epoch PN2 adopted just before; a bound anchored at every adoption let them
    // take PN2 from epoch 1 to 301 in 0.4 ms. The bound grows a lap a period since PN2
    // adopted epoch 1 (at the boot switch, ten periods ago), whatever PN2 adopts meanwhile,
    // and an adoption that lowers it re-anchors it: PN2 follows two, drops the rest.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1;
    const Epoch lap = epoch_lap(topology);
    Cluster cluster(topology);
    cluster.run(10);
    ASSERT_EQ(cluster.node(PN2).epoch(), 1u);
    const TimeNs start = cluster.now();
    View forged = cluster.node(PN2).view();
    forged.master = PN1;
    forged.seq = 1;
    const auto dropped = cluster.node(PN2).stats().ahead_dropped;
    for (Epoch e = 1 + lap; e <= 1 + 100 * lap; e += lap) {
        ASSERT_EQ(topology.owner(e), PN1);
        forged.epoch = e;
        cluster.inject(PN2, Command{PN1, forged});
    }
    ASSERT_LT(cluster.now() - start, P);
    EXPECT_LE(cluster.node(PN2).epoch(), 1 + lap * (1 + 10));
    EXPECT_EQ(cluster.node(PN2).epoch(), 1 + 2 * lap);
    EXPECT_GE(cluster.node(PN2).stats().ahead_dropped, dropped + 98);
}

TEST(NodeProtocolValueFaults, ANodeThatKnowsNoEpochCountsEachReportFromWhenItWasHeard) {
    // spec/EpochBound.tla: a restarted ST1, no Command of which reached it for five
    // periods, heard epoch 1 from the others since it booted and epoch 4 from PN3 just now.
    // The first Command it follows may be a lap above each, plus a lap per period since
    // each was heard: 1 + 3 x 6 = 19. Counting every report from its boot (4 + 3 x 6) let
    // a liar's 22 in: the wait was counted twice.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    for (NodeId n : {PN1, PN2, PN3}) cluster.block_commands(n, ST1);
    cluster.crash(ST1);
    cluster.restart(ST1);
    cluster.run(5);
    ASSERT_EQ(cluster.node(ST1).epoch(), 1u);
    Heartbeat report{PN3, 4, cluster.node(PN3).monitor().incarnation(), false, 0, {}, false};
    report.seq = 9000;
    cluster.inject(ST1, report);
    View forged = cluster.node(ST1).view();
    forged.master = PN1;
    forged.seq = 1;
    for (const Epoch e : {22u, 19u}) {
        ASSERT_EQ(topology.owner(e), PN1);
        forged.epoch = e;
        cluster.inject(ST1, Command{PN1, forged});
    }
    EXPECT_EQ(cluster.node(ST1).epoch(), 19u);
    EXPECT_GE(cluster.node(ST1).stats().ahead_dropped, 1u);
}

TEST(NodeProtocolValueFaults, NoMasterReadmitsIntoAnEpochBeyondTheWidth) {
    // spec/EpochBound.tla (ReadmitBy, TopLapInv; mutant EpochBoundReadmitOpens): a
    // readmission opens an epoch, the readmitting Master's next or, handed over, the next
    // of the configuration's Master. A cluster whose saved epochs are near the width
    // warm-boots (PN1 Master of the epoch it owns below the top), PN1 dies and PN2 takes
    // over into the epoch below the top; PN1 comes back. Readmitting it would open an
    // epoch beyond the last one a node adopts (PN1's or PN2's next), which every other
    // node refuses as proof: PN2 would adopt it and be cut off. PN2 stays Master
    // where it is, counts the refusal, and PN1 stays out.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    const Epoch top = max_adoptable_epoch(topology);
    ASSERT_EQ(topology.owner(top), PN3);
    for (NodeId n : {PN1, PN2, PN3, ST1}) cluster.crash(n);
    for (NodeId n : {PN2, PN3, ST1, PN1}) cluster.restart(n, Mutant::none, top - 3);
    cluster.run(15);
    ASSERT_TRUE(cluster.node(PN1).is_master());
    ASSERT_EQ(cluster.node(PN1).epoch(), top - 2);
    cluster.crash(PN1);
    for (int k = 0; k < 40 && !cluster.node(PN2).is_master(); ++k) cluster.run(1);
    ASSERT_TRUE(cluster.node(PN2).is_master());
    ASSERT_EQ(cluster.node(PN2).epoch(), top - 1);
    const std::uint64_t readmissions = cluster.node(PN2).stats().readmissions;
    ASSERT_EQ(cluster.node(PN2).stats().readmissions_refused, 0u);
    cluster.restart(PN1);
    cluster.run(40);
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN2).epoch(), top - 1);
    for (NodeId n : {PN1, PN2, PN3, ST1}) EXPECT_LE(cluster.node(n).epoch(), top) << n;
    EXPECT_GE(cluster.node(PN2).stats().readmissions_refused, 1u);
    EXPECT_EQ(cluster.node(PN2).stats().readmissions, readmissions);
    EXPECT_EQ(cluster.node(PN3).stats().commands_refused, 0u);
}

TEST(NodeProtocolValueFaults, NoMasterOpensAnEpochWithinALapOfTheWidth) {
    // spec/EpochBound.tla (TopLapInv; mutant EpochBoundTopLapOpens): a cluster whose saved
    // epochs are near the width warm-boots; PN2 takes over when PN1 dies, and a
    // value-faulty ST1 says in its heartbeats it follows the last adoptable epoch (PN3's).
    // Moving past it would open an epoch within a lap of kMaxEpoch, whose Commands every
    // other node refuses as proof: PN2 stays Master where it is, and PN1, restarted,
    // follows it.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    const Epoch top = max_adoptable_epoch(topology);
    ASSERT_EQ(topology.owner(top), PN3);
    for (NodeId n : {PN1, PN2, PN3, ST1}) cluster.crash(n);
    for (NodeId n : {PN2, PN3, ST1, PN1}) cluster.restart(n, Mutant::none, top - 3);
    cluster.run(15);
    ASSERT_TRUE(cluster.node(PN1).is_master());
    cluster.crash(PN3);
    cluster.run(10);
    cluster.crash(PN1);
    for (int k = 0; k < 40 && !cluster.node(PN2).is_master(); ++k) cluster.run(1);
    ASSERT_TRUE(cluster.node(PN2).is_master());
    const Epoch mastered = cluster.node(PN2).epoch();
    for (int k = 0; k < topology.miss_limit() + 3; ++k) {
        Heartbeat lie{ST1, top, cluster.node(ST1).monitor().incarnation(), false, 0, {}, false};
        lie.seq = 7000 + static_cast<std::uint32_t>(k);
        cluster.inject(PN2, lie);
        cluster.run(1);
    }
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN2).epoch(), mastered);
    EXPECT_LE(cluster.node(PN2).epoch(), top);
    EXPECT_GE(cluster.node(PN2).stats().take_overs_refused, 1u);
    cluster.restart(PN1);
    cluster.run(10);
    EXPECT_EQ(cluster.node(PN1).epoch(), mastered);
    EXPECT_EQ(cluster.node(PN1).stats().commands_refused, 0u);
}

TEST(NodeProtocolValueFaults, AMasterMovesPastAnEpochOfItsOwnItNeverOpened) {
    // keel-sim --liar, earth-observation seed 25282: a value-faulty former Master handed
    // an epoch of PN2's over to PN2 after PN2 had replaced it; a node that followed says so
    // in its heartbeats, and rejects every Command of PN2's older epoch as stale. PN2,
    // which never opened that epoch, moves past it as it does past a failed Master's.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2;
    Cluster cluster(topology);
    cluster.run(10);
    cluster.crash(PN1);
    for (int k = 0; k < 40 && !cluster.node(PN2).is_master(); ++k) cluster.run(1);
    ASSERT_TRUE(cluster.node(PN2).is_master());
    const Epoch own = cluster.node(PN2).epoch() + epoch_lap(topology);  // PN2's next
    ASSERT_EQ(topology.owner(own), PN2);
    for (int k = 0; k < topology.miss_limit() + 2; ++k) {
        Heartbeat heartbeat{PN3, own, cluster.node(PN3).monitor().incarnation(), false, 0, {}, false};
        heartbeat.seq = 5000 + static_cast<std::uint32_t>(k);
        cluster.inject(PN2, heartbeat);
        cluster.run(1);
    }
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_GT(cluster.node(PN2).epoch(), own);
}

TEST(NodeProtocolValueFaults, AnObserverTakesOverFromAMasterThatLeftItsViewForAnEpochNoCommandOfWhichCame) {
    // keel-sim --liar, earth-observation seed 13921: the view's Master followed a newer
    // epoch (a liar's, sent to it alone) and never drove the view again; nothing of that
    // epoch ever reached the others. PN2 (first Observer) hears PN1's heartbeats say so
    // (only those: PN1's own to PN2 are lost) for 3 miss_limit periods, declares PN1 on its
    // word ("left") and takes over, in an epoch above the one PN1 follows. Under the mutant
    // no_master_left it waits for ever (PN1 is heard every period).
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1;
    for (const Mutant mutant : {Mutant::none, Mutant::no_master_left}) {
        SCOPED_TRACE(std::string(to_string(mutant)));
        Cluster cluster(topology, {}, {}, mutant);
        cluster.run(10);
        ASSERT_TRUE(cluster.node(PN1).is_master());
        const Epoch followed = cluster.node(PN1).epoch() + 2;  // PN3's next: not PN1's
        ASSERT_NE(topology.owner(followed), PN1);
        cluster.block(PN1, PN2);
        const int periods = 3 * topology.miss_limit() + 2;
        for (int k = 0; k < periods && !cluster.node(PN2).is_master(); ++k) {
            Heartbeat heartbeat{PN1, followed, cluster.node(PN1).monitor().incarnation(), false, 0, {}, false};
            heartbeat.seq = 5000 + static_cast<std::uint32_t>(k);
            cluster.inject(PN2, heartbeat);
            cluster.run(1);
        }
        if (mutant == Mutant::none) {
            EXPECT_EQ(cluster.node(PN2).stats().masters_left, 1u);
            EXPECT_TRUE(cluster.node(PN2).is_master());
            EXPECT_GT(cluster.node(PN2).epoch(), followed);
        } else {
            EXPECT_EQ(cluster.node(PN2).stats().masters_left, 0u);
            EXPECT_FALSE(cluster.node(PN2).is_master());
        }
    }
}

TEST(NodeProtocolValueFaults, AnObserverTakesOverFromAMasterThatNeverTookTheViewItWasHanded) {
    // spec/ElectionLiar.tla (rule 2, a Master behind its view): a value-faulty PN1 hands
    // PN3 and ST1 a view naming PN2 Master in PN2's next epoch, and goes on as PN2's Master
    // (its heartbeats to PN2 say epoch 1). PN2 never gets the hand-over, so it never
    // commands that view; its heartbeats say an epoch below PN3's view. After 3 miss_limit
    // periods PN3, that view's first Observer, declares PN2 on its word ("left") and takes
    // over above the handed epoch. (A Master ahead of its view is the case above.)
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    ASSERT_TRUE(cluster.node(PN1).is_master());
    const View before = cluster.node(PN3).view();
    View handed;
    handed.epoch = topology.next_epoch(PN2, before.epoch);
    handed.seq = 0;
    handed.config = handed.base = *topology.config_id("P2");
    handed.master = PN2;
    handed.failed.insert(PN1);
    cluster.stop(PN1);
    // As an honest resigning Master does, it says first that it is excluded (its own word
    // backs the exclusion the hand-over adds).
    Heartbeat resigning{PN1, before.epoch, cluster.node(PN1).monitor().incarnation(), true, 4000, {}, false};
    cluster.inject(PN3, resigning);
    cluster.inject(ST1, resigning);
    cluster.inject(PN3, Command{PN1, handed});
    cluster.inject(ST1, Command{PN1, handed});
    ASSERT_EQ(cluster.node(PN3).view().epoch, handed.epoch) << cluster.node(PN3).last_refusal();
    ASSERT_EQ(cluster.node(PN3).view().master, PN2);
    const int periods = 3 * topology.miss_limit() + 3;
    for (int k = 0; k < periods && !cluster.node(PN3).is_master(); ++k) {
        Heartbeat heartbeat{PN1, before.epoch, cluster.node(PN1).monitor().incarnation(), false, 0, {}, false};
        heartbeat.seq = 5000 + static_cast<std::uint32_t>(k);
        cluster.inject(PN2, heartbeat);
        cluster.run(1);
    }
    EXPECT_EQ(cluster.node(PN3).stats().masters_left, 1u);
    EXPECT_TRUE(cluster.node(PN3).is_master());
    EXPECT_GT(cluster.node(PN3).epoch(), handed.epoch);
    // PN2 follows the take-over, an epoch above the one PN1 keeps it in.
    cluster.run(2);
    EXPECT_EQ(cluster.node(PN2).view().master, PN3);
    EXPECT_EQ(cluster.node(PN2).epoch(), cluster.node(PN3).epoch());
}

TEST(NodeProtocolValueFaults, AMemberAheadThatNeverTookTheViewIsPassedOver) {
    // NodeProtocol::diverged_members (keel-sim --liar --loss 5%, prototype3 seed 826): a
    // value-faulty PN1 commands PN3 and ST1 into an epoch of its own (4), and goes on as
    // PN2's Master in epoch 1, silent to the others. PN3 declares PN1, but PN2, ahead of
    // it in the succession, is heard every period and never takes over: its heartbeats
    // say epoch 1, a view it is in that PN3's is not. PN3 passes it over after 2 miss_limit
    // periods and takes over; PN2 follows. Without the rule PN3 waits for ever.
    const Topology topology = testing::topology_of(testing::prototype3());
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    View ahead = cluster.node(PN3).view();
    ahead.epoch = 4;
    ASSERT_EQ(topology.owner(ahead.epoch), PN1);
    ahead.seq = 1;
    cluster.stop(PN1);
    cluster.inject(PN3, Command{PN1, ahead});
    cluster.inject(ST1, Command{PN1, ahead});
    ASSERT_EQ(cluster.node(PN3).view().epoch, 4u);
    ASSERT_EQ(cluster.node(PN2).view().epoch, 1u);
    const int periods = 8 * topology.miss_limit();
    for (int k = 0; k < periods && !cluster.node(PN3).is_master(); ++k) {
        Heartbeat heartbeat{PN1, 1, cluster.node(PN1).monitor().incarnation(), false, 0, {}, false};
        heartbeat.seq = 6000 + static_cast<std::uint32_t>(k);
        cluster.inject(PN2, heartbeat);
        cluster.run(1);
    }
    EXPECT_TRUE(cluster.node(PN3).is_master());
    EXPECT_GT(cluster.node(PN3).epoch(), 4u);
    EXPECT_FALSE(cluster.node(PN2).is_master());
    cluster.run(2);
    EXPECT_EQ(cluster.node(PN2).epoch(), cluster.node(PN3).epoch());
}

TEST_F(NodeProtocolTest, AHandOverNeverExcludesItsReceiver) {
    // A hand-over is sent only to the nodes its view keeps. One excluding its receiver
    // fences it in another node's name (keel-sim --liar, prototype3 seed 119042): refused.
    Cluster cluster(topology);
    cluster.run(10);
    const View before = cluster.node(PN3).view();
    View handed;
    handed.epoch = topology.next_epoch(PN2, before.epoch);
    handed.seq = 0;
    handed.config = handed.base = id("P2");
    handed.master = PN2;
    handed.failed.insert(PN1);
    handed.failed.insert(PN3);
    const auto refused = cluster.node(PN3).stats().unauthorized[1];
    cluster.inject(PN3, Command{PN1, handed});
    EXPECT_EQ(cluster.node(PN3).stats().unauthorized[1], refused + 1);
    EXPECT_EQ(cluster.node(PN3).view(), before);
    EXPECT_FALSE(cluster.node(PN3).config_switch().excluded());
}

TEST_F(NodeProtocolTest, AHandedViewIsNoEdgeTheNewMastersFirstSwitchIsHeldTo) {
    // keel-sim --liar --max-failures 1, prototype3 seed 15049: a value-faulty Master hands
    // its successor one view and the Storage node another under the same id (seq 0). The
    // successor's boot switch, true to its own copy, follows no edge from the Storage
    // node's: that is the handing Master's lie, no proof against the successor. ST1
    // follows it (its view is one the graph places) and holds no one failed for it.
    Cluster cluster(topology);
    cluster.run(10);
    View handed;
    handed.epoch = topology.next_epoch(PN2, cluster.node(ST1).view().epoch);
    handed.seq = 0;
    handed.config = handed.base = id("P2");
    handed.master = PN2;
    cluster.inject(ST1, Command{PN1, handed});
    ASSERT_EQ(cluster.node(ST1).view(), handed);
    View boot = handed;  // what PN2 was handed instead: safe mode, entered from P2
    boot.seq = 1;
    boot.config = kSafeConfig;
    cluster.inject(ST1, Command{PN2, boot});
    EXPECT_EQ(cluster.node(ST1).stats().commands_refused, 0u) << cluster.node(ST1).last_refusal();
    EXPECT_EQ(cluster.node(ST1).view(), boot);
    // The same switch from a view PN2 commanded itself (seq 1) is held to the graph.
    View next = boot;
    next.seq = 2;
    next.config = next.base = id("S2");  // PN2's, but safe mode entered in nominal
    cluster.inject(ST1, Command{PN2, next});
    EXPECT_EQ(cluster.node(ST1).stats().commands_refused, 1u);
    EXPECT_NE(cluster.node(ST1).last_refusal().find("is left only for a configuration of that phase"),
              std::string::npos)
        << cluster.node(ST1).last_refusal();
}

TEST_F(NodeProtocolTest, AMemberThatPreparedAnotherViewUnderTheSameIdIsPassedOver) {
    // keel-sim --liar, prototype3 seed 30979: a value-faulty Master sends one view to PN3
    // (P1, where PN2 is the first Observer) and another under the same id to PN2 (P3,
    // where PN2 is a Worker), then dies. PN2 never takes over; PN3 sees PN2 prepare
    // another view, and after 2 miss_limit periods passes it over and takes over.
    Cluster cluster(topology);
    cluster.run(10);
    View honest = cluster.node(PN3).view();
    honest.epoch = topology.next_epoch(PN1, honest.epoch);
    honest.seq = 1;
    View changed = honest;
    changed.config = changed.base = id("P3");
    cluster.inject(PN3, Command{PN1, honest});
    cluster.inject(PN2, Command{PN1, changed});
    ASSERT_EQ(cluster.node(PN3).view(), honest);
    ASSERT_EQ(cluster.node(PN2).view(), changed);
    EXPECT_GE(cluster.node(PN3).stats().prepared_diverged, 1u);
    cluster.crash(PN1);
    cluster.run(4 * topology.miss_limit() + 4);
    EXPECT_FALSE(cluster.node(PN2).is_master());
    EXPECT_TRUE(cluster.node(PN3).is_master());
    EXPECT_EQ(cluster.node(PN2).view().master, PN3);
    EXPECT_FALSE(cluster.node(PN3).view().failed.contains(PN2));
}

// prototype3 with PN2 a Worker in S1 (its Observer PN3 alone), so that a member ahead in
// P1 is a Worker in the phase switch P1 to S1.
Topology prototype3_s1_without_pn2() {
    keel::mission::Mission mission = testing::prototype3();
    for (keel::mission::Phase& phase : mission.phases) {
        for (keel::mission::Configuration& config : phase.configurations) {
            if (config.name == "S1") config.observers = {"PN3"};
        }
    }
    return testing::topology_of(mission);
}

// spec/DivergedView.tla, MCDivergedViewLost: the Master's switch reaches PN2 (and the
// Storage node) but its copy to PN3 is lost, and the Master dies before repeating it
// (and, with `restart`, comes back as a Worker waiting to be commanded). PN2 goes by the
// newer view, where it is a Worker waiting for PN3; PN3 goes by the view before, where
// PN2 is the first Observer. PN2's Prepared names a newer switch of PN3's epoch, and PN2
// no longer hears that epoch's Master: PN3 passes it over after 2 miss_limit periods and
// takes over, and PN2 follows. Passing over only a member that prepared another view
// under PN3's own id (the rule before) left PN3 waiting for ever.
void a_newer_switch_lost_to_pn3(bool restart) {
    const Topology topology = prototype3_s1_without_pn2();
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    const View before = cluster.node(PN3).view();
    ASSERT_EQ(topology.config_name(before.config), "P1");
    View newer = before;  // the phase switch PN1 commands, P1 to S1 (a phase edge)
    newer.seq = before.seq + 1;
    newer.config = newer.base = *topology.config_id("S1");
    cluster.inject(PN2, Command{PN1, newer});
    cluster.inject(ST1, Command{PN1, newer});
    cluster.crash(PN1);
    ASSERT_EQ(cluster.node(PN2).view(), newer) << cluster.node(PN2).last_refusal();
    ASSERT_EQ(cluster.node(PN3).view(), before);
    ASSERT_TRUE(cluster.node(PN3).config_switch().prepared_newer_switch(PN2));
    if (restart) {
        cluster.run(1);
        cluster.restart(PN1);
    }
    for (int k = 0; k < 6 * topology.miss_limit() + 4 && !cluster.node(PN3).is_master(); ++k) cluster.run(1);
    EXPECT_FALSE(cluster.node(PN2).is_master());
    ASSERT_TRUE(cluster.node(PN3).is_master());
    EXPECT_EQ(cluster.node(PN3).stats().passed_over, 1u);
    EXPECT_EQ(cluster.node(PN3).stats().prepared_diverged, 0u);
    cluster.run(2);
    EXPECT_EQ(cluster.node(PN2).view().master, PN3);
    EXPECT_EQ(cluster.node(ST1).view().master, PN3);
    EXPECT_FALSE(cluster.node(PN3).view().failed.contains(PN2));
}

TEST(NodeProtocolValueFaults, AMemberThatPreparedANewerSwitchThisNodeNeverReceivedIsPassedOver) {
    a_newer_switch_lost_to_pn3(false);
}

TEST(NodeProtocolValueFaults, AMemberThatPreparedANewerSwitchIsPassedOverWhenItHearsTheMasterRestarted) {
    a_newer_switch_lost_to_pn3(true);
}

TEST(NodeProtocolValueFaults, AMemberWhoseHeartbeatsSayANewerEpochIsNotPassedOver) {
    // The newer switch lost to PN3, as above; then PN2 also takes PN1's switch into PN1's
    // next epoch (a Command sent before PN1 crashed), and its Prepared of it never reaches
    // PN3. PN3 still knows PN2's Prepared of the newer switch of its own epoch, but PN2's
    // heartbeats say the newer epoch: PN2 is no member of another switch of PN3's epoch,
    // and a take-over by PN3 in an epoch PN2 may not follow is no pass-over the election's
    // trace spec allows (PassOver: heard at most the taker's epoch). PN3 does not pass it
    // over (NodeProtocol::diverged_members, `in_epoch`).
    const Topology topology = prototype3_s1_without_pn2();
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    const View before = cluster.node(PN3).view();
    View newer = before;
    newer.seq = before.seq + 1;
    newer.config = newer.base = *topology.config_id("S1");
    cluster.inject(PN2, Command{PN1, newer});
    cluster.inject(ST1, Command{PN1, newer});
    View next_epoch = newer;
    next_epoch.epoch = topology.next_epoch(PN1, newer.epoch);
    next_epoch.seq = 1;
    cluster.block_acks(PN2, PN3);
    cluster.inject(PN2, Command{PN1, next_epoch});
    cluster.crash(PN1);
    ASSERT_EQ(cluster.node(PN2).view(), next_epoch) << cluster.node(PN2).last_refusal();
    ASSERT_EQ(cluster.node(PN3).view(), before);
    ASSERT_TRUE(cluster.node(PN3).config_switch().prepared_newer_switch(PN2));
    for (int k = 0; k < 6 * topology.miss_limit() + 4; ++k) cluster.run(1);
    EXPECT_EQ(cluster.node(PN3).stats().passed_over, 0u);
    EXPECT_LE(cluster.running_masters(), 1);
    EXPECT_FALSE(cluster.task_on_two_nodes());
}

TEST(NodeProtocolValueFaults, AMemberWhosePreparedOfThisViewNeverCameIsPassedOver) {
    // spec/DivergedView.tla, NeverPrepared: the cluster goes to science (S1, PN2 a Worker
    // there) and back to nominal (P1, PN2 the first Observer), but the Command of the way
    // back never reaches PN2, and the Master dies. PN2 goes by S1, waiting for PN3; PN3
    // goes by P1, where PN2 is ahead of it, and never hears PN2 prepare P1: it passes PN2
    // over after 2 miss_limit periods and takes over, and PN2 follows. (keel-sim --liar:
    // a lying Master's two switches of one epoch, one to each, leave the same.)
    const Topology topology = prototype3_s1_without_pn2();
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    Cluster cluster(topology);
    cluster.run(10);
    cluster.request_phase(PN1, *topology.phase_id("science"));
    cluster.run(5);
    ASSERT_EQ(topology.config_name(cluster.node(PN2).view().config), "S1");
    ASSERT_EQ(cluster.node(PN2).config_switch().stage(), Stage::Stable);
    cluster.block_commands(PN1, PN2);
    cluster.request_phase(PN1, *topology.phase_id("nominal"));
    cluster.run(1);
    cluster.crash(PN1);
    ASSERT_EQ(topology.config_name(cluster.node(PN3).view().config), "P1");
    ASSERT_EQ(topology.config_name(cluster.node(PN2).view().config), "S1");
    ASSERT_EQ(cluster.node(PN3).view().epoch, cluster.node(PN2).view().epoch);
    for (int k = 0; k < 6 * topology.miss_limit() + 4 && !cluster.node(PN3).is_master(); ++k) cluster.run(1);
    EXPECT_FALSE(cluster.node(PN2).is_master());
    ASSERT_TRUE(cluster.node(PN3).is_master());
    EXPECT_EQ(cluster.node(PN3).stats().passed_over, 1u);
    cluster.run(2);
    EXPECT_EQ(cluster.node(PN2).view().master, PN3);
    EXPECT_EQ(cluster.node(ST1).view().master, PN3);
}

TEST_F(NodeProtocolTest, AnObserverThatBootedAfterTheBootSwitchIsNotPassedOverForNeverPreparingIt) {
    // keel-sim earth-observation seed 7050: PN2 boots after PN1's boot switch (seq 1) and
    // PN1's crash. PN2 never prepared PN3's view, but it goes by the epoch's first view,
    // the initial one, where it is the first Observer and takes over in its own time: PN3
    // does not pass it over (the rule holds at seq >= 2 only), and PN2 takes over.
    NodeSet late;
    late.insert(PN2);
    Cluster cluster(topology, late);
    cluster.run(10);
    ASSERT_EQ(cluster.node(PN3).view().seq, 1u);
    cluster.crash(PN1);
    cluster.run(1);
    cluster.boot(PN2);
    for (int k = 0; k < 30 && !cluster.node(PN2).is_master() && !cluster.node(PN3).is_master(); ++k) {
        cluster.run(1);
    }
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_FALSE(cluster.node(PN3).is_master());
    EXPECT_EQ(cluster.node(PN3).stats().passed_over, 0u);
}

TEST_F(NodeProtocolTest, AnObserverAheadThatTookANewerSwitchTakesOverItselfAndIsNotPassedOver) {
    // The same lost copy, in the shipped mission: PN2 is the first Observer of the newer
    // view (S1) as of the one before (P1). It takes over within miss_limit periods, before
    // PN3's wait of 2 miss_limit periods ends, and PN3 follows it: one take-over.
    Cluster cluster(topology);
    cluster.run(10);
    const View before = cluster.node(PN3).view();
    View newer = before;
    newer.seq = before.seq + 1;
    newer.config = newer.base = id("S1");
    cluster.inject(PN2, Command{PN1, newer});
    cluster.inject(ST1, Command{PN1, newer});
    cluster.crash(PN1);
    ASSERT_EQ(cluster.node(PN2).view(), newer) << cluster.node(PN2).last_refusal();
    cluster.run(6 * topology.miss_limit() + 4);
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_FALSE(cluster.node(PN3).is_master());
    EXPECT_EQ(cluster.node(PN3).stats().passed_over, 0u);
    EXPECT_EQ(cluster.node(PN3).view().master, PN2);
}

TEST_F(NodeProtocolTest, AMemberThatTookANewerSwitchAndStillHearsTheMasterIsNotPassedOver) {
    // keel-sim prototype3 seed 12313 (--loss 5%): PN3 cannot hear PN1, so it misses PN1's
    // switch that PN2 takes, and declares PN1. PN2's Prepared names a newer switch of
    // PN3's epoch, but PN2 still hears PN1 (its acknowledgements of PN1's heartbeats move
    // on): the Master is alive, and PN3 must not pass PN2 over and take over alone.
    Cluster cluster(topology);
    cluster.run(10);
    const View before = cluster.node(PN3).view();
    cluster.block(PN1, PN3);
    cluster.request_phase(PN1, *topology.phase_id("science"));
    cluster.run(1);
    ASSERT_GT(cluster.node(PN2).view().seq, before.seq);
    ASSERT_EQ(cluster.node(PN3).view(), before);
    ASSERT_TRUE(cluster.node(PN3).config_switch().prepared_newer_switch(PN2));
    for (int k = 0; k < 8 * topology.miss_limit(); ++k) {
        cluster.run(1);
        ASSERT_FALSE(cluster.node(PN3).is_master()) << "period " << k;
    }
    EXPECT_EQ(cluster.node(PN3).stats().passed_over, 0u);
    EXPECT_TRUE(cluster.node(PN1).is_master());
}

TEST_F(NodeProtocolTest, ATakeOverOpensAnEpochAboveOneItsVotersFollowOfTheNodeItSucceeds) {
    // keel-sim --liar, prototype3 seed 49016: PN3 alone follows an epoch of PN1's far
    // above PN2's (a copy PN1 changed). PN1 dies; PN2 takes over above it, else PN3's
    // acknowledgements of epoch 7 lapse PN2's lease at once, and PN2's heartbeats of an
    // older epoch never reach PN3 as news.
    Cluster cluster(topology);
    cluster.run(10);
    View ahead = cluster.node(PN3).view();
    ahead.epoch = 7;  // PN1's, within a lap a period of PN3's
    ASSERT_EQ(topology.owner(ahead.epoch), PN1);
    ahead.seq = 1;
    cluster.inject(PN3, Command{PN1, ahead});
    ASSERT_EQ(cluster.node(PN3).view().epoch, 7u);
    ASSERT_EQ(cluster.node(PN2).view().epoch, 1u);
    cluster.run(2);
    cluster.crash(PN1);
    cluster.run(4 * topology.miss_limit() + 4);
    ASSERT_TRUE(cluster.node(PN2).is_master());
    EXPECT_EQ(cluster.node(PN2).view().epoch, topology.next_epoch(PN2, 7));
    EXPECT_EQ(cluster.node(PN3).view().epoch, topology.next_epoch(PN2, 7));
    EXPECT_EQ(cluster.node(PN2).stats().lease_step_downs, 0u);
}

TEST_F(NodeProtocolTest, AKeptStateOfALaterEpochsLineageRunsOnInALineageOfItsView) {
    // A cold start: the cluster boots at epoch 1, and the Storage node keeps taskB's state
    // from a lineage opened in epoch 57 (the task once started without it). taskB resumes
    // from it in a lineage of the boot view, so its next checkpoints are no versions from
    // the future: the Storage node stores them (the host's write replaces the kept record).
    // (keel-sim --liar found the same with a value-faulty Storage node's reply.)
    const Version kept{lineage_of(57, 2), 100};
    Cluster cluster(topology, {}, {StoredCheckpoint{taskB, kept, {0x64}}});
    cluster.run(10);
    ASSERT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.node(PN3).config_switch().version(taskB).lineage, lineage_of(1, 1));
    EXPECT_GE(cluster.node(PN3).config_switch().version(taskB).count, kept.count);
    const auto stored = cluster.node(ST1).store()->latest_version(taskB);
    ASSERT_TRUE(stored.has_value());
    EXPECT_EQ(stored->lineage, lineage_of(1, 1));
    EXPECT_GT(stored->count, kept.count);
    EXPECT_EQ(cluster.node(ST1).stats().unauthorized[5], 0u);
}

TEST_F(NodeProtocolTest, ATaskResumedFromALaterEpochsLineageRunsOnInALineageOfItsView) {
    // spec/ValueFault.tla (RunLineage) holds for every start, the resumption after a hold
    // too: PN3 lost its lease and held taskB; when its acknowledgements came back it asked
    // the Storage node, and a value-faulty ST1 answered with a state of a lineage of epoch
    // 9. Kept as it is, every later checkpoint of PN3's would be from the future, refused
    // by the Storage node: the flush of the next switch never acknowledged.
    Cluster cluster(topology);
    ASSERT_NO_FATAL_FAILURE(hold_then_resume_pn3(cluster));
    const View view = cluster.node(PN3).view();
    const Version future{lineage_of(view.epoch + 8, 1), cluster.node(PN3).config_switch().version(taskB).count + 50};
    cluster.inject(PN3, CheckpointReply{ST1, view.epoch, view.seq, taskB, true, future, {0x07}});
    ASSERT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.node(PN3).config_switch().version(taskB).lineage, lineage_of(view.epoch, view.seq));
    EXPECT_GE(cluster.node(PN3).config_switch().version(taskB).count, future.count);
    cluster.unblock_all();
    cluster.run(5);
    const auto stored = cluster.node(ST1).store()->latest_version(taskB);
    ASSERT_TRUE(stored.has_value());
    EXPECT_EQ(stored->lineage, lineage_of(view.epoch, view.seq));
    EXPECT_GT(stored->count, future.count);
    EXPECT_EQ(cluster.node(ST1).stats().unauthorized[5], 0u);
}

TEST_F(NodeProtocolTest, AHeldTaskResumesFromItsOwnStateOverACountNoCorrectRunReaches) {
    // The resumption after a hold (resume_released): the Storage node's answer carries the
    // forged count; PN3 keeps its own state.
    Cluster cluster(topology);
    ASSERT_NO_FATAL_FAILURE(hold_then_resume_pn3(cluster));
    const View view = cluster.node(PN3).view();
    const Version own = cluster.node(PN3).config_switch().version(taskB);
    cluster.inject(PN3, CheckpointReply{ST1, view.epoch, view.seq, taskB, true, {own.lineage, kMaxVersionCount}, {0x07}});
    ASSERT_TRUE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.node(PN3).config_switch().version(taskB), own);
    EXPECT_EQ(cluster.node(PN3).config_switch().unadoptable_states(), 1u);
}

TEST_F(NodeProtocolTest, AMasterThatCommandsWhatTheGraphDoesNotPlaceIsReplaced) {
    Cluster cluster(topology);
    cluster.run(10);
    // PN1 commands P3 (taskB on PN3) with PN3 excluded: no graph walk ends there.
    View bad = cluster.node(PN1).view();
    bad.seq += 1;
    bad.config = bad.base = id("P3");
    bad.failed.insert(PN3);
    cluster.inject(ST1, Command{PN1, bad});
    EXPECT_EQ(cluster.node(ST1).stats().commands_refused, 1u);
    EXPECT_NE(cluster.node(ST1).last_refusal().find("places taskB on PN3"), std::string::npos)
        << cluster.node(ST1).last_refusal();
    // PN2, the first Observer, refuses it too and holds PN1 failed on its own word: it
    // takes over at once, before PN1 could command anyone else.
    cluster.inject(PN2, Command{PN1, bad});
    EXPECT_EQ(cluster.node(PN2).stats().commands_refused, 1u);
    EXPECT_TRUE(cluster.node(PN2).is_master());
    for (NodeId n : {PN1, PN2, PN3, ST1}) EXPECT_NE(cluster.node(n).view().config, id("P3"));
    // PN1's Command now comes too late for PN3: stale, not followed.
    cluster.inject(PN3, Command{PN1, bad});
    EXPECT_NE(cluster.node(PN3).view().config, id("P3"));
    cluster.run(10);
    EXPECT_TRUE(cluster.node(PN2).is_master());
    EXPECT_TRUE(cluster.node(PN2).view().failed.contains(PN1));
    EXPECT_FALSE(cluster.task_on_two_nodes());
}

TEST_F(NodeProtocolTest, TheNextSwitchOfAViewFollowsAnEdgeOfTheGraph) {
    Cluster cluster(topology);
    cluster.run(10);
    // P4 is a valid configuration with nothing failed, but no edge leads from P1 to P4
    // unless PN3 fails.
    View skip = cluster.node(PN1).view();
    skip.seq += 1;
    skip.config = skip.base = id("P4");
    cluster.inject(PN3, Command{PN1, skip});
    EXPECT_EQ(cluster.node(PN3).stats().commands_refused, 1u);
    EXPECT_NE(cluster.node(PN3).last_refusal().find("no phase edge"), std::string::npos);
    EXPECT_EQ(cluster.node(PN3).view().config, id("P1"));
    // The same switch with PN3 failed is the graph's edge: not refused by PN2, and
    // followed once PN3's exclusion is backed by a node other than PN1 (here PN3's own
    // word: it asks to be excluded).
    skip.failed.insert(PN3);
    cluster.inject(PN2, Command{PN1, skip});
    EXPECT_EQ(cluster.node(PN2).stats().commands_refused, 0u);
    EXPECT_EQ(cluster.node(PN2).stats().commands_unbacked, 1u);
    EXPECT_EQ(cluster.node(PN2).view().config, id("P1"));
    cluster.inject(PN2, ErrorNotification{PN3, 1, PN3});
    cluster.inject(PN2, Command{PN1, skip});
    EXPECT_EQ(cluster.node(PN2).view().config, id("P4"));
}

// Fault model 3, rule 4: the Master's Activate starts nothing on a node before every
// other member's own Prepared for the same view. PN1 lies: it sends PN2 alone the phase
// change to S1 (taskB moves from PN3 to PN2), then its Activate.
TEST_F(NodeProtocolTest, AnActivateBeforeEveryMembersPreparedStartsNothing) {
    for (const Mutant mutant : {Mutant::none, Mutant::no_peer_prepared}) {
        if (mutant != Mutant::none && !kMutantsCompiled) continue;
        Cluster cluster(topology, {}, {}, mutant);
        cluster.run(10);
        ASSERT_TRUE(cluster.running(PN3).contains(taskB));
        View s1 = cluster.node(PN1).view();
        s1.seq += 1;
        s1.config = s1.base = id("S1");
        cluster.inject(PN2, Command{PN1, s1});
        ASSERT_EQ(cluster.node(PN2).view().config, id("S1"));
        cluster.inject(PN2, Ack{PN1, s1.epoch, s1.seq, AckKind::Prepared, view_digest(s1)});
        cluster.inject(PN2, ActivateCommand{PN1, s1.epoch, s1.seq});
        cluster.run(3);
        if (mutant == Mutant::none) {
            EXPECT_FALSE(cluster.task_on_two_nodes());
            EXPECT_FALSE(cluster.running(PN2).contains(taskB));
            EXPECT_TRUE(cluster.node(PN2).config_switch().activation_held());
            EXPECT_EQ(cluster.node(PN2).config_switch().activations_held(), 1u);
            EXPECT_TRUE(cluster.running(PN3).contains(taskB));
        } else {
            EXPECT_TRUE(cluster.task_on_two_nodes()) << "the mutant activates on the Master's word";
        }
    }
}

// Rule 4 binds the view, not only its id: PN1 sends PN2 the phase change to S1 and PN3
// and ST1 the same configuration again, both as switch <<1, 2>>. Every node prepares its
// own; none starts anything, though each gets an Activate and every member's Prepared.
TEST_F(NodeProtocolTest, TwoViewsUnderOneSwitchIdStartNothing) {
    for (const Mutant mutant : {Mutant::none, Mutant::no_peer_prepared}) {
        if (mutant != Mutant::none && !kMutantsCompiled) continue;
        Cluster cluster(topology, {}, {}, mutant);
        cluster.run(10);
        View again = cluster.node(PN1).view();
        again.seq += 1;
        View s1 = again;
        s1.config = s1.base = id("S1");
        cluster.inject(PN2, Command{PN1, s1});
        cluster.inject(PN3, Command{PN1, again});
        cluster.inject(ST1, Command{PN1, again});
        cluster.inject(PN2, Ack{PN1, s1.epoch, s1.seq, AckKind::Prepared, view_digest(s1)});
        for (NodeId n : {PN2, PN3, ST1}) cluster.inject(n, ActivateCommand{PN1, s1.epoch, s1.seq});
        cluster.run(3);
        if (mutant == Mutant::none) {
            EXPECT_FALSE(cluster.task_on_two_nodes());
            EXPECT_TRUE(cluster.node(PN2).config_switch().activation_held());
            EXPECT_FALSE(cluster.node(PN2).config_switch().peers_prepared().contains(PN3));
        } else {
            EXPECT_TRUE(cluster.task_on_two_nodes());
        }
    }
}

// Rule 5: an exclusion a Command adds is followed once backed by a node other than its
// sender, or once another member that checked it follows the view (its Prepared).
TEST_F(NodeProtocolTest, AnExclusionOnlyItsSenderDeclaredIsNotFollowed) {
    for (const Mutant mutant : {Mutant::none, Mutant::unbacked_exclusions}) {
        if (mutant != Mutant::none && !kMutantsCompiled) continue;
        Cluster cluster(topology, {}, {}, mutant);
        cluster.run(10);
        View p4 = cluster.node(PN1).view();
        p4.seq += 1;
        p4.config = p4.base = id("P4");
        p4.failed.insert(PN3);
        cluster.inject(PN2, ErrorNotification{PN1, 1, PN3});  // the sender's own: no backing
        cluster.inject(PN2, Command{PN1, p4});
        if (mutant != Mutant::none) {
            EXPECT_EQ(cluster.node(PN2).view().config, id("P4")) << "the mutant follows it";
            continue;
        }
        EXPECT_EQ(cluster.node(PN2).view().config, id("P1"));
        EXPECT_EQ(cluster.node(PN2).stats().commands_unbacked, 1u);
        EXPECT_FALSE(cluster.node(PN2).monitor().failed().contains(PN1)) << "no evidence against PN1";
        // ST1 follows it (a backing PN2 has not seen): its Prepared vouches for the view.
        cluster.inject(PN2, Ack{ST1, p4.epoch, p4.seq, AckKind::Prepared, view_digest(p4)});
        cluster.inject(PN2, Command{PN1, p4});
        EXPECT_EQ(cluster.node(PN2).view().config, id("P4"));
    }
}


// Rule 5 through a fence: PN1 excludes PN2 together with PN3 (alive, heard by PN2), a
// view PN2 follows unchecked, then readmits PN2 in a new epoch that still excludes PN3.
// What PN2 adopted from the fencing view is no evidence, and neither is that view's
// failed set for the last-monitor clause: the readmission is checked against the last
// view PN2 checked. Once ST1, which checked it, prepares the view, the same Command is
// followed (how an honest readmission goes when PN2 missed the declarations).
TEST_F(NodeProtocolTest, AFencedNodeChecksTheExclusionsItWasFencedWith) {
    for (const Mutant mutant : {Mutant::none, Mutant::unbacked_exclusions}) {
        if (mutant != Mutant::none && !kMutantsCompiled) continue;
        Cluster cluster(topology, {}, {}, mutant);
        cluster.run(10);
        const View before = cluster.node(PN1).view();
        View fence = before;
        fence.seq += 1;
        fence.config = kSafeConfig;
        fence.failed.insert(PN2);
        fence.failed.insert(PN3);
        cluster.inject(PN2, Command{PN1, fence});
        ASSERT_TRUE(cluster.node(PN2).view().failed.contains(PN2)) << "a view excluding PN2 is followed";
        View back = before;
        back.epoch = topology.next_epoch(PN1, before.epoch);
        back.seq = 1;
        back.config = back.base = id("P4");
        back.failed = NodeSet{};
        back.failed.insert(PN3);
        cluster.inject(PN2, Command{PN1, back});
        if (mutant != Mutant::none) {
            EXPECT_EQ(cluster.node(PN2).view().config, id("P4")) << "the mutant follows it";
            continue;
        }
        EXPECT_NE(cluster.node(PN2).view().config, id("P4"));
        EXPECT_EQ(cluster.node(PN2).stats().commands_unbacked, 1u);
        cluster.inject(PN2, Ack{ST1, back.epoch, back.seq, AckKind::Prepared, view_digest(back)});
        cluster.inject(PN2, Command{PN1, back});
        EXPECT_EQ(cluster.node(PN2).view().config, id("P4")) << cluster.node(PN2).last_refusal();
    }
}


// Rule 5's silence backing through a fence, at a node that is no processing node: ST1
// hears heartbeats only from monitors. prototype3 with a Worker PN4 (a monitor only in P5).
// PN1 fences ST1 with SAFE based on P5 (ST1 excluded), then readmits it into P1 excluding
// PN4, which is alive. PN4, a Worker, never sent ST1 a heartbeat: its silence there backs
// nothing, because the fencing view's monitors are not what ST1 checks against; the last
// view it checked (P1) does not make PN4 a monitor.
TEST(NodeProtocolFence, SilenceBacksNothingByTheFencingViewsMonitors) {
    keel::mission::Mission m = testing::prototype3();
    keel::mission::Node pn4;
    pn4.name = "PN4";
    pn4.kind = keel::mission::NodeKind::processing;
    m.nodes.push_back(pn4);
    keel::mission::Configuration p5 = m.phases[0].configurations[0];
    p5.name = "P5";
    p5.observers = {"PN2", "PN4"};
    m.phases[0].configurations.push_back(p5);
    const Topology topology = testing::topology_of(m);
    const NodeId PN1 = 0, ST1 = 3, PN4 = 4;
    ASSERT_EQ(topology.node_name(PN4), "PN4");
    for (const Mutant mutant : {Mutant::none, Mutant::unbacked_exclusions}) {
        if (mutant != Mutant::none && !kMutantsCompiled) continue;
        Cluster cluster(topology, {}, {}, mutant);
        cluster.run(10);
        const View before = cluster.node(PN1).view();
        ASSERT_FALSE(topology.monitors(before).contains(PN4));
        View fence = before;
        fence.epoch = topology.next_epoch(PN1, before.epoch);
        fence.seq = 1;
        fence.config = kSafeConfig;
        fence.base = *topology.config_id("P5");
        fence.failed = NodeSet{};
        fence.failed.insert(ST1);
        ASSERT_TRUE(topology.monitors(fence).contains(PN4));
        cluster.inject(ST1, Command{PN1, fence});
        ASSERT_TRUE(cluster.node(ST1).view().failed.contains(ST1)) << cluster.node(ST1).last_refusal();
        View back = before;
        back.epoch = topology.next_epoch(PN1, fence.epoch);
        back.seq = 1;
        back.failed = NodeSet{};
        back.failed.insert(PN4);
        cluster.inject(ST1, Command{PN1, back});
        if (mutant != Mutant::none) {
            EXPECT_FALSE(cluster.node(ST1).view().failed.contains(ST1)) << "the mutant follows it";
            continue;
        }
        EXPECT_TRUE(cluster.node(ST1).view().failed.contains(ST1)) << "followed: " << cluster.node(ST1).last_refusal();
        EXPECT_EQ(cluster.node(ST1).stats().commands_unbacked, 1u) << cluster.node(ST1).last_refusal();
    }
}

// spec/Designate.tla in the runtime: prototype3 with heartbeat.tie_grace 3.
Topology tie_grace_topology(int grace) {
    auto mission = testing::prototype3();
    mission.heartbeat.tie_grace = grace;
    return testing::topology_of(mission);
}

// The ground's vote is no command a mission without tie_grace takes, and a designation is
// refused, with its reason, for a node no monitor of the view, a span that ends before its
// wait, and (at the designee) a heartbeat it does not know the send time of.
TEST(NodeProtocolDesignate, ADesignationIsRefusedWithItsReason) {
    const Topology plain = testing::prototype3_topology();
    Cluster without(plain);
    without.run(5);
    const std::string off = without.node(1).ground_designate(1, 0, 20, without.node(1).monitor().seq(), without.now());
    EXPECT_NE(off.find("tie_grace"), std::string::npos) << off;
    const Topology topology = tie_grace_topology(3);
    Cluster cluster(topology);
    cluster.run(5);
    const NodeId PN2 = 1, ST1 = 3;
    NodeProtocol& node = cluster.node(PN2);
    const std::uint32_t seq = node.monitor().seq();
    EXPECT_NE(node.ground_designate(ST1, 0, 20, seq, cluster.now()).find("no monitor"), std::string::npos);
    EXPECT_NE(node.ground_designate(PN2, 20, 20, seq, cluster.now()).find("must end after the wait"),
              std::string::npos);
    EXPECT_NE(node.ground_designate(PN2, 0, 20, seq + 100, cluster.now()).find("not one of this boot"),
              std::string::npos);
    EXPECT_FALSE(node.holds_vote());
    EXPECT_EQ(node.ground_designate(PN2, 0, 20, seq, cluster.now()), "");
    EXPECT_TRUE(node.holds_vote());
    // A designation of another node ends this node's own vote (rule 3).
    EXPECT_EQ(node.ground_designate(0, 0, 20, seq, cluster.now()), "");
    EXPECT_FALSE(node.holds_vote());
}

// The last two monitors, PN1 (the Master) and PN2, cut apart for good (the ground holds PN3
// out). Without tie_grace PN2, the last monitor, takes over alone. With it both stop after
// the tie's grace (PN1 resigns, PN2 stands down and holds taskA) and nobody takes over
// until the ground designates PN2, which then runs as Master while its vote lasts, and
// steps down when it ends.
TEST(NodeProtocolDesignate, TheGroundBreaksATieOfTheLastTwoMonitors) {
    const NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    const auto cut = [&](Cluster& cluster) {
        for (NodeId n : {PN1, ST1}) {
            for (NodeId m : {PN2, PN3}) {
                cluster.block(n, m);
                cluster.block(m, n);
            }
        }
    };
    const auto hold_out_pn3 = [&](Cluster& cluster, const Topology& topology) {
        cluster.run(5);
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            EXPECT_EQ(cluster.node(n).ground_exclude(PN3, cluster.now()), "");
        }
        cluster.settle();
        cluster.run(10);
        ASSERT_TRUE(cluster.node(PN1).view().failed.contains(PN3));
    };
    {
        const Topology plain = testing::prototype3_topology();
        Cluster cluster(plain);
        hold_out_pn3(cluster, plain);
        cut(cluster);
        cluster.run(10);
        EXPECT_TRUE(cluster.node(PN2).is_master()) << "the last monitor takes over alone";
    }
    const Topology topology = tie_grace_topology(3);
    Cluster cluster(topology);
    hold_out_pn3(cluster, topology);
    const TaskId task_a = *topology.task_id("taskA");
    ASSERT_TRUE(cluster.running(PN2).contains(task_a));
    cut(cluster);
    cluster.run(10);
    EXPECT_NE(cluster.node(PN1).resign_state(), NodeProtocol::Resign::none);
    EXPECT_TRUE(cluster.node(PN2).stood_down());
    EXPECT_FALSE(cluster.node(PN2).is_master());
    EXPECT_FALSE(cluster.running(PN2).contains(task_a));
    cluster.run(20);
    EXPECT_FALSE(cluster.node(PN2).is_master()) << "no take-over without the ground";
    const std::uint32_t echo = cluster.node(PN2).monitor().seq();
    for (NodeId n : {PN2, PN3}) EXPECT_EQ(cluster.node(n).ground_designate(PN2, 0, 15, echo, cluster.now()), "");
    cluster.settle();
    cluster.run(2);
    ASSERT_TRUE(cluster.node(PN2).is_master());
    EXPECT_GT(cluster.node(PN2).epoch(), 1u);
    EXPECT_TRUE(cluster.node(PN2).view().failed.contains(PN1));
    EXPECT_TRUE(cluster.node(PN2).holds_vote());
    EXPECT_FALSE(cluster.task_on_two_nodes());
    cluster.run(15);  // the span ends: the tie is still there
    EXPECT_FALSE(cluster.node(PN2).holds_vote());
    EXPECT_NE(cluster.node(PN2).resign_state(), NodeProtocol::Resign::none);
}

}  // namespace
}  // namespace keel::fsm
