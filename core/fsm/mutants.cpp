#include "core/fsm/mutants.hpp"

namespace keel::fsm {

const std::vector<Mutant>& all_mutants() {
    static const std::vector<Mutant> mutants = {
        Mutant::election_no_epoch_check,   Mutant::activate_before_deactivate,
        Mutant::no_checkpoint_restore,     Mutant::declare_on_first_miss,
        Mutant::late_declare,              Mutant::ignore_failed_node_in_placement,
        Mutant::no_retransmit,             Mutant::boot_activates,
        Mutant::no_startup_grace,          Mutant::no_self_suspicion,
        Mutant::single_report_exclusion,   Mutant::no_lease,
        Mutant::no_readmission,            Mutant::no_holder_restore,
        Mutant::handoff_not_flushed,       Mutant::lineage_kept,
        Mutant::no_joint_views,            Mutant::quorum_before_fix,
        Mutant::refuse_phase_edges,        Mutant::no_receiver_checks,
        Mutant::no_peer_prepared,          Mutant::unbacked_exclusions,
        Mutant::ignore_boot,               Mutant::no_warm_boot,
        Mutant::no_view_check,             Mutant::unbounded_master_epoch,
        Mutant::warm_boot_waiting_only,    Mutant::prepared_other_digest,
        Mutant::release_held_early,        Mutant::save_after_send,
        Mutant::ignore_failed_write,       Mutant::hand_over_any_boot,
        Mutant::no_master_left,            Mutant::pause_keeps_running,
        Mutant::designate_no_grace,        Mutant::designate_at_once,
        Mutant::no_online_check,           Mutant::online_gives_up,
    };
    return mutants;
}

std::string_view to_string(Mutant mutant) {
    switch (mutant) {
        case Mutant::none: return "none";
        case Mutant::election_no_epoch_check: return "election-no-epoch-check";
        case Mutant::activate_before_deactivate: return "activate-before-deactivate";
        case Mutant::no_checkpoint_restore: return "no-checkpoint-restore";
        case Mutant::declare_on_first_miss: return "declare-on-first-miss";
        case Mutant::late_declare: return "late-declare";
        case Mutant::ignore_failed_node_in_placement: return "ignore-failed-node-in-placement";
        case Mutant::no_retransmit: return "no-retransmit";
        case Mutant::boot_activates: return "boot-activates";
        case Mutant::no_startup_grace: return "no-startup-grace";
        case Mutant::no_self_suspicion: return "no-self-suspicion";
        case Mutant::single_report_exclusion: return "single-report-exclusion";
        case Mutant::no_lease: return "no-lease";
        case Mutant::no_readmission: return "no-readmission";
        case Mutant::no_holder_restore: return "no-holder-restore";
        case Mutant::handoff_not_flushed: return "handoff-not-flushed";
        case Mutant::lineage_kept: return "lineage-kept";
        case Mutant::no_joint_views: return "no-joint-views";
        case Mutant::quorum_before_fix: return "quorum-before-fix";
        case Mutant::refuse_phase_edges: return "refuse-phase-edges";
        case Mutant::no_receiver_checks: return "no-receiver-checks";
        case Mutant::no_peer_prepared: return "no-peer-prepared";
        case Mutant::unbacked_exclusions: return "unbacked-exclusions";
        case Mutant::ignore_boot: return "ignore-boot";
        case Mutant::no_warm_boot: return "no-warm-boot";
        case Mutant::no_view_check: return "no-view-check";
        case Mutant::no_online_check: return "no-online-check";
        case Mutant::online_gives_up: return "online-gives-up";
        case Mutant::unbounded_master_epoch: return "unbounded-master-epoch";
        case Mutant::warm_boot_waiting_only: return "warm-boot-waiting-only";
        case Mutant::prepared_other_digest: return "prepared-other-digest";
        case Mutant::release_held_early: return "release-held-early";
        case Mutant::save_after_send: return "save-after-send";
        case Mutant::ignore_failed_write: return "ignore-failed-write";
        case Mutant::hand_over_any_boot: return "hand-over-any-boot";
        case Mutant::no_master_left: return "no-master-left";
        case Mutant::pause_keeps_running: return "pause-keeps-running";
        case Mutant::designate_no_grace: return "designate-no-grace";
        case Mutant::designate_at_once: return "designate-at-once";
    }
    return "none";
}

std::optional<Mutant> parse_mutant(std::string_view name) {
    if (name == "none") return Mutant::none;
    for (Mutant mutant : all_mutants()) {
        if (to_string(mutant) == name) return mutant;
    }
    return std::nullopt;
}

}  // namespace keel::fsm
