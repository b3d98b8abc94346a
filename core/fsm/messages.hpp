// The protocol messages of Keel's state machines, as plain structs.
//
// These are the payloads the network layer carries (core/net's Envelope gives them an
// address, a port and a transmission type; core/fsm/codec.hpp turns them into bytes).
// Every message names its sender. Messages that belong to a configuration carry the
// sender's epoch so that a receiver can reject stale ones in one place
// (NodeProtocol::step); `has_epoch` says which ones.
//
// | message            | paper's transmission type | spec action it feeds          |
// |--------------------|---------------------------|-------------------------------|
// | Heartbeat          | heartbeat                 | ReceiveHeartbeat              |
// | Command            | reconfiguration command   | ReceiveCommand (and election) |
// | ActivateCommand    | reconfiguration command   | ReceiveActivate               |
// | Ack                | acknowledgement           | Ack -> BroadcastActivate, CompleteSwitch |
// | ErrorNotification  | error notification        | Exclude at the Master         |
// | CheckpointWrite    | reliable data             | FlushCheckpoint               |
// | CheckpointAck      | acknowledgement           | (flush done)                  |
// | CheckpointRequest  | request                   | Activate (restore)            |
// | CheckpointReply    | response                  | Activate (restore)            |
// | PhaseRequest       | reconfiguration command   | RequestPhase                  |
//
// The election has no message of its own: a node that wins (BecomeMaster) announces its
// epoch with the Command of the switch it starts, as in the MasterElection spec.
#pragma once

#include <cstdint>
#include <string_view>
#include <variant>
#include <utility>
#include <vector>

#include "core/fsm/types.hpp"

namespace keel::fsm {

// One node's heartbeat, as a monitor last heard it: `incarnation` and `seq` are the node's.
struct HeartbeatAck {
    NodeId node = kNoNode;
    std::uint32_t incarnation = 0;
    std::uint32_t seq = 0;
    friend bool operator==(const HeartbeatAck&, const HeartbeatAck&) = default;
};

// Every node sends one per heartbeat period to every processing node (the possible
// monitors); a monitor sends its own to every node. `incarnation` counts the node's boots:
// a monitor that sees it grow knows the node restarted and lost its volatile state, which
// is a failure. `boot` is a number the node draws at random at each boot: a monitor that
// hears a new one knows the node restarted even when its saved incarnation went back (a
// lost write, a restored file, --cold-start in a live cluster), and one that hears a boot
// it saw end knows the heartbeat is stale; `previous_boot` (the boot before this one, from
// the saved state; 0 for none) is retired at once, so that a monitor that never heard it
// does not take a late heartbeat of it for a newer boot. `waiting` says the sender booted from its saved
// state and no Command has reached it since: a monitor that first hears it so knows it
// restarted even if its incarnation looks like a first boot's (its state file went back,
// and the monitor never heard its earlier boots). `seq` numbers the node's heartbeats
// within the incarnation (1, 2, ...). `image` is the first 64 bits of the SHA-256 of the
// mission image the sender flies (0: not known): a node on another image reads
// configuration, task and node ids by another mission, and takes no part.
// `excluded` says the sender knows the cluster has excluded it: monitors count it failed
// at once. `epoch` is the highest epoch the sender has seen, which tells a Master that a
// newer one exists. `acks` (monitors only, fault model 2's lease, spec/Lease.tla): for
// every node the sender watches and has not declared, the last heartbeat it heard from it.
// A monitor also answers each heartbeat of a node it watches at once, with a `reply`
// carrying that node's acknowledgement alone (a reply is never answered), so that a
// node's lease is renewed within a round trip rather than a period.
struct Heartbeat {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    std::uint32_t incarnation = 0;
    bool excluded = false;
    std::uint32_t seq = 0;
    std::vector<HeartbeatAck> acks;
    bool reply = false;
    std::uint32_t boot = 0;
    bool waiting = false;
    std::uint32_t previous_boot = 0;
    std::uint64_t image = 0;
    // The ground's vote for the sender (spec/Designate.tla, rule 3), as milliseconds left
    // of it when it sent this heartbeat (0: it holds none). A node whose Master says so
    // counts the vote for its Master (rule 4: in the view the vote's take-over left joint)
    // until that many milliseconds after the send of its own heartbeat the Master
    // acknowledges here: a bound the Master's own end of the vote never precedes.
    std::uint32_t vote_left_ms = 0;
    friend bool operator==(const Heartbeat&, const Heartbeat&) = default;
};

// The Master's reconfiguration command: switch `view.seq` of `view.epoch` to the view's
// configuration. Also what a new Master announces its epoch with.
struct Command {
    Command() = default;
    Command(NodeId sender, View adopted, std::vector<View> pending = {})
        : from(sender), view(adopted), joint(std::move(pending)) {}
    NodeId from = kNoNode;
    View view;
    // Joint views (spec/Quorum.tla, rule 3a): the views pending at the Master when it made
    // `view`, by which some node may still go. At most kMaxJointViews.
    std::vector<View> joint;
    // A hand-over (`view.master` is not `from`): the boot of its receiver that the sender
    // heard (Heartbeat::boot). The receiver takes the view only in that boot: a hand-over
    // meant for a boot that ended (the node restarted within the hand-over's repeats) would
    // make it Master of an epoch the others may have taken over meanwhile. 0 otherwise.
    std::uint32_t boot = 0;
    friend bool operator==(const Command&, const Command&) = default;
};

// Second phase of a switch: every live node is prepared, activate the new tasks.
struct ActivateCommand {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    Seq seq = 0;
    friend bool operator==(const ActivateCommand&, const ActivateCommand&) = default;
};

enum class AckKind : std::uint8_t { Prepared = 1, Activated = 2 };
const char* to_string(AckKind kind);

// A node's ack of a switch's phase. "Activated" goes to the Master. "Prepared" goes to
// every node the view does not exclude (fault model 3, rule 4): a node starts its new tasks
// only once every other such node has said it is prepared for the same view, so a Master
// that activates early, or sends two nodes different views under one switch id, starts
// nothing anywhere. `view` is the view_digest of the view prepared (0 for Activated);
// `reply` marks a node's answer to a peer's Prepared that it already passed (a reply is
// never answered).
struct Ack {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    Seq seq = 0;
    AckKind kind = AckKind::Prepared;
    std::uint64_t view = 0;
    bool reply = false;
    friend bool operator==(const Ack&, const Ack&) = default;
};

// A monitor declared `failed_node` failed (or a node asks for its own exclusion,
// `failed_node == from`). Sent to the Master, which decides on exclusions, and to every
// other node, so that each can check that an exclusion a Command adds is backed by a
// declaration of a node other than the Command's sender (fault model 3, rule 5).
struct ErrorNotification {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    NodeId failed_node = kNoNode;
    friend bool operator==(const ErrorNotification&, const ErrorNotification&) = default;
};

// A task's state after `version` steps, sent to the Storage node. `final` marks the flush
// after deactivation, which the Storage node acknowledges.
struct CheckpointWrite {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    TaskId task = 0;
    Version version;
    bool final = false;
    std::vector<std::uint8_t> state;
    friend bool operator==(const CheckpointWrite&, const CheckpointWrite&) = default;
};

struct CheckpointAck {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    TaskId task = 0;
    Version version;  // the version the Storage node now holds for the task
    friend bool operator==(const CheckpointAck&, const CheckpointAck&) = default;
};

// Asks for the latest checkpoint of `task` for switch <<epoch, seq>>; the reply echoes
// both so a late reply to an older request can never be mistaken for a current one.
struct CheckpointRequest {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    Seq seq = 0;
    TaskId task = 0;
    friend bool operator==(const CheckpointRequest&, const CheckpointRequest&) = default;
};

// The latest checkpoint of a task; `found` is false when none was ever written.
struct CheckpointReply {
    NodeId from = kNoNode;
    Epoch epoch = 0;
    Seq seq = 0;
    TaskId task = 0;
    bool found = false;
    Version version;
    std::vector<std::uint8_t> state;
    friend bool operator==(const CheckpointReply&, const CheckpointReply&) = default;
};

// A planned reconfiguration: the mission enters `phase`. It comes from the Master's own
// timeline or from the ground, whose commands each node checks itself (the operator's
// signature, core/node/ground.hpp) and hands to its own NodeProtocol (`from` kNoNode): no
// node sends one, and one from the wire is unauthorized. Carries no epoch.
struct PhaseRequest {
    NodeId from = kNoNode;
    PhaseId phase = 0;
    friend bool operator==(const PhaseRequest&, const PhaseRequest&) = default;
};

using Message = std::variant<Heartbeat, Command, ActivateCommand, Ack, ErrorNotification,
                             CheckpointWrite, CheckpointAck, CheckpointRequest, CheckpointReply,
                             PhaseRequest>;

// The message's kind as a stable name ("Heartbeat", "Command", ...).
std::string_view kind_name(const Message& message);
// The name of the Message alternative at `index` ("unknown" beyond them).
std::string_view kind_name(std::size_t index);
NodeId sender_of(const Message& message);
// Whether the message belongs to an epoch (and so may be stale), and that epoch.
bool has_epoch(const Message& message);
Epoch epoch_of(const Message& message);

}  // namespace keel::fsm
