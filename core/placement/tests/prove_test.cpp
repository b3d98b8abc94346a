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

// Phase changes (prove.hpp): `mission_of`'s nominal phase, placed `mode`, with a second
// phase `science` placed `science_mode` (the same tasks), whose configurations are S1 (the
// image of C1) and S2, and C1 -> S1, C2 -> S2 on the change; in nominal PN3's failure
// leads to C2 (its observer PN2 alone).
Mission two_phases(mission::PlacementMode mode, mission::PlacementMode science_mode,
                   std::vector<std::string> s2_observers) {
    Mission m = mission_of(mode, 100, 100, 40);
    mission::Phase& nominal = m.phases[0];
    nominal.configurations.push_back(
        configuration("C2", "PN1", {"PN2"}, {{"producer", "PN2"}, {"consumer", "PN4"}}));
    if (mode != mission::PlacementMode::online) nominal.on_failure = {{"C1", "PN3", "C2", 0}};
    mission::Phase science;
    science.name = "science";
    science.placement = science_mode;
    science.tasks = {"producer", "consumer"};
    science.initial = "S1";
    mission::Configuration s1 =
        configuration("S1", "PN1", {"PN2", "PN3"}, {{"producer", "PN2"}, {"consumer", "PN4"}});
    mission::Configuration s2 =
        configuration("S2", "PN1", std::move(s2_observers), {{"producer", "PN2"}, {"consumer", "PN4"}});
    s1.phase = s2.phase = "science";
    science.configurations = {s1, s2};
    nominal.on_phase = {{"science", "C1", "S1", 0}, {"science", "C2", "S2", 0}};
    science.on_phase = {{"nominal", "S1", "C1", 0}, {"nominal", "S2", "C2", 0}};
    m.phases.push_back(science);
    if (mode == mission::PlacementMode::online) {  // an online phase has its initial alone
        m.phases[0].configurations.pop_back();
        m.phases[0].on_phase = {{"science", "C1", "S1", 0}};
        m.phases[1].on_phase = {{"nominal", "S1", "C1", 0}};
    }
    return m;
}

// A change into a graph+online phase after a failure takes the on_phase entry where the
// runtime does (its master this one, no failed host, valid under the failed set): S2 keeps
// PN3, failed, as its observer, so after PN3's failure the placer answers the change, and
// its answer is proved. With S2's observer PN2 the entry is taken: fewer placements.
TEST(Prove, APhaseChangeAfterAFailureTakesAnEntryValidUnderItAndThePlacerElsewhere) {
    const auto proofs_of = [](const Mission& m) {
        const auto model = Model::build(m, nullptr);
        EXPECT_TRUE(model.has_value());
        return prove(m, *model, 1);
    };
    const std::vector<PhaseProof> invalid_entry = proofs_of(two_phases(
        mission::PlacementMode::graph_online, mission::PlacementMode::graph_online, {"PN3"}));
    const std::vector<PhaseProof> valid_entry = proofs_of(two_phases(
        mission::PlacementMode::graph_online, mission::PlacementMode::graph_online, {"PN2"}));
    ASSERT_EQ(invalid_entry.size(), 2u);
    EXPECT_EQ(invalid_entry[0].violation_count + invalid_entry[1].violation_count, 0);
    EXPECT_EQ(valid_entry[0].violation_count + valid_entry[1].violation_count, 0);
    EXPECT_GT(valid_entry[1].phase_changes, 1);
    EXPECT_GT(invalid_entry[1].placements, valid_entry[1].placements);
}

// From an online configuration into a phase placed by its graph, the runtime takes that
// graph's configuration of the failed set, and refuses the change where it has none this
// Master drives (here its edge for PN2 is SAFE): a violation of the online phase, within
// the tolerance, where the mission names the change. Beyond it (K = 2, the tolerance PN2
// alone) nothing more is one.
TEST(Prove, APhaseChangeTheRuntimeRefusesWithinTheToleranceIsAViolation) {
    Mission m = two_phases(mission::PlacementMode::online, mission::PlacementMode::graph, {"PN2"});
    m.tolerance.nodes = {"PN2"};  // science's graph answers no other failure
    m.phases[1].on_failure = {{"S1", "PN2", mission::kSafe, 0}};
    const auto model = Model::build(m, nullptr);
    ASSERT_TRUE(model.has_value());
    const std::vector<PhaseProof> proofs = prove(m, *model, 2);
    ASSERT_EQ(proofs.size(), 1u);  // science is the verifier's
    ASSERT_EQ(proofs[0].violation_count, 1);
    const ProveViolation& v = proofs[0].violations[0];
    EXPECT_EQ(v.kind, "phase-transition-invalid");
    EXPECT_EQ(v.sequence, std::vector<int>{1});
    EXPECT_NE(v.message.find("the change to phase science is refused"), std::string::npos) << v.message;

    m.phases[0].on_phase.clear();  // a change the mission does not name: explored, no violation
    EXPECT_EQ(prove(m, *model, 2)[0].violation_count, 0);
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

TEST(Prove, AProofIsTheSameOnAnyNumberOfThreads) {
    // Twenty processing nodes; only PN4 has room for the essential consumer: every sequence
    // of at most three failures with PN4 in it is a violation, more than are listed.
    Mission m = mission_of(mission::PlacementMode::online, 50, 100, 60);
    for (int i = 5; i <= 20; ++i) {
        m.nodes.push_back(processing("PN" + std::to_string(i), 50));
        m.tolerance.nodes.push_back("PN" + std::to_string(i));
    }
    m.tolerance.node_failures = 3;
    const auto model = Model::build(m, nullptr);
    ASSERT_TRUE(model.has_value());
    const PhaseProof one = prove(m, *model, 3, kMaxProveTransitions, 1)[0];
    ASSERT_GT(one.violation_count, kMaxListedViolations);  // more found than listed
    ASSERT_EQ(one.violations.size(), static_cast<std::size_t>(kMaxListedViolations));
    ASSERT_GT(one.readmissions, 1000);  // many batches of readmissions, checked apart
    for (const int threads : {2, 3}) {
        const PhaseProof many = prove(m, *model, 3, kMaxProveTransitions, threads)[0];
        EXPECT_EQ(many.violation_count, one.violation_count) << threads;
        EXPECT_EQ(many.readmissions, one.readmissions) << threads;
        EXPECT_EQ(many.placements, one.placements) << threads;
        EXPECT_EQ(many.states, one.states) << threads;
        EXPECT_EQ(many.transitions, one.transitions) << threads;
        ASSERT_EQ(many.violations.size(), one.violations.size()) << threads;
        for (std::size_t i = 0; i < one.violations.size(); ++i) {
            EXPECT_EQ(many.violations[i].kind, one.violations[i].kind) << threads << " #" << i;
            EXPECT_EQ(many.violations[i].sequence, one.violations[i].sequence) << threads << " #" << i;
            EXPECT_EQ(many.violations[i].message, one.violations[i].message) << threads << " #" << i;
        }
    }
}

}  // namespace
}  // namespace keel::placement
