// What keel-node links is flight code: the protocol state machines without their test
// mutants (core/fsm/mutants.hpp), and assertions on.
#include <gtest/gtest.h>

#include <cassert>

#include "core/fsm/mutants.hpp"

namespace {

using keel::fsm::Mutant;

TEST(FlightLibrary, CompilesNoMutant) {
    EXPECT_FALSE(keel::fsm::kMutantsCompiled);
    // Whatever a caller asks for, no mutant branch is taken.
    for (const Mutant mutant : keel::fsm::all_mutants()) {
        EXPECT_FALSE(keel::fsm::mutant_on(mutant, mutant)) << keel::fsm::to_string(mutant);
    }
}

TEST(FlightLibrary, KeepsAssertionsOn) {
#ifdef NDEBUG
    FAIL() << "NDEBUG is defined: assertions are compiled out of the flight build";
#endif
    EXPECT_DEATH(assert(1 + 1 == 3), "");
}

}  // namespace
