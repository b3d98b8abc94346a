// Data-driven scenario tests, in the style of etcd raft's testdata/*.txt.
//
// A scenario file is a list of blocks separated by blank lines. Each block is one command
// line, a line "----", and the expected output (no blank lines inside). Lines starting with
// '#' before a command are comments. Commands:
//
//   mission PATH [seed=N]               load a mission (path relative to the repo root);
//                                       must come first. The cluster boots at the first
//                                       command that is not `boot` (the initial Master's
//                                       boot switch shows in that command's output)
//   boot NODE at DURATION               NODE's process starts late (first boot at that
//                                       time); only before the cluster has booted
//   tick DURATION                       run the clock forward (300ms, 1.5s)
//   crash NODE | restart NODE           a node stops / boots again from its persisted state
//   restart NODE rolled-back            ... from the state it saved before its last boot
//                                       (incarnation and all: a lost write, a restored file)
//   resign NODE                         NODE asks to be treated as failed (a task keeps
//                                       failing there): NodeProtocol::resign
//   partition A B | C D                 symmetric partition between the two groups
//   partition A -> B C                  one-way: A's messages to B and C are lost
//   deaf NODE                           NODE receives nothing (it still sends) until heal
//   pause NODE DURATION                 NODE's process stops (SIGSTOP) for DURATION; what
//                                       arrives meanwhile waits in its queue
//   heal                                end every partition and deafness
//   loss PERCENT                        message loss rate from now on (e.g. loss 5%)
//   disk MIN MAX                        a checkpoint write takes MIN to MAX from now on
//   power-loss NODE [checkpoint]        power is lost at NODE's next disk write (its next
//                                       checkpoint write): down mid-step, the write lost
//   disk-fail NODE | disk-full NODE     every write of NODE's disk fails (full: every
//                                       checkpoint write) until it restarts
//   phase NAME                          a planned phase change, sent to the acting Master
//   stabilize                           heal, stop losses, run until agreement (or fail)
//   status                              one line per node: role, epoch, view, tasks
//   checkpoints                         per checkpointed task: the version the Storage
//                                       node holds, where the task runs and its step
//
// The output of a command is what the state machines did meanwhile: declarations,
// elections, switches started and completed, tasks activated and deactivated, safe mode,
// and any checker violation — one line each, with the virtual time.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/fsm/mutants.hpp"

namespace keel::sim {

struct ScenarioResult {
    bool passed = false;
    std::string diff;      // human-readable mismatches
    std::string rewritten;  // the file with actual outputs (for KEEL_UPDATE_GOLDEN=1)
    int violations = 0;     // checker violations reported in the outputs
};

// The same fault story under another seed or with a mutant (trace validation's mutant
// sweep runs the scenario that reaches a mutant's rule): the seed of its `mission` line
// is replaced, and every node runs the mutant. The golden output no longer applies.
struct ScenarioVariant {
    std::optional<std::uint64_t> seed;
    fsm::Mutant mutant = fsm::Mutant::none;
};

// Runs a scenario file; `root` resolves mission paths. With a `trace_path`, every state
// machine action and environment event is also written there as NDJSON (docs/verification.md).
ScenarioResult run_scenario_file(const std::string& path, const std::string& root,
                                 const std::string& trace_path = {},
                                 const ScenarioVariant& variant = {});

}  // namespace keel::sim
