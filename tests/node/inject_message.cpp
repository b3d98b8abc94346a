#include "inject_message.hpp"

#include <limits>
#include <set>

#include "core/fsm/admission.hpp"

namespace keel::inject {

namespace {

using nlohmann::json;

// The fields one kind may name, so that a misspelt field is an error, not a silent 0.
void check_fields(const json& spec, const std::string& where, const std::set<std::string>& allowed) {
    if (!spec.is_object()) throw MessageError(where + ": expected a JSON object");
    for (const auto& [key, value] : spec.items()) {
        if (!allowed.contains(key)) {
            std::string known;
            for (const std::string& name : allowed) known += (known.empty() ? "" : ", ") + name;
            throw MessageError(where + ": unknown field '" + key + "' (known: " + known + ")");
        }
    }
}

template <typename T>
T number(const json& spec, const char* field, const std::string& where) {
    if (!spec.contains(field)) return T{};
    const json& value = spec.at(field);
    if (!value.is_number_unsigned() && !(value.is_number_integer() && value.get<std::int64_t>() >= 0)) {
        throw MessageError(where + "." + field + ": expected a non-negative integer, got " + value.dump());
    }
    const auto raw = value.get<std::uint64_t>();
    if (raw > std::numeric_limits<T>::max()) {
        throw MessageError(where + "." + field + ": " + std::to_string(raw) + " does not fit (at most " +
                           std::to_string(std::numeric_limits<T>::max()) + ")");
    }
    return static_cast<T>(raw);
}

bool flag(const json& spec, const char* field, const std::string& where) {
    if (!spec.contains(field)) return false;
    if (!spec.at(field).is_boolean()) throw MessageError(where + "." + field + ": expected true or false");
    return spec.at(field).get<bool>();
}

fsm::NodeSet node_set(const json& spec, const char* field, const std::string& where) {
    fsm::NodeSet set;
    if (!spec.contains(field)) return set;
    if (!spec.at(field).is_array()) throw MessageError(where + "." + field + ": expected an array of node ids");
    for (const json& id : spec.at(field)) {
        if (!id.is_number_unsigned() || id.get<std::uint64_t>() >= fsm::kMaxNodes) {
            throw MessageError(where + "." + field + ": " + id.dump() + " is no node id below " +
                               std::to_string(fsm::kMaxNodes) + " (a set holds no larger one)");
        }
        set.insert(static_cast<fsm::NodeId>(id.get<std::uint64_t>()));
    }
    return set;
}

fsm::View view(const json& spec, const std::string& where) {
    check_fields(spec, where, {"epoch", "seq", "config", "base", "master", "failed"});
    fsm::View value;
    value.epoch = number<fsm::Epoch>(spec, "epoch", where);
    value.seq = number<fsm::Seq>(spec, "seq", where);
    value.config = number<fsm::ConfigId>(spec, "config", where);
    value.base = spec.contains("base") ? number<fsm::ConfigId>(spec, "base", where) : value.config;
    value.master = number<fsm::NodeId>(spec, "master", where);
    value.failed = node_set(spec, "failed", where);
    return value;
}

fsm::Version version(const json& spec, const std::string& where) {
    return {number<std::uint64_t>(spec, "lineage", where), number<std::uint64_t>(spec, "version", where)};
}

std::vector<std::uint8_t> state(const json& spec, const std::string& where) {
    return std::vector<std::uint8_t>(number<std::uint32_t>(spec, "state_bytes", where), 0x5A);
}

}  // namespace

fsm::Message message_from_json(const json& spec, fsm::NodeId default_from) {
    if (!spec.is_object() || !spec.contains("kind") || !spec.at("kind").is_string()) {
        throw MessageError("a message is a JSON object with a \"kind\" (Command, Heartbeat, ...)");
    }
    const std::string kind = spec.at("kind").get<std::string>();
    const std::string where = kind;
    const fsm::NodeId from = spec.contains("from") ? number<fsm::NodeId>(spec, "from", where) : default_from;
    if (kind == "Command") {
        check_fields(spec, where, {"kind", "from", "view", "joint", "boot"});
        fsm::Command command;
        command.from = from;
        command.view = view(spec.value("view", json::object()), where + ".view");
        command.boot = number<std::uint32_t>(spec, "boot", where);
        if (spec.contains("joint")) {
            if (!spec.at("joint").is_array()) throw MessageError(where + ".joint: expected an array of views");
            for (const json& joint : spec.at("joint")) command.joint.push_back(view(joint, where + ".joint"));
        }
        return command;
    }
    if (kind == "Heartbeat") {
        check_fields(spec, where, {"kind", "from", "epoch", "incarnation", "excluded", "seq", "acks", "reply",
                                   "boot", "previous_boot", "waiting", "image"});
        fsm::Heartbeat heartbeat;
        heartbeat.from = from;
        heartbeat.epoch = number<fsm::Epoch>(spec, "epoch", where);
        heartbeat.incarnation = number<std::uint32_t>(spec, "incarnation", where);
        heartbeat.excluded = flag(spec, "excluded", where);
        heartbeat.seq = number<std::uint32_t>(spec, "seq", where);
        heartbeat.reply = flag(spec, "reply", where);
        heartbeat.boot = number<std::uint32_t>(spec, "boot", where);
        heartbeat.previous_boot = number<std::uint32_t>(spec, "previous_boot", where);
        heartbeat.waiting = flag(spec, "waiting", where);
        heartbeat.image = number<std::uint64_t>(spec, "image", where);
        for (const json& ack : spec.value("acks", json::array())) {
            check_fields(ack, where + ".acks", {"node", "incarnation", "seq"});
            heartbeat.acks.push_back({number<fsm::NodeId>(ack, "node", where + ".acks"),
                                      number<std::uint32_t>(ack, "incarnation", where + ".acks"),
                                      number<std::uint32_t>(ack, "seq", where + ".acks")});
        }
        return heartbeat;
    }
    if (kind == "Activate") {
        check_fields(spec, where, {"kind", "from", "epoch", "seq"});
        return fsm::ActivateCommand{from, number<fsm::Epoch>(spec, "epoch", where), number<fsm::Seq>(spec, "seq", where)};
    }
    if (kind == "Ack") {
        check_fields(spec, where, {"kind", "from", "epoch", "seq", "ack", "view", "reply"});
        const std::string ack = spec.value("ack", std::string("Prepared"));
        if (ack != "Prepared" && ack != "Activated") throw MessageError(where + ".ack: Prepared or Activated, not " + ack);
        // The view prepared: its digest, or the view itself (the digest is computed here).
        std::uint64_t digest = 0;
        if (spec.contains("view") && spec.at("view").is_object()) {
            digest = fsm::view_digest(view(spec.at("view"), where + ".view"));
        } else if (spec.contains("view")) {
            digest = number<std::uint64_t>(spec, "view", where);
        }
        return fsm::Ack{from, number<fsm::Epoch>(spec, "epoch", where), number<fsm::Seq>(spec, "seq", where),
                        ack == "Prepared" ? fsm::AckKind::Prepared : fsm::AckKind::Activated, digest,
                        flag(spec, "reply", where)};
    }
    if (kind == "ErrorNotification") {
        check_fields(spec, where, {"kind", "from", "epoch", "failed_node"});
        return fsm::ErrorNotification{from, number<fsm::Epoch>(spec, "epoch", where),
                                      number<fsm::NodeId>(spec, "failed_node", where)};
    }
    if (kind == "CheckpointWrite") {
        check_fields(spec, where, {"kind", "from", "epoch", "task", "lineage", "version", "final", "state_bytes"});
        return fsm::CheckpointWrite{from, number<fsm::Epoch>(spec, "epoch", where), number<fsm::TaskId>(spec, "task", where),
                                    version(spec, where), flag(spec, "final", where), state(spec, where)};
    }
    if (kind == "CheckpointAck") {
        check_fields(spec, where, {"kind", "from", "epoch", "task", "lineage", "version"});
        return fsm::CheckpointAck{from, number<fsm::Epoch>(spec, "epoch", where), number<fsm::TaskId>(spec, "task", where),
                                  version(spec, where)};
    }
    if (kind == "CheckpointRequest") {
        check_fields(spec, where, {"kind", "from", "epoch", "seq", "task"});
        return fsm::CheckpointRequest{from, number<fsm::Epoch>(spec, "epoch", where), number<fsm::Seq>(spec, "seq", where),
                                      number<fsm::TaskId>(spec, "task", where)};
    }
    if (kind == "CheckpointReply") {
        check_fields(spec, where, {"kind", "from", "epoch", "seq", "task", "found", "lineage", "version", "state_bytes"});
        return fsm::CheckpointReply{from,
                                    number<fsm::Epoch>(spec, "epoch", where),
                                    number<fsm::Seq>(spec, "seq", where),
                                    number<fsm::TaskId>(spec, "task", where),
                                    flag(spec, "found", where),
                                    version(spec, where),
                                    state(spec, where)};
    }
    if (kind == "PhaseRequest") {
        // "epoch": the envelope's (the message carries none), as an honest node stamps its own.
        check_fields(spec, where, {"kind", "from", "phase", "epoch"});
        return fsm::PhaseRequest{from, number<fsm::PhaseId>(spec, "phase", where)};
    }
    throw MessageError("unknown message kind '" + kind +
                       "' (Heartbeat, Command, Activate, Ack, ErrorNotification, CheckpointWrite, "
                       "CheckpointAck, CheckpointRequest, CheckpointReply, PhaseRequest)");
}

}  // namespace keel::inject
