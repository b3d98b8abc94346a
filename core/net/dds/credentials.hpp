// Checks a node's DDS Security files before the node joins the network, so a node without
// valid credentials refuses to start with a sentence that names the file and the reason
// (missing, not PEM, expired, not yet valid, another node's identity, not signed by the
// CA, revoked, a key that does not belong to the certificate, permissions for another
// subject or expired), instead of DDS's bare "participant could not be created".
//
// Cyclone's own plugins check the same files again when the participant is created; this
// is the operator's explanation, not the enforcement.
#pragma once

#include <algorithm>
#include <ctime>
#include <memory>
#include <set>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include <variant>

#include "core/net/dds/dds_transport.hpp"

using X509 = struct x509_st;
using EVP_PKEY = struct evp_pkey_st;

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

// The ground's operator (docs/operations.md): an identity of its own, "CN=keel-operator,
// OU=MISSION,O=Keel", issued by the mission's CA beside the nodes' and never given to a
// node (a node holds only its certificate, to check the operator's signatures), and a
// permissions document signed by the CA that names the ground commands (verbs) the
// operator may send and until when. `keel-cluster credentials` makes both in
// DIR/operator/ (the key stays with the ground: DIR/operator/key.pem).
inline constexpr std::string_view kOperatorCommonName = "keel-operator";

struct OperatorFiles {
    std::string certificate;  // PEM
    std::string permissions;  // S/MIME, signed by the permissions CA
};
// DIR/operator/cert.pem and DIR/operator/permissions.p7s; DIR is made absolute.
OperatorFiles operator_files_in(const std::string& security_dir);

// When each dated credential a node holds stops being valid: the CA's certificate, the
// node's certificate and permissions, the CRL's next update (after which peers may refuse
// it), and the operator's certificate and grant when given. In the order of expiry.
struct CredentialExpiry {
    std::string file;
    std::string what;      // "the identity certificate", "the CRL's next update", ...
    std::time_t from = 0;  // valid from (UTC; the CRL: its last update)
    std::time_t at = 0;    // valid until (UTC)
    // How long before `at` a node warns: a tenth of the validity, at least a day and at
    // most 30 days (a 30-day set warns 3 days ahead, a year-long one 30 days ahead).
    std::time_t warning_s() const {
        return std::clamp<std::time_t>((at - from) / 10, 86'400, 30 * 86'400);
    }
    bool due(std::time_t now) const { return now >= at - warning_s(); }
};
std::vector<CredentialExpiry> credential_expiries(const SecurityFiles& files,
                                                  const std::optional<OperatorFiles>& operator_files);

class OperatorIdentity {
public:
    // Checks the operator's certificate (signed by the node's identity CA, the operator's
    // common name, the node's mission as its OU, valid at `now`, not in the CRL) and its
    // permissions (signed by the permissions CA, for that subject, not expired); a problem
    // names the file and the reason, as check_credentials does.
    static std::variant<OperatorIdentity, CredentialProblem> load(const SecurityFiles& node,
                                                                  const OperatorFiles& files,
                                                                  std::time_t now = std::time(nullptr));
    // Whether `signature` (DER ECDSA, SHA-256) is the operator's signature of `text`.
    bool verifies(std::string_view text, std::string_view signature) const;
    bool permits(std::string_view verb) const;
    const std::set<std::string>& verbs() const { return verbs_; }
    // The certificate or the permissions expired (or are not valid yet) at `now`.
    std::optional<std::string> expiry_problem(std::time_t now) const;
    const std::string& subject() const { return subject_; }

private:
    std::shared_ptr<X509> certificate_;
    std::shared_ptr<EVP_PKEY> key_;
    std::set<std::string> verbs_;
    std::string not_after_;  // the permissions', UTC YYYY-MM-DDTHH:MM:SS
    std::string subject_;
};

}  // namespace keel::net::dds
