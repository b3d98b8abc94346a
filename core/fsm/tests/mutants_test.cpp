// The test library keel_fsm_mutants has its mutants (the witness of FlightLibrary's tests in
// core/node/tests/flight_test.cpp: the same sources, another build).
#include <gtest/gtest.h>

#include "core/fsm/mutants.hpp"

namespace keel::fsm {
namespace {

TEST(MutantsLibrary, CompilesEveryMutant) {
    EXPECT_TRUE(kMutantsCompiled);
    for (const Mutant mutant : all_mutants()) {
        EXPECT_TRUE(mutant_on(mutant, mutant)) << to_string(mutant);
        EXPECT_FALSE(mutant_on(Mutant::none, mutant)) << to_string(mutant);
        EXPECT_EQ(parse_mutant(to_string(mutant)), mutant);
    }
}

}  // namespace
}  // namespace keel::fsm
