// The placer: a configuration for a phase under a failed set, computed online, or none.
//
// A deterministic function of the model, the phase, the failed set and the current
// configuration (its ids are the tie-breakers everywhere). What it returns passes the
// checker (check.hpp, with Shedding::allowed), which every node runs again before it acts.
//
// - The master stays where it is if it is alive; otherwise it is the current
//   configuration's first alive observer (whom the election makes Master), else the first
//   alive processing node. The observers are the current ones still alive, in their order,
//   topped up from the alive processing nodes in id order to as many as before (at least
//   one where two or more processing nodes are alive).
// - Tasks stay on their hosts where they can (alive, able, within capacity, in id order);
//   the others are placed in order of need (essential first, then the higher priority,
//   then the larger load) on the able node with room that hosts no task of the same group,
//   else on any able node with room, the tightest fit first. A checkpointed task needs an
//   alive storage node.
// - If a task fits nowhere that way, two more passes run in order of need, each task
//   placed when its turn comes or shed when it fits nowhere: one that keeps a task on its
//   host where it still fits, one that places every task afresh. The best of these and
//   the first pass (its tasks that fit nowhere shed) is taken: the essential tasks
//   placed, then the lower priorities shed (the highest shed first compared, then fewer),
//   then the fewer moves. If none places every essential task, a depth-first search
//   places them (at most 4,096 nodes tried that can take a task; it does not spread
//   groups), then the others as before.
//   When that fails too, or no processing node is alive, the answer is safe mode.
//
// Bounded: O(3 * tasks * nodes + 4,096 * nodes) time, O(tasks + nodes) memory. Bin packing is hard;
// this is a heuristic, and it may shed where an exact packing would have fitted: the
// verifier reports what it does beyond the mission's tolerance.
#pragma once

#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/placement/model.hpp"

namespace keel::placement {

struct Placement {
    bool safe = false;        // no placement of the essential tasks: safe mode
    Configuration config;     // when !safe
    std::vector<int> shed;    // tasks of the phase left unplaced, in shedding order
    int moved = 0;            // tasks hosted in `current` that now run elsewhere
    int started = 0;          // tasks placed now that `current` did not place
};

// The placer's pass that places every task afresh depends on the phase and the failed set
// alone (not on the current configuration): a caller that places many times under the
// same failed sets (the prover, prove.hpp) keeps those passes across calls here. One per
// thread and per model (its keys are the failed set and the phase); at most kMaxKept (then
// emptied).
class FreshPasses {
  public:
    struct Pass {
        std::vector<int> host;
        std::vector<int> shed;
        bool essential_placed = true;
    };
    static constexpr std::size_t kMaxKept = 1 << 15;

    const Pass* find(const std::string& key) const {
        const auto it = kept_.find(key);
        return it == kept_.end() ? nullptr : &it->second;
    }
    void keep(std::string key, Pass pass) {
        if (kept_.size() >= kMaxKept) kept_.clear();
        kept_.emplace(std::move(key), std::move(pass));
    }

  private:
    std::unordered_map<std::string, Pass> kept_;  // by phase and failed set
};

// `current` is the configuration the cluster runs (for a phase change, the previous
// phase's); a `host` of the wrong size is read as placing nothing. `fresh`: where the
// fresh passes are kept across calls (nullptr: none; the answer is the same).
Placement place(const Model& model, int phase, const FailedSet& failed,
                const Configuration& current, FreshPasses* fresh = nullptr);

}  // namespace keel::placement
