// The simulator's checkers, one file each under checkers/, each named after the TLA+
// invariant it checks (spec/Heartbeat.tla, spec/MasterElection.tla, spec/ConfigSwitch.tla):
//
// | checker                    | what must hold after every step                          |
// |----------------------------|----------------------------------------------------------|
// | OneMasterPerEpochInv       | no two nodes are ever Master of the same epoch            |
// | NoDoubleActivationInv      | two live nodes running the same task: one of them is     |
// |                            | excluded by the other's view                             |
// | NoTaskOnFailedNodeInv      | no view places a task on a node it has declared failed,  |
// |                            | and a node its own view excludes runs nothing            |
// | CheckpointContinuityInv    | a checkpointed task resumes from the latest checkpoint   |
// |                            | on the Storage node; stored versions never go back       |
// | AccuracyInv                | a live node is declared failed only after at least       |
// |                            | miss_limit - 1 of its heartbeats in a row were lost      |
// | CompletenessInv            | a crashed node is declared by every live monitor within  |
// |                            | (miss_limit + 2) periods plus the largest delay          |
// | AgreementInv               | once faults stop: one acting Master, every live node it  |
// |                            | has not excluded holds its view, Stable, running exactly |
// |                            | its tasks (checked by Simulation::stabilize)             |
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

// AgreementInv (checkers/agreement.cpp): true when the cluster agrees; else `why` says
// what differs.
bool check_agreement(const Simulation& sim, std::string* why);

std::unique_ptr<Checker> make_one_master_per_epoch();
std::unique_ptr<Checker> make_no_double_activation();
std::unique_ptr<Checker> make_no_task_on_failed_node();
std::unique_ptr<Checker> make_checkpoint_continuity();
std::unique_ptr<Checker> make_accuracy();
std::unique_ptr<Checker> make_completeness();

}  // namespace keel::sim
