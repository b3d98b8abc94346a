// DDS Security: the credential check a node runs before it joins (each refusal names the
// file and the reason), and secured participants on loopback: nodes with the mission's
// credentials talk; a participant without them, or a node writing as another node, gets
// nothing delivered.
#include <dds/dds.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "core/net/dds/credentials.hpp"
#include "core/net/dds/dds_transport.hpp"
#include "core/net/endpoint.hpp"
#include "core/net/dds/tests/support.hpp"
#include "keel.h"
#include "test_credentials.hpp"

namespace keel::net::dds {
namespace {

using namespace std::chrono_literals;
using testing::CredentialsDir;
using testing::Identity;
using testing::test_name;

std::filesystem::path temp_dir() {
    return std::filesystem::temp_directory_path() /
           ("keel-credentials-" + std::to_string(::getpid()) + "-" + test_name());
}

// One directory of credentials shared by the checks: every kind of identity the tests need.
class Credentials : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        root_ = new std::filesystem::path(std::filesystem::temp_directory_path() /
                                          ("keel-credentials-" + std::to_string(::getpid())));
        std::filesystem::remove_all(*root_);
        Identity expired{.name = "OLD", .not_before_offset_s = -10 * 86400, .not_after_offset_s = -86400};
        Identity early{.name = "EARLY", .not_before_offset_s = 86400, .not_after_offset_s = 2 * 86400};
        Identity foreign{.name = "ALIEN", .signed_by_other_ca = true};
        Identity misnamed{.name = "PN4", .common_name = "PN1"};
        Identity regranted{.name = "PN5", .granted_subject = "CN=PN1,OU=test,O=Keel"};
        Identity lapsed{.name = "PN6", .permissions_not_after_offset_s = -60};
        Identity self_granted{.name = "PN7", .permissions_signed_by_other_ca = true};
        CredentialsDir made(*root_,
                            {Identity{.name = "PN1", .address = 1}, Identity{.name = "PN2", .address = 2},
                             Identity{.name = "PN3", .address = 3}, expired, early, foreign, misnamed,
                             regranted, lapsed, self_granted},
                            {"PN3"});
    }
    static void TearDownTestSuite() {
        std::filesystem::remove_all(*root_);
        delete root_;
    }
    static std::string problem(const SecurityFiles& files, const std::string& node) {
        const auto found = check_credentials(files, node);
        return found ? found->file + ": " + found->message : "";
    }
    static SecurityFiles files(const std::string& node) {
        return security_files_in(root_->string(), node);
    }
    static std::filesystem::path* root_;
};
std::filesystem::path* Credentials::root_ = nullptr;

TEST_F(Credentials, ANodeWithItsOwnValidCredentialsPasses) {
    EXPECT_EQ(problem(files("PN1"), "PN1"), "");
    EXPECT_EQ(problem(files("PN2"), "PN2"), "");
}

TEST_F(Credentials, EachRefusalNamesTheFileAndTheReason) {
    const std::string missing = problem(security_files_in("/nonexistent/keel", "PN1"), "PN1");
    EXPECT_NE(missing.find("/nonexistent/keel/ca.pem: missing or unreadable"), std::string::npos) << missing;

    const std::string expired = problem(files("OLD"), "OLD");
    EXPECT_NE(expired.find("nodes/OLD/cert.pem: the identity certificate expired on"), std::string::npos)
        << expired;
    const std::string early = problem(files("EARLY"), "EARLY");
    EXPECT_NE(early.find("is not valid yet"), std::string::npos) << early;
    // Another node's credentials given to this node.
    const std::string other = problem(files("PN2"), "PN1");
    EXPECT_NE(other.find("is the identity of 'PN2', not of node 'PN1'"), std::string::npos) << other;
    const std::string misnamed = problem(files("PN4"), "PN4");
    EXPECT_NE(misnamed.find("is the identity of 'PN1', not of node 'PN4'"), std::string::npos) << misnamed;
    const std::string foreign = problem(files("ALIEN"), "ALIEN");
    EXPECT_NE(foreign.find("not signed by the identity CA"), std::string::npos) << foreign;
    const std::string revoked = problem(files("PN3"), "PN3");
    EXPECT_NE(revoked.find("nodes/PN3/cert.pem: was revoked on"), std::string::npos) << revoked;
    const std::string regranted = problem(files("PN5"), "PN5");
    EXPECT_NE(regranted.find("permissions.p7s: grants 'CN=PN1,OU=test,O=Keel', not this node's identity"),
              std::string::npos)
        << regranted;
}

TEST_F(Credentials, ExpiredPermissionsAFileThatIsNotPemAndATamperedGovernanceAreRefused) {
    // Signed, but by a key that is not the permissions CA's: a node granting itself.
    const std::string self_granted = problem(files("PN7"), "PN7");
    EXPECT_NE(self_granted.find("nodes/PN7/permissions.p7s: not an S/MIME document signed by the "
                                "permissions CA"),
              std::string::npos)
        << self_granted;
    const std::string lapsed = problem(files("PN6"), "PN6");
    EXPECT_NE(lapsed.find("nodes/PN6/permissions.p7s: expired on"), std::string::npos) << lapsed;

    const auto dir = temp_dir();
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "cert.pem") << "not a certificate\n";
    SecurityFiles garbled = files("PN1");
    garbled.identity_certificate = (dir / "cert.pem").string();
    const std::string not_pem = problem(garbled, "PN1");
    EXPECT_NE(not_pem.find("cert.pem: not a PEM certificate"), std::string::npos) << not_pem;

    {
        std::ifstream in(files("PN1").governance);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const auto at = text.find("<allow_unauthenticated_participants>false");
        ASSERT_NE(at, std::string::npos);
        text.replace(at, 41, "<allow_unauthenticated_participants>true ");  // let outsiders in
        std::ofstream(dir / "governance.p7s") << text;
    }
    SecurityFiles opened = files("PN1");
    opened.governance = (dir / "governance.p7s").string();
    const std::string tampered = problem(opened, "PN1");
    EXPECT_NE(tampered.find("governance.p7s: not an S/MIME document signed by the permissions CA"),
              std::string::npos)
        << tampered;
    std::filesystem::remove_all(dir);
}

TEST_F(Credentials, AKeyOfAnotherNodeOrATamperedDocumentIsRefused) {
    SecurityFiles swapped = files("PN1");
    swapped.private_key = files("PN2").private_key;
    EXPECT_NE(problem(swapped, "PN1").find("key.pem: does not belong to the certificate"), std::string::npos)
        << problem(swapped, "PN1");

    const auto tampered = temp_dir() / "permissions.p7s";
    std::filesystem::create_directories(tampered.parent_path());
    {
        std::ifstream in(files("PN1").permissions);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const auto at = text.find("keel.from.1");
        ASSERT_NE(at, std::string::npos);
        text.replace(at, 11, "keel.from.*");  // a node granting itself every sender partition
        std::ofstream(tampered) << text;
    }
    SecurityFiles forged = files("PN1");
    forged.permissions = tampered.string();
    EXPECT_NE(problem(forged, "PN1").find("not an S/MIME document signed by the permissions CA"),
              std::string::npos)
        << problem(forged, "PN1");
    std::filesystem::remove_all(temp_dir());
}

DdsConfig secured(NodeAddress address, std::uint32_t domain, const SecurityFiles& files) {
    DdsConfig config;
    config.address = address;
    config.domain_id = domain;
    config.heartbeat_period = 20ms;
    config.heartbeat_miss_limit = 2;
    config.security = files;
    return config;
}

pid_t spawn(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
    return pid;
}

int wait_exit(pid_t pid) {
    int status = 0;
    if (waitpid(pid, &status, 0) != pid) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Two nodes with the mission's credentials exchange messages: keel-net-bench pong (PN2) and
// ping (PN1), each a process of its own (Cyclone 0.10 holds one security configuration per
// process and domain). A participant without credentials in the same domain (this process),
// writing in node 1's sender partition and reading every sender's, is never authenticated:
// no secured endpoint matches it, so it neither injects nor reads anything.
TEST_F(Credentials, SecuredNodesTalkAndAParticipantWithoutCredentialsIsNotHeard) {
    const std::uint32_t domain = domain_id_for(test_name());
    const std::string dir = root_->string();
    const pid_t pong = spawn({KEEL_NET_BENCH, "pong", "--domain", std::to_string(domain), "--duration",
                              "60", "--security", dir, "--identity", "PN2"});
    ASSERT_GT(pong, 0);
    struct Reap {
        pid_t pid;
        ~Reap() {
            kill(pid, SIGTERM);
            wait_exit(pid);
        }
    } reap{pong};

    // The outsider: a plain participant in the same domain.
    const dds_entity_t outsider = dds_create_participant(domain, nullptr, nullptr);
    ASSERT_GT(outsider, 0);
    auto in_partition = [&](bool publisher, const char* partition) {
        dds_qos_t* qos = dds_create_qos();
        const char* partitions[] = {partition};
        dds_qset_partition(qos, 1, partitions);
        const dds_entity_t entity = publisher ? dds_create_publisher(outsider, qos, nullptr)
                                              : dds_create_subscriber(outsider, qos, nullptr);
        dds_delete_qos(qos);
        return entity;
    };
    const dds_entity_t topic =
        dds_create_topic(outsider, &keel_wire_Message_desc, "KeelReliableData", nullptr, nullptr);
    // Its own writer and reader do not meet: what they match is someone else.
    dds_qos_t* apart = dds_create_qos();
    dds_qset_ignorelocal(apart, DDS_IGNORELOCAL_PARTICIPANT);
    dds_qset_reliability(apart, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    const dds_entity_t writer = dds_create_writer(in_partition(true, "keel.from.1"), topic, apart, nullptr);
    const dds_entity_t reader = dds_create_reader(in_partition(false, "keel.from.*"), topic, apart, nullptr);
    dds_delete_qos(apart);
    ASSERT_GT(writer, 0);
    ASSERT_GT(reader, 0);

    const pid_t ping = spawn({KEEL_NET_BENCH, "ping", "--domain", std::to_string(domain), "--sizes",
                              "64", "--rounds-small", "40", "--wire-messages", "20", "--security",
                              dir, "--identity", "PN1"});
    ASSERT_GT(ping, 0);
    std::uint8_t payload[1] = {0x66};
    keel_wire_Message forged{};
    forged.source = 1;
    forged.destination = 2;
    forged.port = 1;  // pong's echo port
    forged.epoch = 1002;
    forged.sequence_number = 1'000'000;
    forged.payload._buffer = payload;
    forged.payload._length = forged.payload._maximum = 1;
    for (int i = 0; i < 50; ++i) {
        dds_write(writer, &forged);
        ++forged.sequence_number;
        std::this_thread::sleep_for(10ms);
    }
    EXPECT_EQ(wait_exit(ping), 0) << "the secured ping got no echoes from the secured pong";
    dds_publication_matched_status_t published{};
    ASSERT_GE(dds_get_publication_matched_status(writer, &published), 0);
    EXPECT_EQ(published.total_count, 0u) << "a secured reader matched an unauthenticated writer";
    dds_subscription_matched_status_t subscribed{};
    ASSERT_GE(dds_get_subscription_matched_status(reader, &subscribed), 0);
    EXPECT_EQ(subscribed.total_count, 0u) << "a secured writer matched an unauthenticated reader";
    void* samples[1] = {nullptr};
    dds_sample_info_t info;
    EXPECT_EQ(dds_take(reader, samples, &info, 1, 1), 0) << "the outsider read a node's sample";
    EXPECT_EQ(dds_delete(outsider), DDS_RETCODE_OK);
}

// A node cannot publish in another node's sender partition: its permissions do not allow
// it (access control refuses the writer), and one whose permissions do not let it command
// cannot create a command writer at all.
TEST_F(Credentials, PermissionsLetANodeWriteOnlyAsItselfAndOnlyWhatItsRoleNeeds) {
    const std::uint32_t domain = domain_id_for(test_name());
    SecurityFiles pn2 = files("PN2");
    // PN2 pretending to be node 1: its writers publish in keel.from.1, outside its grant.
    EXPECT_THROW(DdsTransport(secured(1, domain, pn2)), DdsError);
    EXPECT_NO_THROW(DdsTransport(secured(2, domain, pn2)));

    const auto storage_root = temp_dir();
    std::filesystem::remove_all(storage_root);
    CredentialsDir storage(storage_root, {Identity{.name = "ST1", .address = 4, .may_command = false}});
    DdsConfig config = secured(4, domain, security_files_in(storage_root.string(), "ST1"));
    EXPECT_THROW(DdsTransport{config}, DdsError);
    config.receive_only_kinds = {MessageKind::reconfiguration_command};
    EXPECT_NO_THROW(DdsTransport{config});
    std::filesystem::remove_all(storage_root);
}

}  // namespace
}  // namespace keel::net::dds
