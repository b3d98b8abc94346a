// The honest prefixes: realistic states to start forging from. A scenario is a short honest
// story (the boot switch, then maybe a crash, a late boot, a restart, a resignation, a phase
// request, or two crashes that leave the tolerance for safe mode); running it keeps the
// cluster after each of its first kPrefixRounds heartbeat periods. A fuzz input picks a
// scenario and a number of periods and starts from that copy, so every role and stage of
// both missions is one choice away: Master, Observer, Worker and Storage node, mid-switch,
// holding, excluded, safe mode.
//
// The scenarios of a mission, in this order (tests/fuzz/make-corpus names them so):
//   boot             every node boots at time zero; nothing else happens
//   crash N          N crashes after kEventRound periods (each node N)
//   late N           N boots kLateBootRound periods after the others (each node N)
//   restart N        N crashes after kEventRound periods and boots again from its state
//                    kRestartDelay periods later, to be readmitted (each node N)
//   resign N         N resigns after kEventRound periods (each node N)
//   phase P          the initial Master is asked for phase P after kEventRound periods
//                    (each phase P but the first)
//   crash A then B   A crashes after kEventRound periods, B kSecondCrashDelay later (each
//                    pair of processing nodes A < B)
// Each runs twice, with the nodes' tracing off and on.
#pragma once

#include <string>
#include <vector>

#include "tests/fuzz/cluster.hpp"

namespace keel::fuzz {

inline constexpr int kPrefixRounds = 24;
inline constexpr int kEventRound = 4;
inline constexpr int kLateBootRound = 2;
inline constexpr int kRestartDelay = 4;
inline constexpr int kSecondCrashDelay = 6;

struct ScenarioEvent {
    enum class Kind { crash, restart, resign, phase };
    int round = 0;
    Kind kind = Kind::crash;
    int argument = 0;  // a node id, or for phase a phase id
};

struct Scenario {
    std::string name;
    fsm::NodeSet booted;                // the nodes that boot at time zero
    std::vector<ScenarioEvent> events;  // in round order
};

std::vector<Scenario> scenarios(const fsm::Topology& topology);

class Prefixes {
  public:
    // Runs every scenario of the mission (a second under the sanitizers, once), with the
    // nodes' tracing on or off.
    Prefixes(const fsm::Topology& topology, bool tracing);

    int scenario_count() const { return static_cast<int>(scenarios_.size()); }
    const Scenario& scenario(int index) const {
        return scenarios_[static_cast<std::size_t>(index)];
    }
    // The cluster of `scenario` after `rounds` periods (0 to kPrefixRounds).
    const Cluster& at(int scenario, int rounds) const;

  private:
    std::vector<Scenario> scenarios_;
    std::vector<std::vector<Cluster>> clusters_;  // per scenario, per round
};

}  // namespace keel::fuzz
