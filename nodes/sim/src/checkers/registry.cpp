#include "nodes/sim/src/checkers.hpp"

namespace keel::sim {

std::vector<std::unique_ptr<Checker>> make_checkers() {
    std::vector<std::unique_ptr<Checker>> checkers;
    checkers.push_back(make_one_master_per_epoch());
    checkers.push_back(make_no_double_activation());
    checkers.push_back(make_no_task_on_failed_node());
    checkers.push_back(make_resume_latest_checkpoint());
    checkers.push_back(make_accuracy());
    checkers.push_back(make_completeness());
    checkers.push_back(make_no_false_exclusion());
    checkers.push_back(make_no_state_loss());
    checkers.push_back(make_no_honest_refusal());
    checkers.push_back(make_valid_config());
    checkers.push_back(make_durable_state());
    checkers.push_back(make_paused_task_idle());
    return checkers;
}

const std::vector<std::string>& invariant_names() {
    static const std::vector<std::string> names = {
        "OneMasterPerEpochInv", "NoDoubleActivationInv", "NoTaskOnFailedNodeInv",
        "ResumeLatestCheckpointInv", "AccuracyInv", "CompletenessInv", "NoFalseExclusionInv",
        "NoStateLossInv", "NoHonestRefusalInv", "ValidConfigInv", "DurableStateInv",
        "PausedTaskIdleInv", "SwitchConverges"};
    return names;
}

}  // namespace keel::sim
