// The simulator's checkers, one file each under checkers/, each named after the TLA+
// property it checks in the running C++ (spec/Heartbeat.tla, spec/MasterElection.tla,
// spec/ConfigSwitch.tla), plus the verifier's task-on-failed-node rule:
//
// | checker                   | what must hold after every step                           |
// |---------------------------|-----------------------------------------------------------|
// | OneMasterPerEpochInv      | no two nodes are ever Master of the same epoch             |
// | NoDoubleActivationInv     | two live nodes running the same task: one of them is       |
// |                           | excluded by the other's view (the spec's nodes never       |
// |                           | falsely suspect; ours may, so exclusion is the guard)      |
// | NoTaskOnFailedNodeInv     | no view places a task on a node it has declared failed,    |
// |                           | and a node its own view excludes runs nothing              |
// | ResumeLatestCheckpointInv | a checkpointed task starts from exactly the latest         |
// |                           | checkpoint on the Storage node; stored versions never fall |
// | NoStateLossInv            | a checkpointed task never starts below the state a live    |
// |                           | member of the starting node's view handed off              |
// | AccuracyInv               | a live node is declared failed only after at least         |
// |                           | miss_limit - 1 of its heartbeats in a row were lost        |
// | CompletenessInv           | a crashed node is declared by every live monitor within    |
// |                           | (miss_limit + 2) periods plus the largest delay            |
// | NoHonestRefusalInv        | no node refuses a message as malformed, unauthorized or   |
// |                           | no Master's: every simulated node is honest (fault model  |
// |                           | 3's checks, core/fsm/admission.hpp, cost nothing)          |
// | ValidConfigInv            | no correct node holds or drives a view the proven graph   |
// |                           | does not place (a value-faulty Master's, keel-sim --liar) |
// | DurableStateInv           | a node restarts with a view and an incarnation no lower   |
// |                           | than its own messages named (its state was saved before   |
// |                           | they left: the driver's rule 1)                           |
// | SwitchConverges           | once faults stop, the spec's Converged is reached: one     |
// |                           | idle Master, every live node it has not excluded holds its |
// |                           | view, Stable, running exactly its tasks (checked by        |
// |                           | Simulation::stabilize, not after every step)               |
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nodes/sim/src/simulation.hpp"

namespace keel::sim {

class Checker {
public:
    virtual ~Checker() = default;
    virtual const char* invariant() const = 0;
    // After every step of `node`; sim.step_actions() holds the actions of the step.
    virtual void after_step(Simulation& sim, NodeId node) = 0;
};

std::vector<std::unique_ptr<Checker>> make_checkers();
const std::vector<std::string>& invariant_names();

// The spec's Converged (checkers/switch_converges.cpp): true when the cluster has
// converged; else `why` says what differs.
bool check_converged(const Simulation& sim, std::string* why);

std::unique_ptr<Checker> make_one_master_per_epoch();
std::unique_ptr<Checker> make_no_double_activation();
std::unique_ptr<Checker> make_no_task_on_failed_node();
std::unique_ptr<Checker> make_resume_latest_checkpoint();
std::unique_ptr<Checker> make_accuracy();
std::unique_ptr<Checker> make_no_false_exclusion();
std::unique_ptr<Checker> make_completeness();
std::unique_ptr<Checker> make_no_state_loss();
std::unique_ptr<Checker> make_no_honest_refusal();
std::unique_ptr<Checker> make_valid_config();
std::unique_ptr<Checker> make_durable_state();
std::unique_ptr<Checker> make_paused_task_idle();

}  // namespace keel::sim
