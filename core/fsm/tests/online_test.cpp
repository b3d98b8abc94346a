// Online configurations (core/fsm/online.hpp): the Master's choices beyond the graph, the
// receivers' checks of them (through admission.hpp), the Command that carries them, and
// the ReconfigurationManager that drives them. On the three-node prototype with its nominal
// phase placed graph+online or online.
#include "core/fsm/online.hpp"

#include <gtest/gtest.h>

#include "core/fsm/admission.hpp"
#include "core/fsm/codec.hpp"
#include "core/fsm/reconfiguration_manager.hpp"
#include "core/placement/check.hpp"
#include "test_mission.hpp"

namespace keel::fsm {
namespace {

using keel::mission::PlacementMode;

constexpr NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
constexpr TaskId taskA = 0, taskB = 1;

keel::mission::Mission with_nominal(PlacementMode mode) {
    keel::mission::Mission mission = testing::prototype3();
    auto& nominal = mission.phases[0];
    nominal.placement = mode;
    if (mode == PlacementMode::online) {
        // Only the initial configuration (the image loader's rule for an online phase).
        nominal.configurations.resize(1);
        nominal.on_failure.clear();
        std::erase_if(nominal.on_phase, [](const auto& edge) { return edge.from != "P1"; });
        std::erase_if(mission.phases[1].on_phase, [](const auto& edge) { return edge.to != "P1"; });
    }
    return mission;
}

NodeSet nodes(std::initializer_list<NodeId> ids) {
    NodeSet set;
    for (NodeId id : ids) set.insert(id);
    return set;
}

// The view `from` switches to when the nodes `failed` adds fail, as the Master makes it.
View switched(const Topology& topology, const View& from, const Target& target, NodeSet failed) {
    View view = from;
    view.seq = from.seq + 1;
    view.failed = failed;
    view.config = target.config;
    if (target.is_safe()) {
        view.base = from.is_safe() ? from.base : from.config;
    } else {
        view.base = target.config;
        view.online = target.online;
    }
    (void)topology;
    return view;
}

class OnlineTest : public ::testing::Test {
protected:
    Topology graph_online = testing::topology_of(with_nominal(PlacementMode::graph_online));
    Topology online = testing::topology_of(with_nominal(PlacementMode::online));
    Topology graph = testing::prototype3_topology();
};

TEST_F(OnlineTest, GraphOnlineFollowsTheGraphThenThePlacer) {
    const View initial = graph_online.initial_view();
    // The graph has an edge for PN2: P3, as in a graph phase.
    const Target first = failure_target(graph_online, initial, {PN2}, nodes({PN2}), PN1);
    ASSERT_FALSE(first.is_safe());
    EXPECT_EQ(first.config, *graph_online.config_id("P3"));
    EXPECT_FALSE(first.online);
    // P3 goes to SAFE for PN3: the placer puts both tasks on what is left (PN1, ST1).
    const View p3 = switched(graph_online, initial, first, nodes({PN2}));
    const Target second = failure_target(graph_online, p3, {PN3}, nodes({PN2, PN3}), PN1);
    ASSERT_EQ(second.config, kOnlineConfig);
    ASSERT_TRUE(second.online);
    EXPECT_EQ(second.online->master, PN1);
    EXPECT_TRUE(second.online->observers.empty()) << "one processing node alive: none to observe";
    for (TaskId task : {taskA, taskB}) {
        const NodeId host = second.online->host[task];
        EXPECT_TRUE(host == PN1 || host == ST1) << "task " << task << " on " << host;
    }
    const View beyond = switched(graph_online, p3, second, nodes({PN2, PN3}));
    EXPECT_EQ(view_problem(beyond, graph_online), std::nullopt);
    EXPECT_EQ(edge_problem(p3, beyond, graph_online), std::nullopt);
    // The graph alone gives up there.
    EXPECT_TRUE(failure_target(graph, p3, {PN3}, nodes({PN2, PN3}), PN1).is_safe());
}

TEST_F(OnlineTest, AnOnlinePhasePlacesEveryFailureAndKeepsTheMasterWhereItCan) {
    const View initial = online.initial_view();
    const Target target = failure_target(online, initial, {PN3}, nodes({PN3}), PN1);
    ASSERT_EQ(target.config, kOnlineConfig);
    EXPECT_EQ(target.online->master, PN1);
    // taskA stays on PN2; taskB, on the failed PN3, moves; PN2 observes.
    EXPECT_EQ(target.online->host[taskA], PN2);
    EXPECT_NE(target.online->host[taskB], PN3);
    EXPECT_EQ(target.online->observers, std::vector<NodeId>{PN2});
    // The Master's failure: the first alive observer (PN2) is the placer's master, so the
    // take-over by PN2 is placed, and one by PN3 is SAFE (the placer names another).
    EXPECT_EQ(failure_target(online, initial, {PN1}, nodes({PN1}), PN2).online->master, PN2);
    EXPECT_TRUE(failure_target(online, initial, {PN1}, nodes({PN1}), PN3).is_safe());
}

TEST_F(OnlineTest, ReceiversRefuseAnOnlineConfigurationTheCheckerRefuses) {
    const View initial = online.initial_view();
    const Target target = failure_target(online, initial, {PN3}, nodes({PN3}), PN1);
    const View good = switched(online, initial, target, nodes({PN3}));
    ASSERT_EQ(view_problem(good, online), std::nullopt);
    ASSERT_EQ(edge_problem(initial, good, online), std::nullopt);
    const auto refused = [&](const char* what, auto change, const char* expected) {
        SCOPED_TRACE(what);
        OnlineConfig config = *good.online;
        change(config);
        View bad = good;
        bad.online = OnlinePtr(std::make_shared<OnlineConfig>(config));
        const auto problem = view_problem(bad, online);
        ASSERT_TRUE(problem);
        EXPECT_NE(problem->find(expected), std::string::npos) << *problem;
    };
    refused("a task on the failed node", [](OnlineConfig& c) { c.host[taskA] = PN3; }, "task-on-failed-node");
    refused("the essential task shed", [](OnlineConfig& c) { c.host[taskB] = kNoNode; }, "essential");
    refused("another master", [](OnlineConfig& c) { c.master = PN2; }, "master is PN2");
    refused("the failed node observes", [](OnlineConfig& c) { c.observers = {PN3}; }, "observer-invalid");
    refused("no observer", [](OnlineConfig& c) { c.observers.clear(); }, "observer-invalid");
    // A phase placed by its graph alone carries none.
    View in_graph = good;
    in_graph.online = OnlinePtr(std::make_shared<OnlineConfig>(*good.online));
    const auto problem = view_problem(in_graph, graph);
    ASSERT_TRUE(problem);
    EXPECT_NE(problem->find("placed by its graph alone"), std::string::npos) << *problem;
    // Outside safe mode the configuration is its base.
    View mixed = good;
    mixed.config = *online.config_id("P1");
    EXPECT_TRUE(view_problem(mixed, online));
    // The ids are the mission's (out_of_mission, before any of this).
    View wide = good;
    OnlineConfig extra = *good.online;
    extra.host.push_back(PN1);
    wide.online = OnlinePtr(std::make_shared<OnlineConfig>(extra));
    EXPECT_TRUE(out_of_mission(Command(PN1, wide), online));
    View missing = good;
    missing.online = nullptr;
    EXPECT_TRUE(out_of_mission(Command(PN1, missing), online));
    View unnamed = initial;
    unnamed.online = good.online;
    EXPECT_TRUE(out_of_mission(Command(PN1, unnamed), online));
    // A phase, master, observer or host beyond the mission's.
    for (int field = 0; field < 4; ++field) {
        OnlineConfig beyond = *good.online;
        if (field == 0) beyond.phase = static_cast<PhaseId>(online.phase_count());
        if (field == 1) beyond.master = static_cast<NodeId>(online.node_count());
        if (field == 2) beyond.observers.push_back(static_cast<NodeId>(online.node_count()));
        if (field == 3) beyond.host[taskA] = static_cast<NodeId>(online.node_count());
        View far = good;
        far.online = OnlinePtr(std::make_shared<OnlineConfig>(beyond));
        EXPECT_TRUE(out_of_mission(Command(PN1, far), online)) << "field " << field;
    }
    // The codec refuses more hosts than the capacity's tasks where it decodes them.
    OnlineConfig hosts = *good.online;
    hosts.host.assign(kMaxTasks + 1, PN1);
    View many = good;
    many.online = OnlinePtr(std::make_shared<OnlineConfig>(hosts));
    EXPECT_FALSE(decode(encode(Command(PN1, many))).ok());
}

TEST_F(OnlineTest, ReceiversRefuseSafeModeWhereAPlacementExistsAndTheGraphWhereItAnswers) {
    // An online phase: SAFE for PN3's failure gives up while the placer places both tasks.
    const View initial = online.initial_view();
    const View safe = switched(online, initial, Target::safe(), nodes({PN3}));
    const auto gives_up = edge_problem(initial, safe, online);
    ASSERT_TRUE(gives_up);
    EXPECT_NE(gives_up->find("gives up"), std::string::npos) << *gives_up;
    // graph+online: the graph answers PN2's failure (P3); an online target there is refused.
    const View go = graph_online.initial_view();
    const Target placed = failure_target(online, initial, {PN2}, nodes({PN2}), PN1);
    View instead = switched(graph_online, go, placed, nodes({PN2}));
    ASSERT_EQ(view_problem(instead, graph_online), std::nullopt);
    EXPECT_TRUE(edge_problem(go, instead, graph_online));
    // From an online configuration a failure never returns to a configuration of the graph.
    const Target first = failure_target(online, initial, {PN3}, nodes({PN3}), PN1);
    const View beyond = switched(online, initial, first, nodes({PN3}));
    View back = switched(online, beyond, Target::graph(*online.config_id("P1")), nodes({PN3, ST1}));
    back.base = back.config;
    back.online = nullptr;
    EXPECT_TRUE(edge_problem(beyond, back, online));
    // ... and SAFE in the graph-only mission, where the graph says so, stays accepted.
    const View p3 = switched(graph, graph.initial_view(), Target::graph(*graph.config_id("P3")), nodes({PN2}));
    EXPECT_EQ(edge_problem(p3, switched(graph, p3, Target::safe(), nodes({PN2, PN3})), graph), std::nullopt);
}

// A phase change into a phase the placer may answer takes the graph's on_phase entry only
// where the checker finds it valid under the failed set (keel-place --prove explores the
// same rule): P3 (PN2 failed) changes to S3, here observed by PN2 alone. Into a phase
// placed by its graph alone the entry is taken (the verifier's proof holds it).
TEST_F(OnlineTest, APhaseChangeTakesTheGraphsEntryOnlyWhereItIsValidUnderTheFailedSet) {
    keel::mission::Mission mission = testing::prototype3();
    mission.phases[1].placement = PlacementMode::graph_online;
    for (auto& config : mission.phases[1].configurations) {
        if (config.name == "S3") config.observers = {"PN2"};
    }
    const Topology topology = testing::topology_of(mission);
    constexpr PhaseId science = 1;
    View p3 = topology.initial_view();
    p3.config = p3.base = *topology.config_id("P3");
    const std::optional<Target> before = phase_target(topology, p3, science, PN1);
    ASSERT_TRUE(before);
    EXPECT_EQ(before->config, *topology.config_id("S3")) << "PN2 alive: S3 is valid";
    p3.failed = nodes({PN2});
    const std::optional<Target> after = phase_target(topology, p3, science, PN1);
    ASSERT_TRUE(after);
    ASSERT_EQ(after->config, kOnlineConfig);
    EXPECT_EQ(after->online->master, PN1);
    EXPECT_EQ(after->online->phase, science);
    const View next = switched(topology, p3, *after, p3.failed);
    EXPECT_EQ(view_problem(next, topology), std::nullopt);
    EXPECT_EQ(edge_problem(p3, next, topology), std::nullopt) << "the receivers take the placer's answer";

    mission.phases[1].placement = PlacementMode::graph;
    const Topology graph_only = testing::topology_of(mission);
    const std::optional<Target> by_graph = phase_target(graph_only, p3, science, PN1);
    ASSERT_TRUE(by_graph);
    EXPECT_EQ(by_graph->config, *graph_only.config_id("S3"));
}

TEST_F(OnlineTest, TheCommandCarriesTheConfigurationWhole) {
    const View initial = online.initial_view();
    const View view = switched(online, initial, failure_target(online, initial, {PN3}, nodes({PN3}), PN1), nodes({PN3}));
    const Command command(PN1, view, {view});
    const auto decoded = decode(encode(command));
    ASSERT_TRUE(decoded.ok()) << decoded.detail;
    EXPECT_EQ(*decoded.message, Message(command));
    const auto& back = std::get<Command>(*decoded.message);
    ASSERT_TRUE(back.view.online);
    EXPECT_EQ(*back.view.online, *view.online);
    // Safe mode entered from it keeps it as its base.
    View safe = view;
    safe.config = kSafeConfig;
    const auto safe_back = decode(encode(Command(PN1, safe)));
    ASSERT_TRUE(safe_back.ok());
    EXPECT_EQ(std::get<Command>(*safe_back.message).view, safe);
    // Two views that differ only in where a task runs differ in their digest.
    OnlineConfig moved = *view.online;
    moved.host[taskA] = ST1;
    View other = view;
    other.online = OnlinePtr(std::make_shared<OnlineConfig>(moved));
    EXPECT_NE(view_digest(view), view_digest(other));
    EXPECT_FALSE(view == other);
    // More observers than the capacity is refused where it is decoded.
    OnlineConfig crowded = *view.online;
    crowded.observers.assign(kMaxNodes + 1, PN2);
    View wide = view;
    wide.online = OnlinePtr(std::make_shared<OnlineConfig>(crowded));
    const auto refused = decode(encode(Command(PN1, wide)));
    EXPECT_FALSE(refused.ok());
    EXPECT_NE(refused.detail.find("observers"), std::string::npos) << refused.detail;
}

TEST_F(OnlineTest, TheManagerDrivesOnlineConfigurationsAndTracesThem) {
    ReconfigurationManager manager(graph_online, PN1, Mutant::none);
    manager.boot_as_master(graph_online.initial_view());
    Outbox out{true};
    const auto p3 = manager.exclude(PN2, Evidence{}, out);
    ASSERT_TRUE(p3);
    EXPECT_EQ(p3->config, *graph_online.config_id("P3"));
    const auto beyond = manager.exclude(PN3, Evidence{}, out);
    ASSERT_TRUE(beyond);
    ASSERT_EQ(beyond->config, kOnlineConfig);
    EXPECT_EQ(view_problem(*beyond, graph_online), std::nullopt);
    EXPECT_EQ(edge_problem(*p3, *beyond, graph_online), std::nullopt);
    bool traced = false;
    for (const auto& action : out.actions()) {
        if (const auto* trace = std::get_if<act::Trace>(&action);
            trace != nullptr && std::string_view(trace->action) == "Exclude" && trace->args.find("\"c\":\"online\"") != std::string::npos) {
            traced = trace->args.find("\"online\":{\"phase\":\"nominal\",\"m\":\"PN1\"") != std::string::npos;
        }
    }
    EXPECT_TRUE(traced) << "the Exclude line names the online configuration";
    for (const auto& action : out.actions()) EXPECT_FALSE(std::holds_alternative<act::EnterSafeMode>(action));
    // A readmission of PN3 in graph+online returns to the graph's configuration of the
    // smaller failed set (P3) when that is not SAFE.
    const Target back = recovery_target(graph_online, *beyond, PN3);
    EXPECT_EQ(back.config, *graph_online.config_id("P3"));
    // A phase change from online to science: the graph's configuration for the failed set
    // (S1 walked through PN2 and PN3 is SAFE), so none; the graph-only science phase has no
    // placer, and the change is refused.
    EXPECT_FALSE(manager.on_phase(1, out));
}

}  // namespace
}  // namespace keel::fsm
