// NodeProtocol end to end on a tiny lossless cluster: messages are delivered in order one
// millisecond after they are sent, and every node ticks at the same period boundaries.
#include "core/fsm/node_protocol.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <memory>

#include "test_mission.hpp"

namespace keel::fsm {
namespace {

constexpr TimeNs P = 100 * kNanosecondsPerMillisecond;

class Cluster {
public:
    explicit Cluster(const Topology& topology) : topology_(topology) {
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            nodes_.push_back(std::make_unique<NodeProtocol>(topology, n, 0, NodeOptions{}));
            alive_.push_back(true);
            drain(n);
        }
    }

    NodeProtocol& node(NodeId n) { return *nodes_[n]; }
    TimeNs now() const { return now_; }
    void crash(NodeId n) { alive_[n] = false; }
    void restart(NodeId n) {
        auto persisted = nodes_[n]->persistent_state();
        nodes_[n] = std::make_unique<NodeProtocol>(topology_, n, now_, NodeOptions{}, persisted);
        alive_[n] = true;
        drain(n);
    }
    void request_phase(NodeId n, PhaseId phase) {
        nodes_[n]->request_phase(phase, now_);
        drain(n);
        deliver_all();
    }
    // Runs `periods` heartbeat periods: tick everyone, deliver everything.
    void run(int periods) {
        for (int k = 0; k < periods; ++k) {
            now_ += P;
            for (NodeId n = 0; n < nodes_.size(); ++n) {
                if (!alive_[n]) continue;
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
    int activations(TaskId task) const { return activations_[task]; }
    Version last_activation_version(TaskId task) const { return last_version_[task]; }

private:
    void drain(NodeId n) {
        for (auto& action : nodes_[n]->take_ready()) {
            if (auto* send = std::get_if<act::Send>(&action)) {
                queue_.push_back({send->to, std::move(send->message)});
            } else if (auto* activate = std::get_if<act::Activate>(&action)) {
                ++activations_[activate->task];
                last_version_[activate->task] = activate->version;
            }
        }
    }
    void deliver_all() {
        for (int guard = 0; guard < 100000 && !queue_.empty(); ++guard) {
            auto [to, message] = std::move(queue_.front());
            queue_.pop_front();
            if (!alive_[to]) continue;
            now_ += 1000;  // a microsecond per delivery keeps time moving forward
            nodes_[to]->step(message, now_);
            drain(to);
        }
    }

    const Topology& topology_;
    std::vector<std::unique_ptr<NodeProtocol>> nodes_;
    std::vector<bool> alive_;
    std::deque<std::pair<NodeId, Message>> queue_;
    TimeNs now_ = 0;
    std::array<int, kMaxTasks> activations_{};
    std::array<Version, kMaxTasks> last_version_{};
};

class NodeProtocolTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    TaskId taskA = 0, taskB = 1;
    ConfigId id(const char* name) { return *topology.config_id(name); }
};

TEST_F(NodeProtocolTest, QuietClusterStaysInItsInitialConfiguration) {
    Cluster cluster(topology);
    cluster.run(50);
    for (NodeId n = 0; n < 4; ++n) {
        EXPECT_EQ(cluster.node(n).view().config, id("P1"));
        EXPECT_EQ(cluster.node(n).view().seq, 0u);
    }
    EXPECT_TRUE(cluster.node(PN1).is_master());
    EXPECT_GE(*cluster.node(ST1).store()->latest_version(taskB), 49u);
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
    EXPECT_EQ(cluster.last_activation_version(taskB), 10u);
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
    cluster.request_phase(PN2, *topology.phase_id("science"));  // forwarded to PN1
    cluster.run(3);
    EXPECT_EQ(cluster.node(PN1).view().config, id("S1"));
    EXPECT_TRUE(cluster.node(PN3).config_switch().active().contains(taskA));
    EXPECT_TRUE(cluster.node(PN2).config_switch().active().contains(taskB));
    EXPECT_FALSE(cluster.node(PN3).config_switch().active().contains(taskB));
    EXPECT_EQ(cluster.activations(taskB), 2);
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

}  // namespace
}  // namespace keel::fsm
