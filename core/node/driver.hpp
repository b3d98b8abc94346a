// NodeDriver: the one place where a node's state machines' actions become effects, for
// keel-node and keel-sim alike (sans-IO: the host does the IO).
//
// NodeProtocol (core/fsm) decides; after each of its calls the driver takes its ready
// actions and carries them out in order through a DriverHost: send a message, activate or
// deactivate a task, write a trace line, store a checkpoint. Between the protocol and those
// effects the driver enforces the runtime's ordering rules (docs/fault-model.md, "Durable
// state"), which no state machine can see:
//
//  1. The node's state is durable before anything that depends on it leaves. Before the
//     actions of a call are carried out the host saves the node's state (epoch, view,
//     incarnation, boot; DriverHost::save_state); when it cannot, the call's messages are
//     dropped (a loss, which the protocol survives) and the node leaves (rule 3).
//  2. Nothing the Storage node says about a task runs ahead of its disk. A checkpoint the
//     protocol stores (act::StoreCheckpoint) is handed to the host's disk, which reports
//     the write later (checkpoint_written, checkpoint_failed); until then the task's
//     acknowledgements, restore replies and StoreCheckpoint trace line wait
//     (HeldUntilStored). A write that fails releases nothing that waited for it.
//  3. A disk failure is fail-stop. The node resigns (its resignation changes neither epoch
//     nor view, so it stands for nothing unsaved), sends nothing after it, and the host
//     stops (keel-node exits 5; keel-sim crashes the node).
//
// keel-node's host is NodeRuntime (runtime.cpp: DDS, the executor, SQLite and the
// persister's thread); keel-sim's is Simulation (nodes/sim/src/simulation.cpp: its
// network, fake tasks and simulated disk), so the simulator's checkers judge these rules
// too. The mutants release_held_early, save_after_send and ignore_failed_write
// (core/fsm/mutants.hpp; keel_node_driver_mutants only) each break one of them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/fsm/actions.hpp"
#include "core/fsm/mutants.hpp"
#include "core/fsm/node_protocol.hpp"
#include "core/node/held_until_stored.hpp"

namespace keel::node {

// What a node's effects go through. Every call comes from the thread that drives.
class DriverHost {
public:
    virtual ~DriverHost() = default;
    // A protocol message for node `to`; NodeDriver::kBroadcast: the heartbeat every node
    // that watches this one receives (DriverOptions::coalesce_heartbeats).
    virtual void send(fsm::NodeId to, const fsm::Message& message) = 0;
    // The same message to each of `to` (DriverOptions::one_send_per_command); by default one
    // send() each.
    virtual void send_to_each(const std::vector<fsm::NodeId>& to, const fsm::Message& message) {
        for (const fsm::NodeId node : to) send(node, message);
    }
    virtual void activate(const fsm::act::Activate& action) = 0;
    virtual void deactivate(fsm::TaskId task) = 0;
    virtual void write_trace(const fsm::act::Trace& line) = 0;
    // Saves the node's state when it changed since the last save, durably before it
    // returns; false when it could not be saved.
    virtual bool save_state() = 0;
    // Queues the Storage node's checkpoint for a durable write and returns its ticket (1,
    // 2, ...: the order of the calls; per task, writes finish in that order, a waiting one
    // replaced by a newer one). The host reports the write to checkpoint_written or
    // checkpoint_failed. Nothing: the node stores no checkpoint (not the Storage node, or
    // no disk).
    virtual std::optional<std::uint64_t> store_checkpoint(fsm::act::StoreCheckpoint& store) = 0;
    // The disk failed (`what`): the node has resigned and sends nothing more; the host
    // stops it.
    virtual void disk_failed(std::string_view what) = 0;
    // Notices, for the host's log.
    virtual void declared_failed(const fsm::act::DeclareFailed&) {}
    virtual void entered_safe_mode() {}
    // An action as the protocol emitted it, before the driver carries it out (keel-sim's
    // checkers read the step's actions).
    virtual void observe(const fsm::Action&) {}
};

// What the driver needs of the state machines: their ready actions, and the resignation a
// disk failure calls for. NodeProtocol is one (NodeDriver's first constructor); unit tests
// script their own.
class ActionSource {
public:
    virtual ~ActionSource() = default;
    virtual void take_ready(std::vector<fsm::Action>& into) = 0;
    virtual void resign(fsm::TimeNs now) = 0;
};

struct DriverOptions {
    // A heartbeat goes to every monitor with the same content: send it once, to kBroadcast
    // (keel-node: the heartbeat topic keeps the latest sample per sender). Off: one send
    // per monitor (keel-sim's network).
    bool coalesce_heartbeats = false;
    // Test builds only (keel_node_driver_mutants): one of the driver's mutants.
    fsm::Mutant mutant = fsm::Mutant::none;
    // A step's trace lines are written before its messages leave (keel-node: a node killed
    // between a send and its line would leave a trace that lacks what others received, and
    // trace validation would reject an honest run). The messages go after the step's other
    // effects, in their order: as if the network took a microsecond longer. Off: in the
    // protocol's order (keel-sim, whose seeded runs depend on it).
    bool lines_before_sends = false;
    // With lines_before_sends: a step's same Command (or Activate) to several nodes, one
    // after the other (a switch's broadcast), goes to the host as one send_to_each
    // (keel-node: one DDS sample for all of them, not one per member that every member
    // reads). What each node receives is unchanged.
    bool one_send_per_command = false;
};

struct DriverCounters {
    std::uint64_t state_save_errors = 0;
    std::uint64_t checkpoint_write_errors = 0;
    // Checkpoint acknowledgements, restore replies and trace lines dropped because the
    // write they stood for failed, or came after the disk failed.
    std::uint64_t dropped_for_disk = 0;
};

class NodeDriver {
public:
    static constexpr fsm::NodeId kBroadcast = 0xFFFF;

    NodeDriver(fsm::NodeProtocol& protocol, DriverHost& host, DriverOptions options = {});
    NodeDriver(ActionSource& source, DriverHost& host, DriverOptions options = {});
    NodeDriver(const NodeDriver&) = delete;
    NodeDriver& operator=(const NodeDriver&) = delete;

    // Carries out the protocol's ready actions, in order (after every protocol call).
    void drive(fsm::TimeNs now);
    // Saves the node's state now (a ground command's seq, before the command acts); false
    // when it could not: the node then leaves (rule 3).
    bool save_state(fsm::TimeNs now);
    // The host's disk wrote `ticket` of `task` (store_checkpoint): what waited for it goes.
    void checkpoint_written(fsm::TaskId task, std::uint64_t ticket);
    // It could not: what waited for it is dropped, and the node leaves (rule 3).
    void checkpoint_failed(fsm::TaskId task, std::uint64_t ticket, fsm::TimeNs now);

    // The disk failed: the node resigned and sends nothing more (the host stops it).
    bool stopped() const { return stopped_; }
    bool state_failed() const { return state_failed_; }
    bool storage_failed() const { return storage_failed_; }
    const DriverCounters& counters() const { return counters_; }
    // Messages and trace lines waiting for a checkpoint write.
    std::size_t held() const { return held_.held(); }

private:
    void carry_out(std::vector<fsm::Action>& actions);
    // The step's messages in order; a run of the same Command to several nodes as one
    // send_to_each (DriverOptions::one_send_per_command).
    void send_in_order(std::vector<fsm::act::Send>& sends);
    void release(fsm::Action& action);
    void leave(std::string_view what, fsm::TimeNs now);
    bool mutant(fsm::Mutant which) const { return fsm::mutant_on(options_.mutant, which); }

    class ProtocolSource final : public ActionSource {
    public:
        explicit ProtocolSource(fsm::NodeProtocol& protocol) : protocol_(&protocol) {}
        void take_ready(std::vector<fsm::Action>& into) override { protocol_->take_ready(into); }
        void resign(fsm::TimeNs now) override { protocol_->resign(now); }

    private:
        fsm::NodeProtocol* protocol_;
    };
    std::optional<ProtocolSource> adapter_;
    ActionSource* protocol_;
    DriverHost* host_;
    DriverOptions options_;
    DriverCounters counters_;
    HeldUntilStored<fsm::Action> held_;
    std::vector<fsm::Action> actions_;
    bool state_failed_ = false;
    bool storage_failed_ = false;
    bool stopped_ = false;
    bool sends_closed_ = false;
};

}  // namespace keel::node
