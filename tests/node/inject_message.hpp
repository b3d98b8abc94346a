// keel-node-inject's --message: any protocol message, with any field values, from JSON
// (fault model 3's tool: a value-faulty node says something wrong under its own name).
//
//   {"kind": "Command", "view": {"epoch": 3, "seq": 1, "config": 999, "base": 999,
//                                "master": 2, "failed": [0, 1]}, "joint": [ ...views ]}
//   {"kind": "Heartbeat", "epoch": 1, "incarnation": 1, "excluded": false, "seq": 9,
//    "acks": [{"node": 0, "incarnation": 1, "seq": 8}], "reply": false}
//   {"kind": "Activate", "epoch": 1, "seq": 2}
//   {"kind": "Ack", "epoch": 1, "seq": 2, "ack": "Prepared"}          ("Activated")
//   {"kind": "ErrorNotification", "epoch": 1, "failed_node": 0}
//   {"kind": "CheckpointWrite", "epoch": 1, "task": 1, "lineage": 0, "version": 7,
//    "final": true, "state_bytes": 24}
//   {"kind": "CheckpointAck", "epoch": 1, "task": 1, "lineage": 0, "version": 7}
//   {"kind": "CheckpointRequest", "epoch": 1, "seq": 2, "task": 1}
//   {"kind": "CheckpointReply", "epoch": 1, "seq": 2, "task": 1, "found": true,
//    "lineage": 0, "version": 7, "state_bytes": 24}
//   {"kind": "PhaseRequest", "phase": 1}
//
// Every field but "kind" may be left out (0, false, empty); "from" defaults to the
// injector's own address; ids are the mission's indexes (nodes in file order, configurations
// in file order over every phase; 65535 is safe mode, 65534 no configuration). Values are
// taken as given, beyond the codec's widths too: the point is to send what an honest node
// never does. A JSON value of the wrong type, an unknown kind or field, or a number that does
// not fit its field's type is an error naming the field.
#pragma once

#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "core/fsm/messages.hpp"

namespace keel::inject {

class MessageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Throws MessageError naming what is wrong.
fsm::Message message_from_json(const nlohmann::json& spec, fsm::NodeId default_from);

}  // namespace keel::inject
