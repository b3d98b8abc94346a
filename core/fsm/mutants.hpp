// Deliberately broken variants of the state machines, for tests only.
//
// Each mutant breaks one rule that one simulator checker (named after a TLA+ invariant)
// exists to protect; tests/sim runs a campaign per mutant and expects that checker to
// fire within a bounded number of seeds — proof that the checkers can fail. A node runs
// correct code unless NodeOptions::mutant says otherwise; the runtime never sets it.
//
// Mutants exist only in the test library, keel_fsm_mutants (compiled with KEEL_FSM_MUTANTS,
// linked by keel-sim and the tests). In the flight library, keel_fsm (keel-node's),
// mutant_on() is the constant false: every mutant branch is dead code the compiler drops,
// whatever NodeOptions::mutant says.
#pragma once

#include <optional>
#include <string_view>
#include <vector>

namespace keel::fsm {

enum class Mutant {
    none,
    // Election: no stale-epoch rejection, epochs claimed as epoch + 1 by whoever suspects
    // the Master, without waiting for higher-priority Observers. Breaks OneMasterPerEpochInv.
    election_no_epoch_check,
    // ConfigSwitch: a node activates its new tasks as soon as it receives the Command,
    // before the others have deactivated theirs. Breaks NoDoubleActivationInv.
    activate_before_deactivate,
    // ConfigSwitch: a checkpointed task starts from scratch instead of from the Storage
    // node's latest checkpoint. Breaks ResumeLatestCheckpointInv.
    no_checkpoint_restore,
    // Heartbeat: a node is declared failed after one missed period. Breaks AccuracyInv.
    declare_on_first_miss,
    // Heartbeat: a node is declared failed only after twice the miss limit. Breaks
    // CompletenessInv.
    late_declare,
    // ReconfigurationManager: a failed worker is added to the failed set but the decision
    // graph is not walked, so its tasks stay placed on it. Breaks NoTaskOnFailedNodeInv.
    ignore_failed_node_in_placement,
    // ConfigSwitch: the Master never retransmits a Command or an Activate, so a lost
    // message stalls the switch forever. Breaks SwitchConverges.
    no_retransmit,
    // ConfigSwitch: at first boot a node activates its initial-configuration tasks at
    // version 0 by itself, without a Command (the behaviour before the boot switch). A node
    // whose process starts after the cluster moved its task elsewhere runs a stale copy.
    // Breaks ResumeLatestCheckpointInv (with boot skew).
    boot_activates,
    // Heartbeat: a node never heard since boot is declared after miss_limit periods, as if
    // there were no start-up grace. Breaks AccuracyInv (its start-up clause).
    no_startup_grace,
    // Heartbeat: a monitor counts a period in which it heard no one, or in which its own
    // loop ran late, against every node it watches (no self-suspicion). A deaf or starved
    // monitor declares healthy nodes. Breaks NoFalseExclusionInv (when the Master is the
    // last monitor) and AccuracyInv.
    no_self_suspicion,
    // NodeProtocol: the Master excludes a node on one declaration, its own or one
    // Observer's report (the rule before fault model 2). A single partly deaf monitor gets
    // healthy nodes excluded. Breaks NoFalseExclusionInv.
    single_report_exclusion,
    // NodeProtocol: no lease (the rule before fault model 2): a node cut off from its
    // monitors keeps running its tasks, and a cut-off or mute Master keeps commanding,
    // while the cluster replaces them. Breaks NoExcludedRunsInv.
    no_lease,
    // NodeProtocol: no reintegration (the rule before spec/Rejoin.tla): an excluded node
    // stays out for good, restarted or healed, and one restart spends the tolerance.
    // Breaks SwitchConverges (its reintegration clause).
    no_readmission,
    // ConfigSwitch: the ground's pause of a task is taken (its GroundPause line) but the
    // task runs on. Breaks PausedTaskIdle (keel-sim) and trace validation's Steps.
    pause_keeps_running,
    // NodeProtocol: the ground counts with a node in a tie for ever (no standing
    // acknowledgement that runs out: spec/Designate.tla's DesignateAdmittedOnly): a node the
    // designation's side cut off runs on beside the designee. Breaks
    // AtMostOneRunningMasterInv or NoExcludedRunsInv (keel-sim --ground-designates).
    designate_no_grace,
    // NodeProtocol: a designation's wait is ignored (DesignateAtOnce): a later designee
    // acts while an earlier one's vote still runs. Breaks the same.
    designate_at_once,
    // ConfigSwitch: without the Storage node a checkpointed task starts from version 0 on
    // its new host, instead of from the state its old host handed off (the rule before
    // fault model 2, item 4). Breaks NoStateLossInv.
    no_holder_restore,
    // ConfigSwitch: a hand-off made while the Storage node was excluded is not flushed to
    // it when a view includes it again; a later start restores the Storage node's older
    // version. Breaks NoStateLossInv.
    handoff_not_flushed,
    // NodeProtocol: a Master whose switch is under way judges its lease and its evidence
    // by the view it drives only, not also by the views some node may still go by (no
    // joint views; spec/Quorum.tla, QuorumNoJointLease).
    no_joint_views,
    // NodeProtocol: the rules before spec/Quorum.tla (QuorumBeforeFix): two declarations
    // enough for an exclusion and the lease whatever the view's size (one when one voter is
    // left), and no joint views. A phase switch cut by a partition leaves two running
    // Masters.
    quorum_before_fix,
    // ConfigSwitch: a start without the Storage node keeps the lineage of the state it
    // starts from instead of opening one (the rule before lineages): a readmitted Storage
    // node keeps a state of the lineage the cluster abandoned, with more steps, over the
    // one it went on with, and a later start from it restores the abandoned lineage.
    // Breaks NoStateLossInv (spec/Handoff.tla: HandoffVersionsByCount).
    lineage_kept,
    // NodeProtocol: a receiver checking its Master's next switch knows no phase edge of
    // the decision graph (admission.hpp, edge_problem): every honest phase change is
    // refused as no Master's, and its Master declared wrong. Breaks NoHonestRefusalInv.
    refuse_phase_edges,
    // NodeProtocol: none of fault model 3's receiver checks (admission.hpp): no bounds
    // against the mission, no authority by role, no check of the Master's Commands, no
    // epoch bound, no wait for the members' Prepared (rule 4; rule 5 goes with the check
    // of the Commands). The baseline of ./keel bench admission (the checks' cost); with a
    // value-faulty node it aborts (an id the mission lacks reaches an index).
    no_receiver_checks,
    // ConfigSwitch: a node starts its new tasks on its Master's Activate alone, without
    // every other member's Prepared for the same view (rule 4): a lying Master that
    // activates one node before another has stopped the task runs it twice.
    no_peer_prepared,
    // NodeProtocol: a receiver follows a Command whatever exclusions it adds, backed by no
    // declaration of any node but its sender (rule 5): a lying Master excludes a live node
    // and gives its task to another.
    unbacked_exclusions,
    // HeartbeatMonitor: monitors ignore the boot identifier in heartbeats and go by the
    // incarnation alone: a node restarted from a state file that went back (a lost write,
    // a restored file) is heard as the node it was, and the cluster still places the tasks
    // it lost on it.
    ignore_boot,
    // NodeProtocol: no warm boot. After a whole-cluster power cycle every node waits to
    // be commanded and none ever is (spec mutant ElectionNoWarmBoot).
    no_warm_boot,
    // NodeProtocol: a Command's view is not checked against the graph (view_problem,
    // edge_problem): a value-faulty Master's view off the graph is followed. Breaks
    // ValidConfigInv (keel-sim --liar).
    no_view_check,
    // NodeProtocol: a node that opened its epoch itself (the initial Master, a take-over)
    // bounds the epochs it takes from heartbeats as one never commanded (up to the width):
    // one heartbeat of a liar's moves a Master's epoch to where no node follows it.
    // Breaks SwitchConverges (keel-sim --liar).
    unbounded_master_epoch,
    // NodeProtocol: the warm boot counts only waiting (restarted) processing nodes, not
    // those that know themselves excluded: a value-faulty Master that fenced every other
    // processing node and restarted leaves the cluster headless. Breaks SwitchConverges
    // (keel-sim --liar).
    warm_boot_waiting_only,
    // ConfigSwitch: a node's Prepared names the digest of another view than the one it
    // prepared: every member it reaches counts a divergence (NodeStats::prepared_diverged)
    // in an honest cluster. Breaks NoHonestRefusalInv, the witness that the checker reads
    // that counter.
    prepared_other_digest,
    // NodeDriver (core/node/driver.hpp, rule 2): the Storage node's acknowledgements,
    // restore replies and StoreCheckpoint lines go at once, not when the checkpoint they
    // stand for is on its disk: a power loss before the write loses a version the cluster
    // was told is stored. Breaks ResumeLatestCheckpointInv (its durable clause).
    release_held_early,
    // NodeDriver (rule 1): the node's state is saved after the messages of the step that
    // changed it have left, and a failed save drops none of them.
    save_after_send,
    // NodeDriver (rule 3): a checkpoint write that failed is taken for a written one: what
    // waited for it is released and the Storage node flies on without it. Breaks
    // ResumeLatestCheckpointInv (its durable clause) once the Storage node restarts.
    ignore_failed_write,
    // NodeProtocol: a node takes a hand-over whatever boot of it the hand-over names: one
    // that restarted within the repeats of a hand-over meant for its previous boot becomes
    // Master of that epoch beside the Observer that took over from it meanwhile. Rejected
    // by trace validation (TraceElection's hand-over names its receiver's boot).
    hand_over_any_boot,
    // NodeProtocol: an Observer never declares its view's Master for leaving the view (its
    // heartbeats saying it follows a newer epoch no Command of which came): a value-faulty
    // Master that leaves a node in an epoch of its own alone, and hands the others an
    // older one naming that node, leaves the cluster headless. Breaks SwitchConverges
    // (keel-sim --liar, earth-observation seed 13921).
    no_master_left,
    // NodeProtocol (online placement, spec/Online.tla's OnlineNoReceiverCheck): a node takes
    // the online configuration a Command carries without running the checker on it, nor
    // online.hpp's rules for the switch to it. Breaks ValidConfigInv (keel-sim --liar on a
    // mission whose phases place online).
    no_online_check,
    // ReconfigurationManager and NodeProtocol (online placement): a Master driving an online
    // configuration answers the next failure with safe mode, and so does a node taking over
    // from an online configuration, although its placer finds a placement; receivers take
    // that safe mode (online_edge_problem's rule skipped). No safety property breaks; trace
    // validation refuses the Exclude or BecomeMaster line (switch.py asks keel-place whether
    // the placer places there).
    online_gives_up,
};

#ifdef KEEL_FSM_MUTANTS
inline constexpr bool kMutantsCompiled = true;
// Whether the mutant `which` is the active one.
constexpr bool mutant_on(Mutant active, Mutant which) { return active == which; }
#else
inline constexpr bool kMutantsCompiled = false;
constexpr bool mutant_on(Mutant, Mutant) { return false; }
#endif

std::string_view to_string(Mutant mutant);
std::optional<Mutant> parse_mutant(std::string_view name);
const std::vector<Mutant>& all_mutants();

}  // namespace keel::fsm
