// Checks a node's DDS Security files before the node joins the network, so a node without
// valid credentials refuses to start with a sentence that names the file and the reason
// (missing, not PEM, expired, not yet valid, another node's identity, not signed by the
// CA, revoked, a key that does not belong to the certificate, permissions for another
// subject or expired), instead of DDS's bare "participant could not be created".
//
// Cyclone's own plugins check the same files again when the participant is created; this
// is the operator's explanation, not the enforcement.
#pragma once

#include <ctime>
#include <optional>
#include <string>
#include <string_view>

#include "core/net/dds/dds_transport.hpp"

namespace keel::net::dds {

struct CredentialProblem {
    std::string file;     // the file at fault
    std::string message;  // why, in one sentence
};

// The subject the identity certificate of `node_name` must carry: its common name is the
// node's name in the mission.
std::optional<CredentialProblem> check_credentials(const SecurityFiles& files,
                                                   std::string_view node_name,
                                                   std::time_t now = std::time(nullptr));

}  // namespace keel::net::dds
