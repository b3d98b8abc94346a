// The checker against each rule of "valid under F" (a configuration that breaks exactly that
// rule), and the placer: its choices on small missions, and on random missions that every
// placement it returns passes the checker, that it sheds only when it must (against an
// exhaustive search on small ones) and never an essential task.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/placement/check.hpp"
#include "core/placement/model.hpp"
#include "core/placement/place.hpp"

namespace keel::placement {
namespace {

using mission::Mission;

mission::Node node(const std::string& name, std::vector<std::string> caps, std::int64_t cpu,
                   std::int64_t mem, bool processing = true, bool storage = false) {
    mission::Node n;
    n.name = name;
    n.kind = processing ? mission::NodeKind::processing : mission::NodeKind::interface;
    n.role = storage ? mission::NodeRole::storage
                     : (processing ? mission::NodeRole::none : mission::NodeRole::interface);
    n.capabilities = std::move(caps);
    n.capacity.cpu = cpu;
    n.capacity.mem_mb = mem;
    return n;
}

mission::Task task(const std::string& name, std::vector<std::string> requires_caps,
                   std::int64_t cpu, std::int64_t mem = 0) {
    mission::Task t;
    t.name = name;
    t.requires_capabilities = std::move(requires_caps);
    t.load.cpu = cpu;
    t.load.mem_mb = mem;
    return t;
}

// Gives `m` one phase P1 with every task, in its configuration C1: `master`, `observers`
// and `placement` as given.
void one_phase(Mission& m, std::string master, std::vector<std::string> observers,
               std::vector<std::pair<std::string, std::string>> placement) {
    mission::Phase p;
    p.name = "P1";
    for (const auto& t : m.tasks) p.tasks.push_back(t.name);
    p.initial = "C1";
    mission::Configuration c;
    c.name = "C1";
    c.phase = "P1";
    c.master = std::move(master);
    c.observers = std::move(observers);
    c.placement = std::move(placement);
    p.configurations.push_back(c);
    m.phases.push_back(p);
}

// Three processing nodes (PN3 without the camera's capability), a storage node and an
// interface node; one phase with every task and the configuration C1.
Mission small_mission() {
    Mission m;
    m.name = "small";
    m.nodes = {node("PN1", {"eigen"}, 100, 512), node("PN2", {"eigen"}, 100, 512),
               node("PN3", {}, 100, 512), node("ST1", {}, 50, 256, false, true),
               node("IF1", {"camera"}, 50, 256, false)};
    m.tasks = {task("camera", {"camera"}, 20), task("acca0", {"eigen"}, 60),
               task("acca1", {"eigen"}, 60), task("sink", {}, 10), task("aocs", {}, 30)};
    m.tasks[1].group = "acca";
    m.tasks[2].group = "acca";
    m.tasks[3].checkpoint = true;
    m.tasks[4].essential = true;
    m.tasks[4].checkpoint = true;
    one_phase(m, "PN1", {"PN2", "PN3"},
              {{"camera", "IF1"}, {"acca0", "PN1"}, {"acca1", "PN2"}, {"sink", "ST1"}, {"aocs", "PN3"}});
    return m;
}

struct Fixture : ::testing::Test {
    Mission mission = small_mission();
    Model model = *Model::build(mission, nullptr);
    Configuration c1 = *model.configuration(mission, "C1");
    int n(const char* name) const { return model.node_id(name); }
    int t(const char* name) const { return model.task_id(name); }
    FailedSet failed(std::initializer_list<const char*> names) const {
        FailedSet f = model.no_failures();
        for (const char* name : names) f[static_cast<std::size_t>(n(name))] = true;
        return f;
    }
    // The kinds `config` breaks, sorted.
    std::vector<std::string> kinds(const Configuration& config, const FailedSet& f,
                                   Shedding shedding = Shedding::forbidden) const {
        std::vector<std::string> out;
        for (const Finding& finding : check(model, 0, f, config, shedding)) out.push_back(finding.kind);
        std::sort(out.begin(), out.end());
        return out;
    }
    using Kinds = std::vector<std::string>;
};

TEST_F(Fixture, AValidConfigurationHasNoFinding) {
    EXPECT_EQ(kinds(c1, model.no_failures()), Kinds{});
    EXPECT_EQ(kinds(c1, failed({"PN3"})).size(), 2u);  // aocs on it, and it observes
}

TEST_F(Fixture, EachRuleOfValidUnderFIsCheckedAlone) {
    const FailedSet none = model.no_failures();
    Configuration c = c1;
    c.host[static_cast<std::size_t>(t("sink"))] = kNone;
    EXPECT_EQ(kinds(c, none), Kinds{"task-missing"});
    EXPECT_EQ(kinds(c, none, Shedding::allowed), Kinds{});  // sink is not essential
    c = c1;
    c.host[static_cast<std::size_t>(t("aocs"))] = kNone;
    EXPECT_EQ(kinds(c, none, Shedding::allowed), Kinds{"task-missing"});  // aocs is
    c = c1;
    c.host[static_cast<std::size_t>(t("camera"))] = n("PN3");
    EXPECT_EQ(kinds(c, none), Kinds{"capability"});
    c = c1;
    c.host[static_cast<std::size_t>(t("acca1"))] = n("PN1");
    EXPECT_EQ(kinds(c, none), Kinds{"capacity"});  // 120 > 100
    EXPECT_EQ(kinds(c1, failed({"IF1"})), Kinds{"task-on-failed-node"});
    c = c1;
    c.master = n("ST1");
    EXPECT_EQ(kinds(c, none), Kinds{"master-invalid"});
    EXPECT_EQ(kinds(c1, failed({"PN1"})), (Kinds{"master-invalid", "task-on-failed-node"}));
    c = c1;
    c.observers = {n("PN2"), n("PN2")};
    EXPECT_EQ(kinds(c, none), Kinds{"observer-invalid"});
    c.observers = {n("PN1")};
    EXPECT_EQ(kinds(c, none), Kinds{"observer-invalid"});
    c.observers = {n("IF1")};
    EXPECT_EQ(kinds(c, none), Kinds{"observer-invalid"});
    c.observers = {};
    EXPECT_EQ(kinds(c, none), Kinds{"observer-invalid"});
    c.observers = {n("PN2")};
    EXPECT_EQ(kinds(c, none), Kinds{});
    EXPECT_EQ(kinds(c1, failed({"ST1"})), (Kinds{"storage-unavailable", "task-on-failed-node"}));
}

TEST_F(Fixture, ATaskOfAnotherPhaseAndIdsBeyondTheMissionAreFindings) {
    Mission m = mission;
    m.phases[0].tasks.pop_back();  // aocs is of no phase now
    const Model other = *Model::build(m, nullptr);
    EXPECT_EQ(check(other, 0, other.no_failures(), c1).at(0).kind, "task-missing");
    Configuration c = c1;
    c.master = 99;
    EXPECT_EQ(check(model, 0, model.no_failures(), c).at(0).kind, "malformed");
    c = c1;
    c.host[0] = 99;
    EXPECT_EQ(check(model, 0, model.no_failures(), c).at(0).kind, "malformed");
    c = c1;
    c.host.pop_back();
    EXPECT_EQ(check(model, 0, model.no_failures(), c).at(0).kind, "malformed");
    EXPECT_EQ(check(model, 7, model.no_failures(), c1).at(0).kind, "malformed");
}

TEST_F(Fixture, TheFailureOfANodeThatHostsNothingMovesNothing) {
    Mission m = mission;
    m.nodes.push_back(node("PN4", {"eigen"}, 100, 512));
    const Model model4 = *Model::build(m, nullptr);
    const Configuration from = *model4.configuration(m, "C1");
    FailedSet f = model4.no_failures();
    f[static_cast<std::size_t>(model4.node_id("PN4"))] = true;
    const Placement p = place(model4, 0, f, from);
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.config, from);
    EXPECT_EQ(p.moved, 0);
    EXPECT_TRUE(p.shed.empty());
}

TEST_F(Fixture, OnlyTheTasksOfTheFailedNodeMoveAndTheMasterStays) {
    const Placement p = place(model, 0, failed({"PN2"}), c1);
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.config.master, n("PN1"));
    EXPECT_EQ(p.config.observers, std::vector<int>{n("PN3")});
    // acca1 fits nowhere (PN1 has 40 left, PN3 lacks eigen): shed; nothing else moves.
    EXPECT_EQ(p.shed, std::vector<int>{t("acca1")});
    EXPECT_EQ(p.moved, 0);
    Configuration expected = c1;
    expected.observers = {n("PN3")};
    expected.host[static_cast<std::size_t>(t("acca1"))] = kNone;
    EXPECT_EQ(p.config, expected);
    EXPECT_TRUE(valid(model, 0, failed({"PN2"}), p.config, Shedding::allowed));
}

TEST_F(Fixture, TheMasterFailedTheFirstAliveObserverIsMaster) {
    const Placement p = place(model, 0, failed({"PN1"}), c1);
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.config.master, n("PN2"));
    EXPECT_EQ(p.config.observers, std::vector<int>{n("PN3")});
    EXPECT_TRUE(valid(model, 0, failed({"PN1"}), p.config, Shedding::allowed));
}

TEST_F(Fixture, RedundantCopiesGoOnDifferentNodesWhereTheyCan) {
    Configuration nothing = c1;
    std::fill(nothing.host.begin(), nothing.host.end(), kNone);
    const Placement p = place(model, 0, model.no_failures(), nothing);
    ASSERT_FALSE(p.safe);
    EXPECT_NE(p.config.host[static_cast<std::size_t>(t("acca0"))],
              p.config.host[static_cast<std::size_t>(t("acca1"))]);
    EXPECT_EQ(p.started, 5);
}

TEST_F(Fixture, WhenNotEverythingFitsTheLowestPriorityIsShedNeverAnEssentialTask) {
    // PN1 and PN2 down: PN3 cannot run acca (no eigen): both copies are shed, whatever
    // their priority; aocs (essential) stays.
    Placement p = place(model, 0, failed({"PN1", "PN2"}), c1);
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.shed.size(), 2u);
    EXPECT_TRUE(valid(model, 0, failed({"PN1", "PN2"}), p.config, Shedding::allowed));
    // Capacity: PN1 alone (PN2, PN3 down) has 100: aocs 30 + one acca 60; the other copy
    // and whatever has the lowest priority go.
    Mission m = mission;
    m.tasks[1].priority = 5;  // acca0
    m.tasks[2].priority = 1;  // acca1
    const Model prio = *Model::build(m, nullptr);
    FailedSet f = prio.no_failures();
    f[static_cast<std::size_t>(prio.node_id("PN2"))] = true;
    f[static_cast<std::size_t>(prio.node_id("PN3"))] = true;
    p = place(prio, 0, f, *prio.configuration(m, "C1"));
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.shed, std::vector<int>{prio.task_id("acca1")});
    EXPECT_EQ(p.config.host[static_cast<std::size_t>(prio.task_id("acca0"))], prio.node_id("PN1"));
}

// Three processing nodes of cpu 100 and `tasks`; one phase with all of them, in C1 (master
// PN1, observer PN2) with the hosts given.
Mission three_nodes(std::vector<mission::Task> tasks, std::vector<std::pair<std::string, std::string>> hosts) {
    Mission m;
    m.name = "three";
    m.nodes = {node("PN1", {}, 100, 512), node("PN2", {}, 100, 512), node("PN3", {}, 100, 512),
               node("PN4", {}, 200, 512), node("IF1", {"camera"}, 50, 256, false)};
    m.tasks = std::move(tasks);
    one_phase(m, "PN1", {"PN2"}, std::move(hosts));
    return m;
}

TEST(Placer, KeepingEveryTaskThatFitsLosesToAPassThatShedsALowerPriority) {
    // PN3 (hosting c, priority 9) and PN4 fail: keeping a and b where they are leaves c
    // nowhere, though c fits alone on PN1 or PN2; the pass in order of need places c and
    // sheds a or b (priority 1).
    std::vector<mission::Task> tasks = {task("a", {}, 60), task("b", {}, 60), task("c", {}, 60)};
    tasks[0].priority = 1;
    tasks[1].priority = 1;
    tasks[2].priority = 9;
    const Mission m = three_nodes(tasks, {{"a", "PN1"}, {"b", "PN2"}, {"c", "PN3"}});
    const Model model = *Model::build(m, nullptr);
    FailedSet f = model.no_failures();
    f[static_cast<std::size_t>(model.node_id("PN3"))] = 1;
    f[static_cast<std::size_t>(model.node_id("PN4"))] = 1;
    const Placement p = place(model, 0, f, *model.configuration(m, "C1"));
    ASSERT_FALSE(p.safe);
    ASSERT_EQ(p.shed.size(), 1u);
    EXPECT_NE(p.shed[0], model.task_id("c"));
    EXPECT_NE(p.config.host[static_cast<std::size_t>(model.task_id("c"))], kNone);
}

TEST(Placer, WhereATaskRunsNowhereTheFewestMovesWinNotTheFirstPass) {
    // The camera's interface node fails (it runs nowhere else: shed whatever the pass).
    // PN1 runs x (60) and y, z (50 each, priority 5) over its capacity (a configuration
    // of another phase): keeping tasks in id order keeps x and moves y and z; keeping
    // them in order of need keeps y and z and moves x alone, the fewest moves.
    std::vector<mission::Task> tasks = {task("x", {}, 60), task("y", {}, 50), task("z", {}, 50),
                                        task("camera", {"camera"}, 10)};
    tasks[1].priority = 5;
    tasks[2].priority = 5;
    const Mission m = three_nodes(tasks, {{"x", "PN1"}, {"y", "PN1"}, {"z", "PN1"}, {"camera", "IF1"}});
    const Model model = *Model::build(m, nullptr);
    FailedSet f = model.no_failures();
    f[static_cast<std::size_t>(model.node_id("IF1"))] = 1;
    const Placement p = place(model, 0, f, *model.configuration(m, "C1"));
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.shed, std::vector<int>{model.task_id("camera")});
    EXPECT_EQ(p.moved, 1);
    EXPECT_EQ(p.config.host[static_cast<std::size_t>(model.task_id("y"))], model.node_id("PN1"));
    EXPECT_EQ(p.config.host[static_cast<std::size_t>(model.task_id("z"))], model.node_id("PN1"));
    // Witness: the same without x over PN1's capacity, the first pass wins at once (the
    // camera shed, nothing moved).
    const Mission fits = three_nodes(tasks, {{"x", "PN2"}, {"y", "PN1"}, {"z", "PN1"}, {"camera", "IF1"}});
    const Model light = *Model::build(fits, nullptr);
    const Placement q = place(light, 0, f, *light.configuration(fits, "C1"));
    EXPECT_EQ(q.shed, std::vector<int>{light.task_id("camera")});
    EXPECT_EQ(q.moved, 0);
}

TEST(Placer, TheSearchPlacesTheEssentialTasksWhereTheGreedyPassesCannot) {
    // PN3, PN4 and IF1 fail; PN1 and PN2 (100 each) take six essential tasks of 50, 40, 40,
    // 30, 20, 20: the tightest fit in order of load leaves the last 20 nowhere
    // (50+40 | 40+30+20), the search backtracks to 50+30+20 | 40+40+20.
    std::vector<mission::Task> tasks = {task("e50", {}, 50), task("e40a", {}, 40), task("e40b", {}, 40),
                                        task("e30", {}, 30), task("e20a", {}, 20), task("e20b", {}, 20)};
    std::vector<std::pair<std::string, std::string>> hosts;
    for (auto& t : tasks) {
        t.essential = true;
        hosts.emplace_back(t.name, "PN4");
    }
    const Mission m = three_nodes(tasks, hosts);
    const Model model = *Model::build(m, nullptr);
    FailedSet f = model.no_failures();
    f[static_cast<std::size_t>(model.node_id("PN3"))] = 1;
    f[static_cast<std::size_t>(model.node_id("PN4"))] = 1;
    f[static_cast<std::size_t>(model.node_id("IF1"))] = 1;
    const Placement p = place(model, 0, f, *model.configuration(m, "C1"));
    ASSERT_FALSE(p.safe);
    EXPECT_TRUE(p.shed.empty());
    EXPECT_TRUE(valid(model, 0, f, p.config));
}

TEST_F(Fixture, SafeModeOnlyWhenTheEssentialTasksDoNotFit) {
    // No storage node: checkpointed tasks cannot run; aocs is essential and checkpointed.
    EXPECT_TRUE(place(model, 0, failed({"ST1"}), c1).safe);
    EXPECT_TRUE(place(model, 0, failed({"PN1", "PN2", "PN3"}), c1).safe);
    Mission m = mission;
    m.tasks[4].checkpoint = false;
    const Model light = *Model::build(m, nullptr);
    FailedSet f = light.no_failures();
    f[static_cast<std::size_t>(light.node_id("ST1"))] = true;
    const Placement p = place(light, 0, f, *light.configuration(m, "C1"));
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.shed, std::vector<int>{light.task_id("sink")});
}

TEST_F(Fixture, AnUnboundedNodeTakesAnyLoadAndACurrentConfigurationOfAnotherPhaseIsNoHome) {
    // PN3 with no capacity stated takes acca0 and acca1 both (groups spread where they
    // can: PN1 and PN2 are down); a current configuration whose host list does not fit
    // the mission (another mission's, or of no size) is read as placing nothing.
    Mission m = mission;
    m.nodes[2].capabilities = {"eigen"};
    m.nodes[2].capacity.cpu.reset();
    m.nodes[2].capacity.mem_mb.reset();
    const Model unbounded = *Model::build(m, nullptr);
    FailedSet f = unbounded.no_failures();
    f[static_cast<std::size_t>(unbounded.node_id("PN1"))] = true;
    f[static_cast<std::size_t>(unbounded.node_id("PN2"))] = true;
    const Configuration from = *unbounded.configuration(m, "C1");
    Placement p = place(unbounded, 0, f, from);
    ASSERT_FALSE(p.safe);
    EXPECT_TRUE(p.shed.empty());
    EXPECT_EQ(p.config.host[static_cast<std::size_t>(unbounded.task_id("acca0"))], unbounded.node_id("PN3"));
    EXPECT_EQ(p.config.host[static_cast<std::size_t>(unbounded.task_id("acca1"))], unbounded.node_id("PN3"));
    EXPECT_TRUE(valid(unbounded, 0, f, p.config));
    Configuration odd = from;
    odd.host.pop_back();
    p = place(unbounded, 0, unbounded.no_failures(), odd);
    ASSERT_FALSE(p.safe);
    EXPECT_EQ(p.started, 5);
    EXPECT_EQ(p.moved, 0);
    EXPECT_TRUE(valid(unbounded, 0, unbounded.no_failures(), p.config));
}

// Random missions: up to 5 nodes, 5 tasks, small capacities, so that shedding and safe
// mode happen; every placement is checked, and compared with an exhaustive search.
struct Random {
    std::mt19937 rng;
    int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
};

Mission random_mission(Random& r) {
    Mission m;
    m.name = "random";
    const int nodes = r.pick(1, 5);
    for (int i = 0; i < nodes; ++i) {
        std::vector<std::string> caps;
        if (r.pick(0, 1) == 1) caps.push_back("a");
        if (r.pick(0, 2) == 0) caps.push_back("b");
        const bool storage = r.pick(0, 4) == 0;
        const bool processing = !storage && r.pick(0, 4) != 0;
        m.nodes.push_back(node("N" + std::to_string(i), caps, r.pick(0, 4) * 25, r.pick(1, 4) * 100,
                               processing, storage));
    }
    const int tasks = r.pick(1, 5);
    for (int i = 0; i < tasks; ++i) {
        std::vector<std::string> caps;
        if (r.pick(0, 2) == 0) caps.push_back("a");
        if (r.pick(0, 4) == 0) caps.push_back("b");
        mission::Task t = task("T" + std::to_string(i), caps, r.pick(0, 4) * 15, r.pick(0, 3) * 100);
        t.essential = r.pick(0, 3) == 0;
        t.checkpoint = r.pick(0, 3) == 0;
        t.priority = r.pick(0, 3);
        if (r.pick(0, 2) == 0) t.group = "g";
        m.tasks.push_back(t);
    }
    std::vector<std::pair<std::string, std::string>> placement;
    for (const auto& t : m.tasks) placement.emplace_back(t.name, m.nodes[static_cast<std::size_t>(r.pick(0, nodes - 1))].name);
    std::vector<std::string> observers;
    if (nodes > 1) observers.push_back(m.nodes[1].name);
    one_phase(m, m.nodes[0].name, observers, std::move(placement));
    return m;
}

// Whether the tasks not in `skip` can all be placed under `failed` (every assignment).
bool fits_exhaustively(const Model& model, const FailedSet& failed, const Configuration& base,
                       const std::vector<bool>& skip) {
    Configuration c = base;
    std::vector<int> tasks;
    for (int t = 0; t < model.task_count(); ++t) {
        c.host[static_cast<std::size_t>(t)] = kNone;
        if (!skip[static_cast<std::size_t>(t)]) tasks.push_back(t);
    }
    std::vector<int> choice(tasks.size(), 0);
    while (true) {
        for (std::size_t i = 0; i < tasks.size(); ++i) c.host[static_cast<std::size_t>(tasks[i])] = choice[i];
        if (valid(model, 0, failed, c, Shedding::allowed)) return true;
        std::size_t i = 0;
        while (i < choice.size() && ++choice[i] == model.node_count()) choice[i++] = 0;
        if (i == choice.size()) return false;
    }
}

TEST(PlacerOnRandomMissions, EveryPlacementIsValidAndShedsOnlyWhenItMust) {
    Random r{std::mt19937(20261130)};
    int placed = 0, shedding = 0, safe = 0, missed = 0;
    for (int round = 0; round < 3000; ++round) {
        const Mission m = random_mission(r);
        const Model model = *Model::build(m, nullptr);
        const Configuration from = *model.configuration(m, "C1");
        FailedSet failed = model.no_failures();
        for (int n = 0; n < model.node_count(); ++n) failed[static_cast<std::size_t>(n)] = r.pick(0, 3) == 0;
        const Placement p = place(model, 0, failed, from);
        // The fresh pass kept across calls (the prover's) changes no answer: filled from
        // a placement of nothing under the same failed set, then read for this one.
        FreshPasses fresh;
        (void)place(model, 0, failed, Configuration{}, &fresh);
        const Placement kept = place(model, 0, failed, from, &fresh);
        EXPECT_EQ(kept.safe, p.safe) << "round " << round;
        EXPECT_EQ(kept.config, p.config) << "round " << round;
        EXPECT_EQ(kept.shed, p.shed) << "round " << round;
        EXPECT_EQ(kept.moved, p.moved) << "round " << round;
        if (p.safe) {
            ++safe;
            // No placement of the essential tasks, with any master: check the master
            // choice separately (no alive processing node) or the essential tasks.
            bool processing_alive = false;
            for (int n = 0; n < model.node_count(); ++n) {
                processing_alive |= model.node(n).processing && !failed[static_cast<std::size_t>(n)];
            }
            if (!processing_alive) continue;
            std::vector<bool> skip(static_cast<std::size_t>(model.task_count()), false);
            for (int t = 0; t < model.task_count(); ++t) skip[static_cast<std::size_t>(t)] = !model.task(t).essential;
            // An exhaustive search with the master the placer would choose: any alive
            // processing node with the observers rule met is as good (they carry no load).
            Configuration probe;
            probe.host.assign(static_cast<std::size_t>(model.task_count()), kNone);
            for (int n = 0; n < model.node_count(); ++n) {
                if (model.node(n).processing && !failed[static_cast<std::size_t>(n)]) {
                    if (probe.master == kNone) probe.master = n; else if (probe.observers.empty()) probe.observers.push_back(n);
                }
            }
            EXPECT_FALSE(fits_exhaustively(model, failed, probe, skip))
                << "round " << round << ": safe mode though the essential tasks fit";
            continue;
        }
        ++placed;
        const auto findings = check(model, 0, failed, p.config, Shedding::allowed);
        EXPECT_TRUE(findings.empty()) << "round " << round << ": " << findings.at(0).message;
        for (const int t : p.shed) EXPECT_FALSE(model.task(t).essential) << "round " << round;
        if (!p.shed.empty()) {
            ++shedding;
            std::vector<bool> skip(static_cast<std::size_t>(model.task_count()), false);
            if (fits_exhaustively(model, failed, p.config, skip)) ++missed;
        }
    }
    // Every outcome happens in these rounds (the test is not vacuous).
    EXPECT_GT(placed, 500);
    EXPECT_GT(shedding, 50);
    EXPECT_GT(safe, 50);
    // A heuristic may shed where an exact packing fits: how often, bounded.
    RecordProperty("placed", placed);
    RecordProperty("shedding", shedding);
    RecordProperty("missed", missed);
    std::printf("placed %d, shedding %d (of which an exact packing fitted everything: %d), safe %d\n",
                placed, shedding, missed, safe);
    EXPECT_LE(missed * 20, shedding);
}

}  // namespace
}  // namespace keel::placement
