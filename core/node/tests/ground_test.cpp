// GroundGate (ground.hpp): a ground command is admitted only signed by the mission's
// operator, for this image, with a seq above the last one, and a verb the operator's
// permissions grant; OperatorIdentity::load refuses an operator identity the mission's CA
// did not issue, one of another name, revoked or expired.
#include "core/node/ground.hpp"

#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <openssl/pem.h>

#include <cstdio>
#include <filesystem>
#include <memory>

#include "core/net/dds/tests/test_credentials.hpp"

namespace keel::node {
namespace {

namespace fs = std::filesystem;
using net::dds::OperatorIdentity;
using net::dds::testing::CredentialsDir;
using net::dds::testing::Identity;

constexpr std::string_view kImage = "0123456789abcdef";

// The operator's signature of `text` (DER ECDSA over SHA-256) in hex, as keel-cluster makes it.
std::string sign(const fs::path& key_path, std::string_view text) {
    std::FILE* file = std::fopen(key_path.c_str(), "r");
    EXPECT_NE(file, nullptr);
    std::unique_ptr<EVP_PKEY, decltype(&EVP_PKEY_free)> key(
        PEM_read_PrivateKey(file, nullptr, nullptr, nullptr), EVP_PKEY_free);
    std::fclose(file);
    std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context(EVP_MD_CTX_new(), EVP_MD_CTX_free);
    std::size_t size = 0;
    EVP_DigestSignInit(context.get(), nullptr, EVP_sha256(), nullptr, key.get());
    EVP_DigestSign(context.get(), nullptr, &size, reinterpret_cast<const unsigned char*>(text.data()), text.size());
    std::string signature(size, '\0');
    EVP_DigestSign(context.get(), reinterpret_cast<unsigned char*>(signature.data()), &size,
                   reinterpret_cast<const unsigned char*>(text.data()), text.size());
    signature.resize(size);
    std::string hex;
    for (const unsigned char byte : signature) {
        char two[3];
        std::snprintf(two, sizeof two, "%02x", byte);
        hex += two;
    }
    return hex;
}

std::string command(std::uint64_t seq, std::string_view verb_and_argument, std::string_view image = kImage) {
    return "keel-ground/1 image=" + std::string(image) + " seq=" + std::to_string(seq) + " " +
           std::string(verb_and_argument);
}

class Ground : public ::testing::Test {
protected:
    void SetUp() override {
        root = fs::temp_directory_path() /
               ("keel-ground-test-" + std::to_string(::getpid()) + "-" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(root);
    }
    void TearDown() override { fs::remove_all(root); }

    // Credentials with node PN1 and the operator; the gate of PN1 with its operator.
    GroundGate gate(const Identity& operator_identity, std::uint64_t last_seq = 0,
                    const std::vector<std::string>& revoked = {}) {
        CredentialsDir dir(root, {Identity{.name = "PN1"}, operator_identity}, revoked);
        auto loaded = load();
        EXPECT_TRUE(std::holds_alternative<OperatorIdentity>(loaded))
            << std::get<net::dds::CredentialProblem>(loaded).message;
        return GroundGate(true, std::get<OperatorIdentity>(loaded), "", std::string(kImage), last_seq);
    }
    std::variant<OperatorIdentity, net::dds::CredentialProblem> load() {
        return OperatorIdentity::load(net::dds::security_files_in(root.string(), "PN1"),
                                      net::dds::operator_files_in(root.string()));
    }
    std::string signed_line(std::string_view text) { return sign(root / "operator" / "key.pem", text) + " " + std::string(text); }

    fs::path root;
    static Identity operator_with(std::string verbs) {
        return Identity{.name = "operator", .common_name = "keel-operator", .operator_verbs = std::move(verbs)};
    }
};

std::string refusal_kind(const std::variant<GroundCommand, GroundRefusal>& result) {
    const auto* refusal = std::get_if<GroundRefusal>(&result);
    return refusal == nullptr ? "admitted" : refusal->kind;
}

TEST_F(Ground, ASignedCommandIsAdmittedOnceAndItsSeqOnlyGrows) {
    GroundGate ground = gate(operator_with("phase recover exclude"));
    const auto admitted = ground.admit(signed_line(command(10, "phase science")), std::time(nullptr));
    ASSERT_EQ(refusal_kind(admitted), "admitted");
    EXPECT_EQ(std::get<GroundCommand>(admitted).verb, "phase");
    EXPECT_EQ(std::get<GroundCommand>(admitted).arguments, std::vector<std::string>{"science"});
    EXPECT_EQ(ground.last_seq(), 10u);
    // The same command again, and an older one: replays.
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(10, "phase science")), std::time(nullptr))), "replay");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(9, "phase nominal")), std::time(nullptr))), "replay");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(11, "exclude PN2")), std::time(nullptr))), "admitted");
    EXPECT_EQ(ground.accepted(), 2u);
    EXPECT_EQ(ground.refused().at("replay"), 2u);
    EXPECT_NE(ground.json().find("\"replay\":2"), std::string::npos) << ground.json();
}

TEST_F(Ground, ASavedSeqRefusesACommandReplayedAfterARestart) {
    GroundGate ground = gate(operator_with("phase"), 10);
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(10, "phase science")), std::time(nullptr))), "replay");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(12, "phase science")), std::time(nullptr))), "admitted");
}

TEST_F(Ground, AChangedCommandAnotherImageAVerbNotGrantedAndGarbageAreRefused) {
    GroundGate ground = gate(operator_with("phase"));
    // Signed for one text, sent with another: the signature does not hold.
    const std::string signature = sign(root / "operator" / "key.pem", command(5, "phase science"));
    EXPECT_EQ(refusal_kind(ground.admit(signature + " " + command(5, "phase nominal"), std::time(nullptr))),
              "signature");
    // Signed by a node's key, not the operator's.
    EXPECT_EQ(refusal_kind(ground.admit(sign(root / "nodes" / "PN1" / "key.pem", command(5, "phase science")) +
                                            " " + command(5, "phase science"),
                                        std::time(nullptr))),
              "signature");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(6, "phase science", "ffffffffffffffff")),
                                        std::time(nullptr))),
              "image");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(7, "exclude PN2")), std::time(nullptr))), "verb");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(8, "designate PN2")), std::time(nullptr))), "malformed");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(8, "phase")), std::time(nullptr))), "malformed");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(0, "phase science")), std::time(nullptr))), "malformed");
    EXPECT_EQ(refusal_kind(ground.admit("zz " + command(9, "phase science"), std::time(nullptr))), "malformed");
    EXPECT_EQ(refusal_kind(ground.admit("nothing", std::time(nullptr))), "malformed");
    // None of them moved the seq: a valid command still goes through.
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(5, "phase science")), std::time(nullptr))), "admitted");
    EXPECT_EQ(ground.accepted(), 1u);
}

TEST_F(Ground, ACommandAfterTheOperatorsPermissionsExpiredIsRefused) {
    Identity expiring = operator_with("phase");
    expiring.permissions_not_after_offset_s = 60;
    GroundGate ground = gate(expiring);
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(1, "phase science")), std::time(nullptr) + 3600)),
              "expired");
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(1, "phase science")), std::time(nullptr))), "admitted");
}

TEST_F(Ground, UnsignedGroundVerbsAreTakenOnlyWithoutAnOperatorIdentity) {
    GroundGate secured = gate(operator_with("phase"));
    ASSERT_TRUE(secured.admit_unsigned("phase").has_value());
    EXPECT_EQ(secured.admit_unsigned("phase")->kind, "unsigned");
    GroundGate insecure(false, std::nullopt, "", std::string(kImage), 0);
    EXPECT_FALSE(insecure.admit_unsigned("phase").has_value());
    // Without an operator there is nothing to check a signature with.
    EXPECT_EQ(refusal_kind(insecure.admit(signed_line(command(1, "phase science")), std::time(nullptr))),
              "signature");
    // A secured node whose operator identity did not load flies, and takes no ground
    // command, signed or not, saying why.
    GroundGate orphan(true, std::nullopt, "DIR/operator/cert.pem: was revoked", std::string(kImage), 0);
    EXPECT_EQ(orphan.admit_unsigned("phase")->kind, "unsigned");
    const auto refused = orphan.admit(signed_line(command(1, "phase science")), std::time(nullptr));
    ASSERT_EQ(refusal_kind(refused), "signature");
    EXPECT_NE(std::get<GroundRefusal>(refused).why.find("was revoked"), std::string::npos);
}

TEST_F(Ground, ACommandWhoseSeqCannotBeSavedIsRefused) {
    GroundGate ground = gate(operator_with("phase"));
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(4, "phase science")), std::time(nullptr), false)),
              "unsaved");
    EXPECT_EQ(ground.last_seq(), 0u);
    EXPECT_EQ(refusal_kind(ground.admit(signed_line(command(4, "phase science")), std::time(nullptr))), "admitted");
}

TEST_F(Ground, AnOperatorIdentityTheMissionsCaDidNotIssueOrOfAnotherNameOrRevokedIsRefused) {
    {
        Identity other = operator_with("phase");
        other.signed_by_other_ca = true;
        CredentialsDir dir(root, {Identity{.name = "PN1"}, other});
        const auto loaded = load();
        ASSERT_TRUE(std::holds_alternative<net::dds::CredentialProblem>(loaded));
        EXPECT_NE(std::get<net::dds::CredentialProblem>(loaded).message.find("not signed by the identity CA"),
                  std::string::npos);
    }
    fs::remove_all(root);
    {
        Identity misnamed = operator_with("phase");
        misnamed.common_name = "PN2";
        CredentialsDir dir(root, {Identity{.name = "PN1"}, misnamed});
        const auto loaded = load();
        ASSERT_TRUE(std::holds_alternative<net::dds::CredentialProblem>(loaded));
        EXPECT_NE(std::get<net::dds::CredentialProblem>(loaded).message.find("not of the operator"),
                  std::string::npos);
    }
    fs::remove_all(root);
    {
        CredentialsDir dir(root, {Identity{.name = "PN1"}, operator_with("phase")}, {"operator"});
        const auto loaded = load();
        ASSERT_TRUE(std::holds_alternative<net::dds::CredentialProblem>(loaded));
        EXPECT_NE(std::get<net::dds::CredentialProblem>(loaded).message.find("was revoked"), std::string::npos);
    }
    fs::remove_all(root);
    {
        Identity early = operator_with("phase");
        early.permissions_not_before_offset_s = 3600;  // a grant valid from an hour on
        CredentialsDir dir(root, {Identity{.name = "PN1"}, early});
        const auto loaded = load();
        ASSERT_TRUE(std::holds_alternative<net::dds::CredentialProblem>(loaded));
        EXPECT_NE(std::get<net::dds::CredentialProblem>(loaded).message.find("is not valid yet"),
                  std::string::npos);
    }
    fs::remove_all(root);
    {
        Identity foreign = operator_with("phase");
        foreign.permissions_signed_by_other_ca = true;
        CredentialsDir dir(root, {Identity{.name = "PN1"}, foreign});
        const auto loaded = load();
        ASSERT_TRUE(std::holds_alternative<net::dds::CredentialProblem>(loaded));
        EXPECT_NE(std::get<net::dds::CredentialProblem>(loaded).message.find("not an S/MIME document"),
                  std::string::npos);
    }
}

}  // namespace
}  // namespace keel::node
