// What a node's state machines ask their caller to do: the output half of the
// step/tick contract (node_protocol.hpp).
//
// | action           | the caller must                                                |
// |------------------|----------------------------------------------------------------|
// | Send             | send `message` to node `to` (encode with codec.hpp)            |
// | Activate         | start `task` from `state` (its checkpoint, or its own state    |
// |                  | when `resumed` after a lease hold), at `version`               |
// | Deactivate       | stop `task`; no further TaskStepped events for it              |
// | StoreCheckpoint  | (Storage node) persist the checkpoint before or after replying; |
// |                  | the state machine has already made it the latest one           |
// | DeclareFailed    | nothing required: `node` was declared failed by this node      |
// | EnterSafeMode    | nothing required: this node, as Master, entered safe mode      |
// | Trace            | append the event to the node's trace (optional)                |
//
// Sends to the node itself never appear: NodeProtocol delivers them internally, in order,
// before it returns.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "core/fsm/messages.hpp"

namespace keel::fsm::act {

struct Send {
    NodeId to = kNoNode;
    Message message;
};

struct Activate {
    TaskId task = 0;
    Version version;
    std::vector<std::uint8_t> state;
    // True when the state was read from the Storage node; false for a task without
    // checkpoints, a checkpointed task that never wrote one, or no storage node alive.
    bool restored = false;
    // True when the task continues on this node from its own last state after its lease
    // was held (ConfigSwitch::release): no other node ran it meanwhile, and its version is
    // at least the stored one (checkpoints in flight may not have landed).
    bool resumed = false;
    // The state the task starts from: `version` but for the lineage, which a start without
    // the Storage node opens anew (types.hpp, Version). Equal to `version` otherwise.
    Version from;
};

struct Deactivate {
    TaskId task = 0;
};

struct StoreCheckpoint {
    TaskId task = 0;
    Version version;
    std::vector<std::uint8_t> state;
    // The host's write replaces a foreign writer's newer version (CheckpointStore,
    // overridden): kept on disk too, though its version is lower.
    bool replaces = false;
};

// Why a monitor declared a node failed.
enum class FailureReason : std::uint8_t {
    missed,     // miss_limit heartbeat periods in a row without a heartbeat
    restarted,  // its heartbeat shows a new incarnation: it lost its volatile state
    excluded,   // its heartbeat says the cluster has already excluded it
    wrong,      // it sent what no honest node sends (fault model 3: a refused Command)
    left,       // the view's Master: its heartbeats say it follows a newer epoch (it left
                // the view), and no Command of one reached this node (NodeProtocol)
};

struct DeclareFailed {
    NodeId node = kNoNode;
    FailureReason reason = FailureReason::missed;
};

struct EnterSafeMode {};

// One state-machine action for the NDJSON trace (docs/verification.md, spec/NAMES.md): `fsm` is
// "heartbeat", "election" or "switch"; `action` the spec's action name; `vars` a JSON
// object with the node's entries of the spec variables; `args` the action's parameters.
struct Trace {
    const char* fsm = "";
    const char* action = "";
    std::string args;  // JSON object
    std::string vars;  // JSON object
};

}  // namespace keel::fsm::act

namespace keel::fsm {

using Action = std::variant<act::Send, act::Activate, act::Deactivate, act::StoreCheckpoint,
                            act::DeclareFailed, act::EnterSafeMode, act::Trace>;

// Where the state machines put their actions during one step or tick.
class Outbox {
public:
    explicit Outbox(bool tracing) : tracing_(tracing) {}

    bool tracing() const { return tracing_; }
    // Defined in actions.cpp, not inlined: GCC 12, inlining the variant's move into the
    // loops of IdSet::for_each that call these, reports members of the other alternatives
    // as maybe uninitialized (a false positive, an error under KEEL_WERROR). One call per
    // action costs nothing.
    void send(NodeId to, Message message);
    void push(Action action);
    void trace(const char* fsm, const char* action, std::string args, std::string vars) {
        if (tracing_) actions_.push_back(act::Trace{fsm, action, std::move(args), std::move(vars)});
    }
    std::vector<Action>& actions() { return actions_; }
    const std::vector<Action>& actions() const { return actions_; }

private:
    bool tracing_;
    std::vector<Action> actions_;
};

}  // namespace keel::fsm
