// The prover (prove.hpp) on small missions: an online phase where every tolerated failure
// places every task; one where the placer must give up the essential task (a violation
// with its failure sequence); a graph+online graph whose SAFE and whose other Master the
// placer answers; the counts beyond the tolerance; memoisation.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/mission/mission.hpp"
#include "core/placement/model.hpp"
#include "core/placement/prove.hpp"

namespace keel::placement {
namespace {

using mission::Mission;

mission::Node processing(const std::string& name, std::int64_t cpu) {
    mission::Node n;
    n.name = name;
    n.kind = mission::NodeKind::processing;
    n.role = mission::NodeRole::none;
    n.capabilities = {"eigen"};
    n.capacity.cpu = cpu;
    n.capacity.mem_mb = 512;
    return n;
}

mission::Node storage() {
    mission::Node n;
    n.name = "ST1";
    n.kind = mission::NodeKind::interface;
    n.role = mission::NodeRole::storage;
    n.capacity.cpu = 50;
    n.capacity.mem_mb = 512;
    return n;
}

mission::Task task(const std::string& name, std::int64_t cpu, bool essential) {
    mission::Task t;
    t.name = name;
    t.requires_capabilities = {"eigen"};
    t.load.cpu = cpu;
    t.load.mem_mb = 32;
    t.essential = essential;
    return t;
}

mission::Configuration configuration(const std::string& name, const std::string& master,
                                     std::vector<std::string> observers,
                                     std::vector<std::pair<std::string, std::string>> hosts) {
    mission::Configuration c;
    c.name = name;
    c.phase = "nominal";
    c.master = master;
    c.observers = std::move(observers);
    c.placement = std::move(hosts);
    return c;
}

// Four processing nodes of `cpu` each (PN4's `pn4_cpu`) and a storage node; one phase
// `mode` with `producer` (30 cpu) and the essential `consumer` (`consumer_cpu`), starting
// in C1 (master PN1, observers PN2 and PN3; consumer on PN4); one tolerated failure.
Mission mission_of(mission::PlacementMode mode, std::int64_t cpu, std::int64_t pn4_cpu,
                   std::int64_t consumer_cpu) {
    Mission m;
    m.name = "prove";
    m.nodes = {processing("PN1", cpu), processing("PN2", cpu), processing("PN3", cpu),
               processing("PN4", pn4_cpu), storage()};
    m.tasks = {task("producer", 30, false), task("consumer", consumer_cpu, true)};
    m.tolerance.node_failures = 1;
    m.tolerance.nodes = {"PN1", "PN2", "PN3", "PN4"};
    mission::Phase p;
    p.name = "nominal";
    p.placement = mode;
    p.tasks = {"producer", "consumer"};
    p.initial = "C1";
    p.configurations.push_back(
        configuration("C1", "PN1", {"PN2", "PN3"}, {{"producer", "PN2"}, {"consumer", "PN4"}}));
    m.phases.push_back(p);
    return m;
}

PhaseProof proof_of(const Mission& m, int failures) {
    const auto model = Model::build(m, nullptr);
    EXPECT_TRUE(model.has_value());
    return prove_phase(m, *model, 0, failures);
}

TEST(Prove, AnOnlinePhaseThatPlacesEveryTolerableFailureIsProved) {
    const Mission m = mission_of(mission::PlacementMode::online, 100, 100, 40);
    const PhaseProof p = proof_of(m, 1);
    EXPECT_EQ(p.violation_count, 0);
    EXPECT_EQ(p.within.failed_sets, 4);
    EXPECT_EQ(p.within.running_every_task, 4);
    EXPECT_EQ(p.states, 1);
    EXPECT_EQ(p.transitions, 5);  // PN1..PN4 and ST1
    // ST1 is not tolerated: beyond the tolerance, and nothing needs it.
    EXPECT_EQ(p.beyond.failed_sets, 1);
    EXPECT_EQ(p.beyond.running_every_task, 1);
}

TEST(Prove, AnEssentialTaskThePlacerCannotKeepIsAViolationWithItsSequence) {
    // Only PN4 has room for the consumer (60 cpu): PN4's failure leaves it nowhere.
    const Mission m = mission_of(mission::PlacementMode::online, 50, 100, 60);
    const PhaseProof p = proof_of(m, 1);
    ASSERT_EQ(p.violation_count, 1);
    ASSERT_EQ(p.violations.size(), 1u);
    EXPECT_EQ(p.violations[0].kind, "safe-mode-within-tolerance");
    EXPECT_EQ(p.violations[0].sequence, std::vector<int>{3});
    EXPECT_NE(p.violations[0].message.find("PN4 failed"), std::string::npos);
    EXPECT_EQ(p.within.safe, 1);
}

TEST(Prove, GraphPlusOnlineTakesTheGraphWhereItAnswersAndThePlacerElsewhere) {
    Mission m = mission_of(mission::PlacementMode::graph_online, 100, 100, 40);
    mission::Phase& p = m.phases[0];
    // PN4's failure: the graph's C2. PN1's: C3, whose Master (PN3) is not the elected PN2.
    // PN2's: SAFE. PN3's: no edge, and PN3 matters (an observer).
    p.configurations.push_back(
        configuration("C2", "PN1", {"PN2", "PN3"}, {{"producer", "PN2"}, {"consumer", "PN3"}}));
    p.configurations.push_back(
        configuration("C3", "PN3", {"PN2"}, {{"producer", "PN2"}, {"consumer", "PN4"}}));
    p.on_failure = {{"C1", "PN4", "C2", 0},
                    {"C1", "PN1", "C3", 0},
                    {"C1", "PN2", mission::kSafe, 0}};
    const PhaseProof proof = proof_of(m, 1);
    EXPECT_EQ(proof.violation_count, 0);
    EXPECT_EQ(proof.within.running_every_task, 4);
    EXPECT_EQ(proof.placements, 3);  // PN1, PN2, PN3 (and ST1's failure keeps C1: no edge)
}

TEST(Prove, BeyondTheToleranceEveryReachedFailedSetIsCountedOnce) {
    Mission m = mission_of(mission::PlacementMode::online, 100, 100, 40);
    m.tasks[1].checkpoint = true;  // needs the storage node alive
    const PhaseProof p = proof_of(m, 3);
    EXPECT_EQ(p.violation_count, 0);
    const Outcomes& beyond = p.beyond;
    EXPECT_EQ(beyond.failed_sets, beyond.running_every_task + beyond.shedding + beyond.safe);
    EXPECT_GT(p.beyond.failed_sets, 0);
    EXPECT_GT(p.beyond.safe, 0);  // ST1 among the failed
    // Memoised: fewer states than the 1 + 5 + 5 * 4 orders of at most two failures.
    EXPECT_LT(p.states, 1 + 5 + 5 * 4);
}

// Readmissions (spec/Rejoin.tla): in every state reached, each failed node comes back; in
// an online phase the placer answers every one, from the state's configuration, its
// Master staying; none is a violation here. Not vacuous: the readmissions are counted, and
// they grow with the failed sets (two failures: each state of one failure readmits one,
// each of two readmits two).
TEST(Prove, EveryReadmissionOfEveryReachedStateIsAnsweredByThePlacer) {
    const Mission m = mission_of(mission::PlacementMode::online, 100, 100, 30);
    const PhaseProof one = proof_of(m, 1);
    const PhaseProof two = proof_of(m, 2);
    EXPECT_EQ(one.violation_count, 0);
    EXPECT_EQ(two.violation_count, 0);
    EXPECT_GT(one.readmissions, 0);
    EXPECT_GT(two.readmissions, one.readmissions);
    EXPECT_LE(one.readmissions, 5);  // at most one per state of one failure (five nodes)
}

TEST(Prove, AProofThatReachesItsBoundIsIncomplete) {
    const Mission m = mission_of(mission::PlacementMode::online, 100, 100, 40);
    const auto model = Model::build(m, nullptr);
    ASSERT_TRUE(model.has_value());
    EXPECT_TRUE(prove_phase(m, *model, 0, 2).complete);
    const PhaseProof p = prove_phase(m, *model, 0, 2, 3);
    EXPECT_FALSE(p.complete);
    EXPECT_EQ(p.transitions, 3);
}

}  // namespace
}  // namespace keel::placement
