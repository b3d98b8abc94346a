#include "core/fsm/election.hpp"

#include <gtest/gtest.h>

#include "test_mission.hpp"

namespace keel::fsm {
namespace {

class ElectionTest : public ::testing::Test {
protected:
    Topology topology = testing::prototype3_topology();
    NodeId PN1 = 0, PN2 = 1, PN3 = 2, ST1 = 3;
    View view = topology.initial_view();
    Outbox out{false};
};

TEST_F(ElectionTest, RolesFromTheView) {
    EXPECT_EQ(Election(topology, PN1, view, 1, false, Mutant::none).role(), Role::Master);
    EXPECT_EQ(Election(topology, PN2, view, 1, false, Mutant::none).role(), Role::Observer);
    EXPECT_EQ(Election(topology, ST1, view, 1, false, Mutant::none).role(), Role::Worker);
    EXPECT_EQ(Election(topology, PN1, view, 1, true, Mutant::none).role(), Role::Worker);
}

TEST_F(ElectionTest, StaleEpochsAreRejected) {
    Election election(topology, PN2, view, 3, false, Mutant::none);
    EXPECT_TRUE(election.is_stale(2));
    EXPECT_FALSE(election.is_stale(3));
    EXPECT_FALSE(election.is_stale(4));
    Election mutant(topology, PN2, view, 3, false, Mutant::election_no_epoch_check);
    EXPECT_FALSE(mutant.is_stale(2));
}

TEST_F(ElectionTest, FirstObserverTakesOverInItsOwnEpoch) {
    Election election(topology, PN2, view, 1, false, Mutant::none);
    EXPECT_TRUE(election.suspect(PN1, view, true, out));
    EXPECT_EQ(election.become_master(view, out), 2u);
    EXPECT_EQ(election.role(), Role::Master);
    EXPECT_EQ(election.leader(), PN2);
}

TEST_F(ElectionTest, SecondObserverWaitsForTheFirst) {
    Election election(topology, PN3, view, 1, false, Mutant::none);
    EXPECT_FALSE(election.suspect(PN1, view, true, out));
    EXPECT_TRUE(election.suspect(PN2, view, true, out));
    EXPECT_EQ(election.become_master(view, out), 3u);
}

TEST_F(ElectionTest, ANodeThatHearsNobodyDoesNotTakeOver) {
    Election election(topology, PN2, view, 1, false, Mutant::none);
    EXPECT_FALSE(election.suspect(PN1, view, false, out));
    EXPECT_TRUE(election.may_take_over(view, true));
}

TEST_F(ElectionTest, ASuspicionCanBeWithdrawn) {
    Election election(topology, PN2, view, 1, false, Mutant::none);
    election.suspect(PN1, view, false, out);
    election.clear_suspect(PN1);
    EXPECT_FALSE(election.may_take_over(view, true));
}

TEST_F(ElectionTest, WorkersNeverTakeOver) {
    Election election(topology, ST1, view, 1, false, Mutant::none);
    EXPECT_FALSE(election.suspect(PN1, view, true, out));
}

TEST_F(ElectionTest, ACommandOfAHigherEpochMakesTheMasterStepDown) {
    Election election(topology, PN1, view, 1, false, Mutant::none);
    View next = view;
    next.epoch = 2;
    next.seq = 1;
    next.config = *topology.config_id("P2");
    next.base = next.config;
    next.master = PN2;
    next.failed.insert(PN1);
    election.receive_command(Command{PN2, next}, out);
    EXPECT_EQ(election.epoch(), 2u);
    EXPECT_EQ(election.leader(), PN2);
    EXPECT_EQ(election.role(), Role::Worker);
}

TEST_F(ElectionTest, ACommandClearsSuspicionOfItsSender) {
    Election election(topology, PN3, view, 1, false, Mutant::none);
    election.suspect(PN1, view, true, out);
    EXPECT_TRUE(election.suspects().contains(PN1));
    View again = view;
    again.seq = 1;
    election.receive_command(Command{PN1, again}, out);
    EXPECT_FALSE(election.suspects().contains(PN1));
}

TEST_F(ElectionTest, MutantClaimsWithoutOwnership) {
    Election a(topology, PN2, view, 1, false, Mutant::election_no_epoch_check);
    Election b(topology, PN3, view, 1, false, Mutant::election_no_epoch_check);
    ASSERT_TRUE(a.suspect(PN1, view, true, out));
    ASSERT_TRUE(b.suspect(PN1, view, true, out));
    EXPECT_EQ(a.become_master(view, out), b.become_master(view, out));
}

}  // namespace
}  // namespace keel::fsm
