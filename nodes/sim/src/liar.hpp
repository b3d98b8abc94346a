// A value-faulty node (fault model 3, docs/fault-model.md): a single-event upset flipped
// something in the node's memory and it goes on sending well-formed messages with wrong
// values, under its own identity. While it lies, the simulated node still runs its honest
// NodeProtocol, but what it sends is changed on the way out: some of its honest messages
// carry one to three wrong fields, some are not sent, and at each of its period boundaries
// it may forge more, of any kind (a Worker's Command, a processing node's CheckpointAck, a
// restore reply for any task), to one node or to all. Values are drawn near the liar's own
// (its epoch, its switch, its tasks' versions: the values that pass the most checks) and
// sometimes anywhere the wire admits; ids may be one beyond the mission's. Every lie goes
// through the codec as on the wire: what it refuses (a value beyond a field's width) is
// never delivered, and the receiver's NodeProtocol bounds the rest (admission.hpp). The
// sender is always the liar: DDS Security binds every message to its writer's node.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "core/fsm/node_protocol.hpp"
#include "nodes/sim/src/rng.hpp"

namespace keel::sim {

class Liar {
public:
    Liar(const fsm::Topology& topology, fsm::NodeId node, std::uint64_t seed);

    fsm::NodeId node() const { return node_; }
    // The liar's honest message, as it leaves: nothing (not sent), the message itself, or
    // the message with wrong values. `at` is the liar's protocol.
    std::optional<fsm::Message> outgoing(const fsm::Message& honest, const fsm::NodeProtocol& at,
                                         fsm::TimeNs now);
    // A message of any kind to forge at a period boundary, or none; `to_all` says whether
    // it goes to every node (else to `*to`).
    struct Forged {
        fsm::Message message;
        bool to_all = false;
        fsm::NodeId to = fsm::kNoNode;
    };
    // Some are coherent: a switch the graph places, from the liar's own view, that
    // excludes a live node on the liar's word alone (as its Master, or taking over under
    // its own name), sent to some nodes or all, with its Activate at once: what rules 4
    // and 5 exist for (docs/fault-model.md).
    std::vector<Forged> forge(const fsm::NodeProtocol& at, fsm::TimeNs now);


private:
    fsm::Message lie_about(fsm::Message message, const fsm::NodeProtocol& at, fsm::TimeNs now);
    std::optional<fsm::Message> through_the_codec(const fsm::Message& message);
    std::vector<Forged> plausible_switch(const fsm::NodeProtocol& at);
    fsm::Message template_of(std::size_t kind, const fsm::NodeProtocol& at, fsm::TimeNs now) const;

    // --- values ---
    std::uint32_t near(std::uint64_t base, std::uint64_t width_max);
    std::uint64_t near64(std::uint64_t base, std::uint64_t width_max);
    fsm::NodeId any_node();
    fsm::TaskId any_task();
    fsm::ConfigId any_config();
    fsm::NodeSet any_nodes(fsm::NodeSet around);
    fsm::View any_view(const fsm::View& around);
    // An online configuration near the one `around` runs (its graph configuration's, if
    // it is not online): a few of its values changed.
    fsm::OnlinePtr any_online(const fsm::View& around);
    fsm::Version any_version(fsm::Version around, fsm::Epoch epoch);
    std::vector<std::uint8_t> any_state();

    const fsm::Topology* topology_;
    fsm::NodeId node_;
    Rng rng_;
    // The liar's last honest message of each kind, which forged ones start from.
    std::array<std::optional<fsm::Message>, std::variant_size_v<fsm::Message>> last_;
};

}  // namespace keel::sim
