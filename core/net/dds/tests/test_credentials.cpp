#include "test_credentials.hpp"

#include <openssl/bio.h>
#include <openssl/ec.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>

namespace keel::net::dds::testing {

namespace {

void require(bool ok, const char* what) {
    if (!ok) throw std::runtime_error(std::string("test credentials: ") + what);
}

EVP_PKEY* new_key() {
    EVP_PKEY* key = EVP_EC_gen("P-256");
    require(key != nullptr, "EC key");
    return key;
}

X509* new_cert(const std::string& subject_cn, EVP_PKEY* key, X509* issuer, EVP_PKEY* issuer_key,
               long not_before, long not_after, long serial, bool ca) {
    X509* cert = X509_new();
    X509_set_version(cert, 2);
    ASN1_INTEGER_set(X509_get_serialNumber(cert), serial);
    X509_gmtime_adj(X509_getm_notBefore(cert), not_before);
    X509_gmtime_adj(X509_getm_notAfter(cert), not_after);
    X509_NAME* name = X509_get_subject_name(cert);
    X509_NAME_add_entry_by_txt(name, "O", MBSTRING_ASC, reinterpret_cast<const unsigned char*>("Keel"), -1, -1, 0);
    X509_NAME_add_entry_by_txt(name, "OU", MBSTRING_ASC, reinterpret_cast<const unsigned char*>("test"), -1, -1, 0);
    X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC,
                               reinterpret_cast<const unsigned char*>(subject_cn.c_str()), -1, -1, 0);
    X509_set_issuer_name(cert, issuer != nullptr ? X509_get_subject_name(issuer) : name);
    X509_set_pubkey(cert, key);
    if (ca) {
        X509V3_CTX ctx;
        X509V3_set_ctx_nodb(&ctx);
        X509V3_set_ctx(&ctx, cert, cert, nullptr, nullptr, 0);
        X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &ctx, NID_basic_constraints, "critical,CA:TRUE");
        X509_add_ext(cert, ext, -1);
        X509_EXTENSION_free(ext);
    }
    require(X509_sign(cert, issuer_key, EVP_sha256()) > 0, "sign certificate");
    return cert;
}

std::string subject_of(X509* cert) {
    BIO* out = BIO_new(BIO_s_mem());
    X509_NAME_print_ex(out, X509_get_subject_name(cert), 0, XN_FLAG_RFC2253);
    char* data = nullptr;
    const long size = BIO_get_mem_data(out, &data);
    std::string text(data, static_cast<std::size_t>(size));
    BIO_free(out);
    return text;
}

template <class F>
void write_pem(const std::filesystem::path& path, F write) {
    std::filesystem::create_directories(path.parent_path());
    BIO* out = BIO_new_file(path.c_str(), "w");
    require(out != nullptr, "open output");
    require(write(out) == 1, "write PEM");
    BIO_free(out);
}

void write_smime(const std::filesystem::path& path, const std::string& text, X509* cert, EVP_PKEY* key) {
    BIO* in = BIO_new_mem_buf(text.data(), static_cast<int>(text.size()));
    PKCS7* p7 = PKCS7_sign(cert, key, nullptr, in, PKCS7_DETACHED | PKCS7_TEXT | PKCS7_STREAM);
    require(p7 != nullptr, "PKCS7_sign");
    BIO_free(in);
    in = BIO_new_mem_buf(text.data(), static_cast<int>(text.size()));
    write_pem(path, [&](BIO* out) {
        return SMIME_write_PKCS7(out, p7, in, PKCS7_DETACHED | PKCS7_TEXT | PKCS7_STREAM);
    });
    BIO_free(in);
    PKCS7_free(p7);
}

std::string utc(long offset_s) {
    const std::time_t at = std::time(nullptr) + offset_s;
    std::tm tm{};
    gmtime_r(&at, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &tm);
    return text;
}

const char* const kTopics[] = {"KeelData", "KeelReliableData", "KeelRequest", "KeelResponse",
                               "KeelCommand", "KeelAck", "KeelHeartbeat", "KeelError",
                               "KeelLarge", "KeelNodeState"};

std::string governance() {
    return R"(<?xml version="1.0" encoding="utf-8"?>
<dds><domain_access_rules><domain_rule>
<domains><id_range><min>0</min><max>230</max></id_range></domains>
<allow_unauthenticated_participants>false</allow_unauthenticated_participants>
<enable_join_access_control>true</enable_join_access_control>
<discovery_protection_kind>ENCRYPT</discovery_protection_kind>
<liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
<rtps_protection_kind>NONE</rtps_protection_kind>
<topic_access_rules><topic_rule><topic_expression>*</topic_expression>
<enable_discovery_protection>true</enable_discovery_protection>
<enable_liveliness_protection>true</enable_liveliness_protection>
<enable_read_access_control>true</enable_read_access_control>
<enable_write_access_control>true</enable_write_access_control>
<metadata_protection_kind>SIGN</metadata_protection_kind>
<data_protection_kind>ENCRYPT</data_protection_kind>
</topic_rule></topic_access_rules>
</domain_rule></domain_access_rules></dds>
)";
}

std::string permissions(const Identity& identity, const std::string& subject) {
    std::string topics;
    for (const char* topic : kTopics) {
        if (!identity.may_command && std::string(topic) == "KeelCommand") continue;
        topics += "<topic>" + std::string(topic) + "</topic>";
    }
    const std::string address = std::to_string(identity.address);
    // The node's state and the typed protocol topics it writes, also in the default
    // partition (for DDS tools), as keel-cluster credentials grants them.
    std::string for_tools =
        "<topic>KeelNodeState</topic><topic>KeelHeartbeat</topic><topic>KeelAck</topic>";
    if (identity.may_command) for_tools += "<topic>KeelCommand</topic>";
    return R"(<?xml version="1.0" encoding="utf-8"?>
<dds><permissions><grant name=")" + identity.name + R"(">
<subject_name>)" + subject + R"(</subject_name>
<validity><not_before>)" + utc(identity.not_before_offset_s) + "</not_before><not_after>" +
           utc(identity.permissions_not_after_offset_s != 0 ? identity.permissions_not_after_offset_s
                                                            : identity.not_after_offset_s) +
           R"(</not_after></validity>
<allow_rule><domains><id_range><min>0</min><max>230</max></id_range></domains>
<publish><topics>)" + topics + R"(</topics><partitions><partition>keel.from.)" + address +
           R"(</partition><partition>keel.node.*</partition><partition>keel.broadcast</partition></partitions></publish>
<publish><topics>)" + for_tools + R"(</topics><partitions><partition>keel.from.)" + address +
           R"(</partition><partition></partition></partitions></publish>
<subscribe><topics><topic>Keel*</topic></topics><partitions><partition>keel.from.*</partition><partition>keel.node.)" +
           address + R"(</partition><partition>keel.broadcast</partition></partitions></subscribe>
</allow_rule><default>DENY</default></grant></permissions></dds>
)";
}

// The operator's grant, as keel-cluster credentials writes it (nodes/cluster/keel_cluster/security.py).
std::string operator_permissions(const Identity& identity, const std::string& subject) {
    return "<keel_operator_permissions>\n<subject_name>" + subject + "</subject_name>\n<verbs>" +
           identity.operator_verbs + "</verbs>\n<not_before>" +
           utc(identity.permissions_not_before_offset_s != 0 ? identity.permissions_not_before_offset_s
                                                             : identity.not_before_offset_s) +
           "</not_before>\n<not_after>" +
           utc(identity.permissions_not_after_offset_s != 0 ? identity.permissions_not_after_offset_s
                                                            : identity.not_after_offset_s) +
           "</not_after>\n</keel_operator_permissions>\n";
}

}  // namespace

CredentialsDir::CredentialsDir(std::filesystem::path root, const std::vector<Identity>& identities,
                               const std::vector<std::string>& revoked)
    : root_(std::move(root)) {
    std::filesystem::create_directories(root_);
    EVP_PKEY* ca_key = new_key();
    X509* ca = new_cert("Keel test CA", ca_key, nullptr, ca_key, -86400, 30 * 86400, 1, true);
    EVP_PKEY* other_key = new_key();
    X509* other_ca = new_cert("Another CA", other_key, nullptr, other_key, -86400, 30 * 86400, 1, true);
    write_pem(root_ / "ca.pem", [&](BIO* out) { return PEM_write_bio_X509(out, ca); });
    write_pem(root_ / "ca.key", [&](BIO* out) {
        return PEM_write_bio_PrivateKey(out, ca_key, nullptr, nullptr, 0, nullptr, nullptr);
    });
    write_smime(root_ / "governance.p7s", governance(), ca, ca_key);
    std::map<std::string, long> serials;
    long serial = 100;
    for (const Identity& identity : identities) {
        EVP_PKEY* key = new_key();
        const std::string cn = identity.common_name.empty() ? identity.name : identity.common_name;
        X509* cert = new_cert(cn, key, identity.signed_by_other_ca ? other_ca : ca,
                              identity.signed_by_other_ca ? other_key : ca_key,
                              identity.not_before_offset_s, identity.not_after_offset_s, ++serial, false);
        serials[identity.name] = serial;
        const auto dir = identity.operator_verbs.empty() ? root_ / "nodes" / identity.name : root_ / "operator";
        write_pem(dir / "cert.pem", [&](BIO* out) { return PEM_write_bio_X509(out, cert); });
        write_pem(dir / "key.pem", [&](BIO* out) {
            return PEM_write_bio_PrivateKey(out, key, nullptr, nullptr, 0, nullptr, nullptr);
        });
        const std::string subject =
            identity.granted_subject.empty() ? subject_of(cert) : identity.granted_subject;
        const std::string grant = identity.operator_verbs.empty()
                                      ? permissions(identity, subject)
                                      : operator_permissions(identity, subject);
        if (identity.permissions_signed_by_other_ca) {
            write_smime(dir / "permissions.p7s", grant, other_ca, other_key);
        } else {
            write_smime(dir / "permissions.p7s", grant, ca, ca_key);
        }
        X509_free(cert);
        EVP_PKEY_free(key);
    }
    X509_CRL* crl = X509_CRL_new();
    X509_CRL_set_version(crl, 1);
    X509_CRL_set_issuer_name(crl, X509_get_subject_name(ca));
    ASN1_TIME* now = ASN1_TIME_adj(nullptr, std::time(nullptr), 0, -60);
    X509_CRL_set1_lastUpdate(crl, now);
    ASN1_TIME* next = ASN1_TIME_adj(nullptr, std::time(nullptr), 30, 0);
    X509_CRL_set1_nextUpdate(crl, next);
    for (const std::string& name : revoked) {
        X509_REVOKED* entry = X509_REVOKED_new();
        ASN1_INTEGER* number = ASN1_INTEGER_new();
        ASN1_INTEGER_set(number, serials.at(name));
        X509_REVOKED_set_serialNumber(entry, number);
        X509_REVOKED_set_revocationDate(entry, now);
        X509_CRL_add0_revoked(crl, entry);
        ASN1_INTEGER_free(number);
    }
    X509_CRL_sort(crl);
    require(X509_CRL_sign(crl, ca_key, EVP_sha256()) > 0, "sign CRL");
    write_pem(root_ / "crl.pem", [&](BIO* out) { return PEM_write_bio_X509_CRL(out, crl); });
    ASN1_TIME_free(now);
    ASN1_TIME_free(next);
    X509_CRL_free(crl);
    X509_free(ca);
    X509_free(other_ca);
    EVP_PKEY_free(ca_key);
    EVP_PKEY_free(other_key);
}

}  // namespace keel::net::dds::testing
