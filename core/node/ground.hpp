// Ground commands (docs/operations.md): what the operators send a running cluster, checked
// by every node before it acts.
//
// A ground command is one line of text, signed by the operator's key:
//
//     keel-ground/1 image=IMAGE seq=SEQ VERB ARG...
//
// IMAGE is the first 16 hex digits of the SHA-256 of the mission image the command is for
// (a command for another image is refused: its ids would name other nodes and
// configurations), SEQ a number that only grows (the ground uses the time in
// microseconds), VERB one of kGroundVerbs. It reaches a node on the node's control input
// as `ground SIGNATURE COMMAND`, SIGNATURE the operator's ECDSA (SHA-256) signature of
// COMMAND's bytes in hex (DER). A node admits it only when the signature is the
// operator's, the operator's certificate and permissions are valid now, the permissions
// name the verb, the image is the node's and SEQ is above every SEQ it admitted before
// (saved with its state: a command replayed after a restart is refused too).
//
// GroundGate decides; the runtime acts (NodeRuntime: `phase` and `recover` at the Master,
// `exclude`, `readmit`, `pause-task`, `resume-task` and `designate` at every node:
// NodeProtocol::ground_exclude, ground_readmit, ground_pause, ground_resume,
// ground_designate) and
// saves the new SEQ before it acts.
#pragma once

#include <array>
#include <cstdint>
#include <ctime>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/net/dds/credentials.hpp"

namespace keel::node {

// The verbs a ground command may name, each with its number of arguments.
struct GroundVerb {
    std::string_view name;
    std::size_t arguments;
    std::string_view meaning;
};
inline constexpr std::array<GroundVerb, 7> kGroundVerbs{{
    {"phase", 1, "enter phase ARG (the Master switches along the mission's phase edge)"},
    {"recover", 1, "leave safe mode for configuration ARG (the Master checks it is proven)"},
    {"exclude", 1, "hold node ARG out: it resigns (its own word) and no Master readmits it"},
    {"readmit", 1, "let node ARG back: it is readmitted as any node that comes back"},
    {"pause-task", 1, "stop task ARG where it runs, keeping it placed (never an essential one)"},
    {"resume-task", 1, "let task ARG, paused, run again from its last state"},
    {"designate", 4,
     "NODE WAIT SPAN ECHO: the ground's vote for NODE to take over a headless cluster (a mission with "
     "heartbeat.tie_grace), from WAIT periods after it arrives to SPAN periods after NODE's heartbeat ECHO"},
}};

struct GroundCommand {
    std::uint64_t seq = 0;
    std::string verb;
    std::vector<std::string> arguments;
    std::string text;  // as signed
};

// Why a command was refused: a stable kind (the status line's counter) and a sentence.
struct GroundRefusal {
    std::string kind;  // malformed, signature, expired, image, verb, replay, unsaved, unsigned
    std::string why;
};

class GroundGate {
public:
    // `secured`: the node runs with DDS Security. A node without (--insecure) trusts its
    // control input as the ground's: it takes unsigned `phase`, `recover`, `exclude` and
    // `readmit` lines. `operator_identity`: the operator's certificate and grant, when they
    // loaded (a secured node without them flies, and refuses every ground command, saying
    // `operator_problem`); `image_prefix`: the node's image's first 16 hex digits (empty:
    // not compared); `last_seq`: the highest SEQ admitted before (saved).
    GroundGate(bool secured, std::optional<net::dds::OperatorIdentity> operator_identity,
               std::string operator_problem, std::string image_prefix, std::uint64_t last_seq);

    // `ground SIGNATURE COMMAND`'s remainder: "SIGNATURE COMMAND". `durable`: the node can
    // save the new SEQ before it acts (it has a state database and its disk works); a
    // command it could not save is refused (`unsaved`): a replay after a restart could not
    // be told apart.
    std::variant<GroundCommand, GroundRefusal> admit(std::string_view signed_line, std::time_t now,
                                                     bool durable = true);
    // An unsigned ground verb (`phase NAME`, `recover NAME` on the control input): taken
    // only by a node without an operator identity.
    std::optional<GroundRefusal> admit_unsigned(std::string_view verb);

    bool secured() const { return secured_; }
    std::uint64_t last_seq() const { return last_seq_; }
    std::uint64_t accepted() const { return accepted_; }
    const std::map<std::string, std::uint64_t>& refused() const { return refused_; }
    // {"accepted": N, "last_seq": S, "refused": {"kind": n, ...}}
    std::string json() const;

private:
    GroundRefusal refuse(std::string kind, std::string why);

    bool secured_ = false;
    std::optional<net::dds::OperatorIdentity> identity_;
    std::string operator_problem_;
    std::string image_prefix_;
    std::uint64_t last_seq_ = 0;
    std::uint64_t accepted_ = 0;
    std::map<std::string, std::uint64_t> refused_;
};

}  // namespace keel::node
