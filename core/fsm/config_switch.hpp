// ConfigSwitch: the two-phase configuration switch (spec/ConfigSwitch.tla, fsm "switch").
//
// A switch is identified by <<epoch, seq>>. The Master broadcasts a Command; every live
// node (every node not in the view's failed set) deactivates the tasks that leave it,
// flushes their final checkpoints to the Storage node and acks Prepared. Only when every
// live node has acked Prepared does the Master broadcast Activate; nodes then start their
// new tasks — checkpointed ones from the latest checkpoint on the Storage node — and ack
// Activated; when all have, the Master completes the switch. A task therefore never runs
// on two live nodes at once, and a migrated task resumes where its previous owner stopped.
//
// One object per node holds both halves: the participant (every node) and the driver
// (masterStage, used while the node is Master). Sends to the node itself are normal sends;
// NodeProtocol delivers them back in order.
//
// Ordering contract:
//  1. Stale messages never reach this class (Election::is_stale, NodeProtocol::step).
//  2. receive_command() after Election::receive_command() for the same Command.
//  3. start_switch() with each view ReconfigurationManager returns, at once.
//  4. task_stepped() once per execution of an active task, with the task's new state;
//     never for a task after its Deactivate action.
//  5. tick() once per heartbeat period: it retransmits whatever is unacknowledged (the
//     channel may lose anything), so progress needs no other timer.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/fsm/actions.hpp"
#include "core/fsm/mutants.hpp"
#include "core/fsm/request_budget.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

enum class Stage : std::uint8_t { Stable, Deactivating, Prepared, Activating };
enum class MasterStage : std::uint8_t { Idle, Preparing, Activating };
const char* to_string(Stage stage);
const char* to_string(MasterStage stage);

class ConfigSwitch {
public:
    // Boot: nothing runs. First boot: `view` is the initial view (epoch 1, seq 0) and the
    // node is Stable; no node activates anything by itself — the initial Master's boot
    // switch (seq 1, NodeProtocol) does, through the ordinary two phases, so a node whose
    // process starts late joins that switch and a node excluded before it booted is fenced
    // by the Command. Restart (`restarted`): `view` is the persisted one and the node
    // waits to be commanded (it adopts even a Command for the switch it already holds).
    ConfigSwitch(const Topology& topology, NodeId self, const View& view, bool restarted,
                 Mutant mutant);

    // Mutant::boot_activates only (the behaviour before the boot switch): the Activate
    // actions of the initial configuration's tasks, at version 0, without any Command.
    void boot_activate_mutant(Outbox& out);

    // --- participant (every node) ---
    // Whether receive_command() would adopt this view (newer than the current one).
    bool would_adopt(const View& target) const;
    // ReceiveCommand: returns true when the command was new and adopted.
    bool receive_command(const Command& command, Epoch epoch, Outbox& out);
    // An Activate starts this node's new tasks only once every other node the view does
    // not exclude acked Prepared for the same view (fault model 3, rule 4; the view's digest
    // in the ack): until then it is held, and receive_prepared() starts them.
    void receive_activate(const ActivateCommand& activate, Epoch epoch, Outbox& out);
    // A Prepared ack from another node (acks go to every member, Ack in messages.hpp): for
    // this node's view, noted; for a newer view, kept as that node's word that it follows
    // it (vouched). A node past its Prepared answers a peer's Prepared with its own.
    void receive_prepared(const Ack& ack, Outbox& out);
    // Whether a node other than `sender` that `target` does not exclude acked Prepared for
    // exactly `target`: it followed that view, so its exclusions were backed where it
    // checked them (NodeProtocol::command_problem, rule 5).
    bool vouched(const View& target, NodeId sender) const;
    // The member whose Prepared vouches for `target` (the first by id), if any.
    std::optional<NodeId> voucher(const View& target, NodeId sender) const;
    // The newest Prepared this node holds from `node` names a switch of this node's view's
    // epoch newer than its view: `node` took a Command of this epoch's Master that never
    // reached this node (NodeProtocol::diverged_members).
    bool prepared_newer_switch(NodeId node) const;
    // This node goes by a view it did not merely load from its saved state (a restarted
    // node is not, until a Command reaches it; a first boot's initial view is), and it
    // holds `node`'s Prepared of that very view (its id and digest).
    bool commanded() const { return synced_; }
    bool prepared_this_view(NodeId node) const { return peers_prepared_.contains(node); }
    // The members of the view but this node that acked Prepared for it (same digest).
    const NodeSet& peers_prepared() const { return peers_prepared_; }
    // An Activate of this view is held for a member's Prepared.
    bool activation_held() const { return activate_held_; }
    // Activates held for members' Prepared, since boot (a count of rule 4 at work: an
    // honest switch holds one only when a Prepared arrives after the Master's Activate).
    std::uint64_t activations_held() const { return activations_held_; }
    void receive_checkpoint_ack(const CheckpointAck& ack, Outbox& out);
    void receive_checkpoint_reply(const CheckpointReply& reply, Epoch epoch, Outbox& out);
    // State without the Storage node (fault model 2, item 4): a CheckpointRequest reaching
    // a node that is not the Storage node asks for the state this node handed off, the
    // task's state when a switch moved it away while this node was a member of the view.
    // The reply says found only for such a hand-off; a node the cluster excluded drops all
    // its hand-offs (it may hold a lineage the cluster has since abandoned: it ran on, cut
    // off, past what the others restored), and while excluded it does not answer. A
    // hand-off made while the Storage node was excluded is flushed to it as soon as a view
    // includes it again, before this node acks Prepared.
    // Requests are answered within a RequestBudget (request_budget.hpp); `now`: receipt.
    void answer_checkpoint_request(const CheckpointRequest& request, TimeNs now, Outbox& out);
    // Requests refused (a node never placed on the task) and left unanswered (the budget).
    const RequestBudget& request_budget() const { return budget_; }
    // The state this node handed off for `task`, if any (see answer_checkpoint_request).
    std::optional<Version> handed_off_version(TaskId task) const {
        if (task >= topology_->task_count() || !handed_off_.contains(task)) return std::nullopt;
        return version_[task];
    }
    // Checkpointed tasks this node started, the Storage node excluded, without their
    // newest state: no member of the view held any, or the node the previous view placed
    // them on is excluded too (what it ran since its last hand-off is out of reach). A
    // loss no node could avoid, traced as StateOutOfReach. A task new to the view, or
    // started by the boot switch, starts from version 0 without being counted.
    std::uint64_t unrecoverable_starts() const { return unrecoverable_starts_; }
    // Checkpointed tasks this node started from the state another node handed off, the
    // Storage node being excluded.
    std::uint64_t holder_restores() const { return holder_restores_; }
    // Stored or handed-off states offered to this node with a step count above
    // kMaxAdoptedCount, which no correct run reaches: treated as lost (a restore starts
    // from no state in a lineage of the view; a holder's reply counts as holding nothing;
    // a resumption keeps this node's own state). An honest cluster never has one.
    std::uint64_t unadoptable_states() const { return unadoptable_states_; }
    // Execute(n, t) by the application: the task's state after one more step.
    void task_stepped(TaskId task, std::vector<std::uint8_t> state, Epoch epoch, Outbox& out);

    // --- driver (Master) ---
    void boot_as_master();
    // `joint`: the views some node may still go by (spec/Quorum.tla, rule 3a), carried in
    // every Command of this switch.
    void start_switch(const View& target, Outbox& out, std::vector<View> joint = {});
    // Ack(n, kind) arriving at the Master. Returns true when this ack completed the switch.
    bool receive_ack(const Ack& ack, Outbox& out);
    void step_down() { master_stage_ = MasterStage::Idle; driving_ = false; }

    // --- resign (NodeProtocol::resign, a Master stepping down) ---
    // Stops driving, deactivates every task this node runs and sends the final checkpoints
    // of the checkpointed ones to the Storage node (retransmitted by tick() until their
    // CheckpointAcks arrive: unflushed() empties). Nothing is activated afterwards until a
    // newer Command is adopted.
    void resign(Outbox& out);
    // The caller gave up waiting for the final checkpoints' acks (Storage unreachable).
    void abandon_flushes() { unflushed_ = TaskSet{}; }
    // The lease (spec/Lease.tla): while held, this node's tasks stay active in the switch
    // (the view still places them here, their versions and states are kept) but do not
    // run: hold() stops the running ones (Deactivate), activations meanwhile are not
    // started, and release() starts every active task again from its own last state and
    // version, a checkpointed one from the Storage node's version if that is newer (this
    // node may have been excluded while held and the task run elsewhere).
    void hold(Outbox& out);
    void release(Outbox& out);
    bool holding() const { return holding_; }
    // The ground's pause of one task (NodeProtocol::ground_pause): like the lease's hold,
    // for that task alone. While paused, the task stays what the switch places here (its
    // version and state kept, its Deactivate and Activate lines as ever, its final
    // checkpoint flushed when a switch moves it away) but does not run: pause() stops it
    // if it runs, an activation meanwhile is not started, and resume() starts it again as
    // release() does (a checkpointed one from the newer of its own state and the Storage
    // node's). Both return false when nothing changes (already paused, not paused).
    bool pause(TaskId task, Outbox& out);
    bool resume(TaskId task, Outbox& out);
    const TaskSet& paused() const { return paused_; }
    // A restarted node's pauses, as saved (before any Command is adopted).
    void restore_paused(TaskSet paused) { paused_ = paused; }
    // A restarted node's word on the state it read back from its disk (the `Restored`
    // line: its view and `saved`, its epoch): trace validation holds it to what this
    // node said before, as others logged it (spec/Durable.tla's SaidDurableInv: what was
    // said was saved first): the epoch of its Commands, the view of its Prepared.
    void trace_restored(Epoch saved, Outbox& out) const;
    // The node's Election role, for the `role` variable of trace lines only.
    void set_role(Role role) { role_ = role; }

    // Retransmissions (contract 5).
    void tick(Epoch epoch, Outbox& out);

    // State (spec variable names).
    const View& view() const { return view_; }  // epoch, seq, config
    // The joint views of the Command this node adopted last (spec/Quorum.tla, rule 3b).
    const std::vector<View>& joint() const { return joint_; }
    Stage stage() const { return stage_; }
    const TaskSet& active() const { return active_; }
    const TaskSet& unflushed() const { return unflushed_; }
    const TaskSet& restoring() const { return restoring_; }
    Version version(TaskId task) const { return version_[task]; }
    bool excluded() const { return view_.failed.contains(self_); }
    bool driving() const { return driving_; }
    MasterStage master_stage() const { return master_stage_; }
    const View& master_view() const { return master_view_; }
    const NodeSet& prepared() const { return prepared_; }
    const NodeSet& activated() const { return activated_; }
    std::string vars_json() const;

private:
    bool storage_available() const;
    void deactivate_leaving(Outbox& out);
    // Starts an active task again after a hold or a pause (release, resume).
    void restart(TaskId task, Outbox& out);
    // Deactivates `tasks` (all active here), sending the final checkpoints of those that
    // have one to the Storage node while it is available.
    void deactivate(TaskSet tasks, Outbox& out);
    void send_final(TaskId task, Epoch epoch, Outbox& out);
    void maybe_prepared(Outbox& out);
    bool resume_released(const CheckpointReply& reply, Outbox& out);
    void activate_arriving(Epoch epoch, Outbox& out);
    bool peers_complete() const;
    void start_activation(Epoch epoch, Outbox& out);
    void send_prepared(NodeSet to, bool reply, Outbox& out) const;
    // Without the Storage node: asks every other member of the view for the state it
    // handed off, and starts from the newest once all have answered (finish_gathering).
    void gather_from_holders(TaskId task, Epoch epoch, Outbox& out);
    void finish_gathering(TaskId task, Outbox& out);
    void activate(TaskId task, Version version, std::vector<std::uint8_t> state, bool restored,
                  Outbox& out, std::optional<std::uint64_t> opened = std::nullopt);
    void maybe_activated(Outbox& out);
    // A state offered with `version` may be taken (its count is at most kMaxAdoptedCount);
    // counts unadoptable_states otherwise.
    bool adoptable(const Version& version);
    void ack(AckKind kind, Outbox& out);
    void broadcast(const Message& message, NodeSet except, Outbox& out) const;
    void trace(const char* action, std::string args, Outbox& out) const;
    void trace_heard_prepared(const Ack& ack, Outbox& out) const;

    const Topology* topology_;
    NodeId self_;
    Mutant mutant_;
    RequestBudget budget_;
    View view_;
    std::vector<View> joint_;
    bool synced_;  // false after a restart until the first Command is adopted
    Stage stage_ = Stage::Stable;
    TaskSet active_;
    TaskSet unflushed_;
    TaskSet restoring_;
    // Per task of the mission (Topology::task_count entries), here and below.
    std::vector<Version> version_;
    std::vector<std::vector<std::uint8_t>> state_;
    // Tasks whose state this node handed off (a switch moved them away while it was a
    // member), and, while restoring without the Storage node, whom it still waits for and
    // the newest state heard so far.
    TaskSet handed_off_;
    TaskSet unstored_;  // hand-offs made while the Storage node was excluded, not yet stored
    TaskSet placed_before_;  // tasks the view replaced by the one under way had placed
    TaskSet host_lost_;      // ...on a node the view under way excludes
    TaskSet gathering_;
    std::vector<NodeSet> holders_pending_;
    std::vector<bool> gathered_found_;
    std::vector<Version> gathered_version_;
    std::vector<std::vector<std::uint8_t>> gathered_state_;
    std::uint64_t unrecoverable_starts_ = 0;
    std::uint64_t holder_restores_ = 0;
    std::uint64_t unadoptable_states_ = 0;

    Role role_ = Role::Worker;
    bool driving_ = false;
    bool holding_ = false;
    TaskSet paused_;     // paused by the ground (pause())
    TaskSet releasing_;  // released, waiting for the Storage node's checkpoint to resume
    MasterStage master_stage_ = MasterStage::Idle;
    View master_view_;
    std::vector<View> master_joint_;
    NodeSet prepared_;
    NodeSet activated_;

    // Rule 4 (participant): the members that acked Prepared for view_, an Activate held
    // for the rest (and the epoch it arrived in), and each node's latest Prepared for a
    // view newer than this node's (<<epoch, seq>> and digest), its word that it follows it.
    struct PeerPrepared {
        Epoch epoch = 0;
        Seq seq = 0;
        std::uint64_t digest = 0;
    };
    NodeSet peers_prepared_;
    bool activate_held_ = false;
    Epoch held_epoch_ = 0;
    std::uint64_t activations_held_ = 0;
    std::vector<PeerPrepared> newer_prepared_;
};

}  // namespace keel::fsm
