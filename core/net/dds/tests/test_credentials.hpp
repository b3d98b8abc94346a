// Test credentials made with OpenSSL's API: a CA, node identities with chosen names and
// dates, governance and permissions documents signed as S/MIME (the layout of
// `keel-cluster credentials`, nodes/cluster/README.md "Security"). For the tests of the
// credential check and of secured participants; never for flight.
#pragma once

#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

namespace keel::net::dds::testing {

struct Identity {
    std::string name;                 // directory nodes/NAME and the common name
    std::string common_name{};        // empty: name
    long not_before_offset_s = -3600; // from now
    long not_after_offset_s = 86400;
    bool signed_by_other_ca = false;  // a certificate the mission's CA never issued
    // Permissions: publish in these partitions (default keel.from.<address>, keel.node.*,
    // keel.broadcast), grant to this subject (default the certificate's).
    int address = 0;
    std::string granted_subject{};
    bool may_command = true;          // KeelCommand among the published topics
    long permissions_not_after_offset_s = 0;  // 0: the certificate's not_after
    bool permissions_signed_by_other_ca = false;  // a grant the mission's CA never signed
    // Non-empty: the ground's operator (credentials.hpp), written to operator/ (cert.pem,
    // key.pem, permissions.p7s granting these verbs) instead of nodes/NAME/.
    std::string operator_verbs{};
    long permissions_not_before_offset_s = 0;  // the operator's grant; 0: the certificate's
};

class CredentialsDir {
public:
    // Writes ca.pem, ca.key, governance.p7s, crl.pem (revoking `revoked`) and
    // nodes/NAME/{cert.pem,key.pem,permissions.p7s} for every identity into `root`.
    CredentialsDir(std::filesystem::path root, const std::vector<Identity>& identities,
                   const std::vector<std::string>& revoked = {});
    const std::filesystem::path& root() const { return root_; }

private:
    std::filesystem::path root_;
};

}  // namespace keel::net::dds::testing
