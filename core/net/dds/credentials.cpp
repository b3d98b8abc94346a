#include "core/net/dds/credentials.hpp"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>
#include <openssl/x509v3.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

namespace keel::net::dds {

namespace {

template <class T, void (*Free)(T*)>
struct Deleter {
    void operator()(T* value) const { Free(value); }
};
using X509Ptr = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using KeyPtr = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using CrlPtr = std::unique_ptr<X509_CRL, Deleter<X509_CRL, X509_CRL_free>>;
using BioPtr = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using Pkcs7Ptr = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;
using StorePtr = std::unique_ptr<X509_STORE, Deleter<X509_STORE, X509_STORE_free>>;

std::optional<std::string> read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) return std::nullopt;
    return text.str();
}

BioPtr memory_bio(const std::string& text) {
    return BioPtr(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
}

std::string time_text(const ASN1_TIME* time) {
    BioPtr out(BIO_new(BIO_s_mem()));
    if (!out || ASN1_TIME_print(out.get(), time) != 1) return "an unreadable date";
    char* data = nullptr;
    const long size = BIO_get_mem_data(out.get(), &data);
    return std::string(data, static_cast<std::size_t>(size));
}

std::string name_text(const X509_NAME* name) {
    BioPtr out(BIO_new(BIO_s_mem()));
    if (!out || X509_NAME_print_ex(out.get(), name, 0, XN_FLAG_RFC2253) < 0) return "?";
    char* data = nullptr;
    const long size = BIO_get_mem_data(out.get(), &data);
    return std::string(data, static_cast<std::size_t>(size));
}


// A certificate's validity at `now`: nullopt when valid, else the sentence.
std::optional<std::string> validity_problem(const X509* cert, std::time_t now, const char* what) {
    std::time_t at = now;
    if (X509_cmp_time(X509_get0_notBefore(cert), &at) > 0) {
        return std::string(what) + " is not valid yet (valid from " +
               time_text(X509_get0_notBefore(cert)) + ")";
    }
    if (X509_cmp_time(X509_get0_notAfter(cert), &at) < 0) {
        return std::string(what) + " expired on " + time_text(X509_get0_notAfter(cert));
    }
    return std::nullopt;
}

// The text between <tag> and </tag>, first occurrence.
std::optional<std::string> element(const std::string& xml, const std::string& tag) {
    const std::string open = "<" + tag + ">";
    const std::string close = "</" + tag + ">";
    const std::size_t begin = xml.find(open);
    if (begin == std::string::npos) return std::nullopt;
    const std::size_t end = xml.find(close, begin + open.size());
    if (end == std::string::npos) return std::nullopt;
    std::string value = xml.substr(begin + open.size(), end - begin - open.size());
    const auto first = value.find_first_not_of(" \t\r\n");
    const auto last = value.find_last_not_of(" \t\r\n");
    return first == std::string::npos ? std::string() : value.substr(first, last - first + 1);
}

// Verifies an S/MIME document signed by `ca`; returns its signed content, or nullopt.
std::optional<std::string> verified_smime(const std::string& text, X509* ca) {
    BioPtr in = memory_bio(text);
    BIO* content_raw = nullptr;
    Pkcs7Ptr p7(SMIME_read_PKCS7(in.get(), &content_raw));
    BioPtr content(content_raw);
    if (!p7) return std::nullopt;
    StorePtr store(X509_STORE_new());
    if (!store || X509_STORE_add_cert(store.get(), ca) != 1) return std::nullopt;
    BioPtr out(BIO_new(BIO_s_mem()));
    // PKCS7_NOVERIFY skips the signer's chain check (the signer is the self-signed CA, which
    // has no purpose for S/MIME): the signature is verified, and the signer must be the CA.
    if (PKCS7_verify(p7.get(), nullptr, store.get(), content.get(), out.get(),
                     PKCS7_NOVERIFY | PKCS7_TEXT) != 1) {
        return std::nullopt;
    }
    STACK_OF(X509)* signers = PKCS7_get0_signers(p7.get(), nullptr, 0);
    bool by_ca = signers != nullptr && sk_X509_num(signers) == 1 &&
                 X509_cmp(sk_X509_value(signers, 0), ca) == 0;
    sk_X509_free(signers);
    if (!by_ca) return std::nullopt;
    char* data = nullptr;
    const long size = BIO_get_mem_data(out.get(), &data);
    return std::string(data, static_cast<std::size_t>(size));
}

// `now` as UTC YYYY-MM-DDTHH:MM:SS, the form the permissions documents' dates take.
std::string utc_text(std::time_t now) {
    char current[32];
    std::tm utc{};
    gmtime_r(&now, &utc);
    std::strftime(current, sizeof current, "%Y-%m-%dT%H:%M:%S", &utc);
    return current;
}

// `not_after` (UTC, YYYY-MM-DDTHH:MM:SS...) is before `now`: compared as text in one form.
bool expired_text(const std::string& not_after, std::time_t now) {
    return not_after.size() >= 19 && not_after.substr(0, 19) < utc_text(now);
}

std::string name_entry(const X509* cert, int nid) {
    const X509_NAME* subject = X509_get_subject_name(cert);
    const int index = X509_NAME_get_index_by_NID(subject, nid, -1);
    if (index < 0) return {};
    const ASN1_STRING* data = X509_NAME_ENTRY_get_data(X509_NAME_get_entry(subject, index));
    return std::string(reinterpret_cast<const char*>(ASN1_STRING_get0_data(data)),
                       static_cast<std::size_t>(ASN1_STRING_length(data)));
}

struct Checker {
    const SecurityFiles& files;
    std::time_t now;

    std::optional<CredentialProblem> problem;

    bool fail(const std::string& file, std::string message) {
        problem = CredentialProblem{file, std::move(message)};
        ERR_clear_error();
        return false;
    }
    bool read(const std::string& path, std::string& text) {
        if (path.empty()) return fail(path, "no file given");
        auto read = read_file(path);
        if (!read) return fail(path, "missing or unreadable");
        text = std::move(*read);
        return true;
    }
    // The CA's CRL (files.crl, when given) is a valid one and does not list `cert`.
    bool not_revoked(const X509* cert, EVP_PKEY* ca_key, const std::string& cert_path) {
        if (files.crl.empty()) return true;
        std::string text;
        if (!read(files.crl, text)) return false;
        BioPtr in = memory_bio(text);
        CrlPtr crl(PEM_read_bio_X509_CRL(in.get(), nullptr, nullptr, nullptr));
        if (!crl) return fail(files.crl, "not a PEM certificate revocation list");
        if (X509_CRL_verify(crl.get(), ca_key) != 1) {
            return fail(files.crl, "not signed by the identity CA " + files.identity_ca);
        }
        X509_REVOKED* revoked = nullptr;
        if (X509_CRL_get0_by_cert(crl.get(), &revoked, const_cast<X509*>(cert)) == 1) {
            return fail(cert_path, "was revoked on " +
                                       time_text(X509_REVOKED_get0_revocationDate(revoked)) + " (" +
                                       files.crl + ")");
        }
        return true;
    }
    bool certificate(const std::string& path, X509Ptr& cert) {
        std::string text;
        if (!read(path, text)) return false;
        BioPtr in = memory_bio(text);
        cert.reset(PEM_read_bio_X509(in.get(), nullptr, nullptr, nullptr));
        if (!cert) return fail(path, "not a PEM certificate");
        return true;
    }
};

}  // namespace

std::optional<CredentialProblem> check_credentials(const SecurityFiles& files,
                                                   std::string_view node_name, std::time_t now) {
    Checker check{files, now, std::nullopt};
    X509Ptr ca;
    X509Ptr cert;
    if (!check.certificate(files.identity_ca, ca)) return check.problem;
    if (auto why = validity_problem(ca.get(), now, "the identity CA certificate")) {
        check.fail(files.identity_ca, *why);
        return check.problem;
    }
    if (!check.certificate(files.identity_certificate, cert)) return check.problem;
    KeyPtr ca_key(X509_get_pubkey(ca.get()));
    if (!ca_key || X509_verify(cert.get(), ca_key.get()) != 1) {
        check.fail(files.identity_certificate,
                   "not signed by the identity CA " + files.identity_ca);
        return check.problem;
    }
    const std::string name = name_entry(cert.get(), NID_commonName);
    if (name != node_name) {
        check.fail(files.identity_certificate,
                   "is the identity of " + (name.empty() ? std::string("no node") : "'" + name + "'") +
                       ", not of node '" + std::string(node_name) + "'");
        return check.problem;
    }
    if (auto why = validity_problem(cert.get(), now, "the identity certificate")) {
        check.fail(files.identity_certificate, *why);
        return check.problem;
    }
    {
        std::string text;
        if (!check.read(files.private_key, text)) return check.problem;
        BioPtr in = memory_bio(text);
        KeyPtr key(PEM_read_bio_PrivateKey(in.get(), nullptr, nullptr, nullptr));
        if (!key) {
            check.fail(files.private_key, "not an unencrypted PEM private key");
            return check.problem;
        }
        if (X509_check_private_key(cert.get(), key.get()) != 1) {
            check.fail(files.private_key,
                       "does not belong to the certificate " + files.identity_certificate);
            return check.problem;
        }
    }
    if (!check.not_revoked(cert.get(), ca_key.get(), files.identity_certificate)) return check.problem;
    X509Ptr permissions_ca;
    if (!check.certificate(files.permissions_ca, permissions_ca)) return check.problem;
    {
        std::string text;
        if (!check.read(files.governance, text)) return check.problem;
        if (!verified_smime(text, permissions_ca.get())) {
            check.fail(files.governance,
                       "not an S/MIME document signed by the permissions CA " + files.permissions_ca);
            return check.problem;
        }
    }
    std::string text;
    if (!check.read(files.permissions, text)) return check.problem;
    const auto permissions = verified_smime(text, permissions_ca.get());
    if (!permissions) {
        check.fail(files.permissions,
                   "not an S/MIME document signed by the permissions CA " + files.permissions_ca);
        return check.problem;
    }
    const std::string subject = name_text(X509_get_subject_name(cert.get()));
    const auto granted = element(*permissions, "subject_name");
    if (!granted || *granted != subject) {
        check.fail(files.permissions, "grants " + (granted ? "'" + *granted + "'" : std::string("no subject")) +
                                          ", not this node's identity '" + subject + "'");
        return check.problem;
    }
    if (const auto not_after = element(*permissions, "not_after")) {
        if (expired_text(*not_after, now)) {
            check.fail(files.permissions, "expired on " + not_after->substr(0, 19) + " UTC");
            return check.problem;
        }
    }
    return std::nullopt;
}

namespace {

std::time_t asn1_time_t(const ASN1_TIME* time) {
    std::tm tm{};
    if (time == nullptr || ASN1_TIME_to_tm(time, &tm) != 1) return 0;
    return timegm(&tm);
}

std::time_t xml_time_t(const std::string& text) {
    std::tm tm{};
    if (text.size() < 19 || strptime(text.substr(0, 19).c_str(), "%Y-%m-%dT%H:%M:%S", &tm) == nullptr) return 0;
    return timegm(&tm);
}

}  // namespace

std::vector<CredentialExpiry> credential_expiries(const SecurityFiles& files,
                                                  const std::optional<OperatorFiles>& operator_files) {
    std::vector<CredentialExpiry> out;
    auto certificate = [&](const std::string& path, const char* what) {
        const auto text = read_file(path);
        if (!text) return;
        BioPtr in = memory_bio(*text);
        X509Ptr cert(PEM_read_bio_X509(in.get(), nullptr, nullptr, nullptr));
        if (cert) {
            out.push_back({path, what, asn1_time_t(X509_get0_notBefore(cert.get())),
                           asn1_time_t(X509_get0_notAfter(cert.get()))});
        }
    };
    auto grant = [&](const std::string& path, const char* what) {
        const auto text = read_file(path);
        if (!text) return;
        // The signature was checked at start (check_credentials, OperatorIdentity::load):
        // the date is read from the signed text as it is.
        const auto not_before = element(*text, "not_before");
        if (const auto not_after = element(*text, "not_after")) {
            out.push_back({path, what, not_before ? xml_time_t(*not_before) : 0, xml_time_t(*not_after)});
        }
    };
    certificate(files.identity_ca, "the identity CA certificate");
    certificate(files.identity_certificate, "the identity certificate");
    grant(files.permissions, "the permissions");
    if (!files.crl.empty()) {
        if (const auto text = read_file(files.crl)) {
            BioPtr in = memory_bio(*text);
            CrlPtr crl(PEM_read_bio_X509_CRL(in.get(), nullptr, nullptr, nullptr));
            if (crl && X509_CRL_get0_nextUpdate(crl.get()) != nullptr) {
                out.push_back({files.crl, "the CRL's next update", asn1_time_t(X509_CRL_get0_lastUpdate(crl.get())),
                               asn1_time_t(X509_CRL_get0_nextUpdate(crl.get()))});
            }
        }
    }
    if (operator_files) {
        certificate(operator_files->certificate, "the operator's certificate");
        grant(operator_files->permissions, "the operator's permissions");
    }
    std::erase_if(out, [](const CredentialExpiry& expiry) { return expiry.at == 0; });
    std::stable_sort(out.begin(), out.end(),
                     [](const CredentialExpiry& a, const CredentialExpiry& b) { return a.at < b.at; });
    return out;
}

OperatorFiles operator_files_in(const std::string& security_dir) {
    const std::filesystem::path dir = std::filesystem::absolute(security_dir) / "operator";
    return {(dir / "cert.pem").string(), (dir / "permissions.p7s").string()};
}

std::variant<OperatorIdentity, CredentialProblem> OperatorIdentity::load(const SecurityFiles& node,
                                                                         const OperatorFiles& files,
                                                                         std::time_t now) {
    Checker check{node, now, std::nullopt};
    X509Ptr ca;
    X509Ptr cert;
    X509Ptr own;
    if (!check.certificate(node.identity_ca, ca)) return *check.problem;
    if (!check.certificate(node.identity_certificate, own)) return *check.problem;
    if (!check.certificate(files.certificate, cert)) return *check.problem;
    KeyPtr ca_key(X509_get_pubkey(ca.get()));
    if (!ca_key || X509_verify(cert.get(), ca_key.get()) != 1) {
        check.fail(files.certificate, "not signed by the identity CA " + node.identity_ca);
        return *check.problem;
    }
    const std::string name = name_entry(cert.get(), NID_commonName);
    if (name != kOperatorCommonName) {
        check.fail(files.certificate, "is the identity of '" + name + "', not of the operator ('" +
                                          std::string(kOperatorCommonName) + "')");
        return *check.problem;
    }
    const std::string mission = name_entry(own.get(), NID_organizationalUnitName);
    if (name_entry(cert.get(), NID_organizationalUnitName) != mission) {
        check.fail(files.certificate, "is the operator of mission '" +
                                          name_entry(cert.get(), NID_organizationalUnitName) +
                                          "', not of this node's '" + mission + "'");
        return *check.problem;
    }
    if (auto why = validity_problem(cert.get(), now, "the operator's certificate")) {
        check.fail(files.certificate, *why);
        return *check.problem;
    }
    if (!check.not_revoked(cert.get(), ca_key.get(), files.certificate)) return *check.problem;
    std::string text;
    if (!check.read(files.permissions, text)) return *check.problem;
    X509Ptr permissions_ca;
    if (!check.certificate(node.permissions_ca, permissions_ca)) return *check.problem;
    const auto permissions = verified_smime(text, permissions_ca.get());
    if (!permissions) {
        check.fail(files.permissions,
                   "not an S/MIME document signed by the permissions CA " + node.permissions_ca);
        return *check.problem;
    }
    OperatorIdentity identity;
    identity.subject_ = name_text(X509_get_subject_name(cert.get()));
    const auto granted = element(*permissions, "subject_name");
    if (!granted || *granted != identity.subject_) {
        check.fail(files.permissions, "grants " + (granted ? "'" + *granted + "'" : std::string("no subject")) +
                                          ", not the operator's identity '" + identity.subject_ + "'");
        return *check.problem;
    }
    const auto not_after = element(*permissions, "not_after");
    if (!not_after || not_after->size() < 19) {
        check.fail(files.permissions, "states no not_after (YYYY-MM-DDTHH:MM:SS, UTC)");
        return *check.problem;
    }
    if (expired_text(*not_after, now)) {
        check.fail(files.permissions, "expired on " + not_after->substr(0, 19) + " UTC");
        return *check.problem;
    }
    const auto not_before = element(*permissions, "not_before");
    if (not_before && not_before->size() >= 19 && utc_text(now) < not_before->substr(0, 19)) {
        check.fail(files.permissions, "is not valid yet (valid from " + not_before->substr(0, 19) + " UTC)");
        return *check.problem;
    }
    const auto verbs = element(*permissions, "verbs");
    if (!verbs) {
        check.fail(files.permissions, "grants no <verbs>");
        return *check.problem;
    }
    std::istringstream words(*verbs);
    for (std::string verb; words >> verb;) identity.verbs_.insert(verb);
    identity.not_after_ = not_after->substr(0, 19);
    identity.certificate_ = std::shared_ptr<X509>(cert.release(), X509_free);
    identity.key_ = std::shared_ptr<EVP_PKEY>(X509_get_pubkey(identity.certificate_.get()), EVP_PKEY_free);
    if (!identity.key_) {
        check.fail(files.certificate, "holds no public key OpenSSL can read");
        return *check.problem;
    }
    return identity;
}

bool OperatorIdentity::verifies(std::string_view text, std::string_view signature) const {
    std::unique_ptr<EVP_MD_CTX, Deleter<EVP_MD_CTX, EVP_MD_CTX_free>> context(EVP_MD_CTX_new());
    const bool verified =
        context && key_ &&
        EVP_DigestVerifyInit(context.get(), nullptr, EVP_sha256(), nullptr, key_.get()) == 1 &&
        EVP_DigestVerify(context.get(), reinterpret_cast<const unsigned char*>(signature.data()),
                         signature.size(), reinterpret_cast<const unsigned char*>(text.data()),
                         text.size()) == 1;
    ERR_clear_error();
    return verified;
}

bool OperatorIdentity::permits(std::string_view verb) const {
    return verbs_.contains(std::string(verb));
}

std::optional<std::string> OperatorIdentity::expiry_problem(std::time_t now) const {
    if (auto why = validity_problem(certificate_.get(), now, "the operator's certificate")) return why;
    if (expired_text(not_after_, now)) return "the operator's permissions expired on " + not_after_ + " UTC";
    return std::nullopt;
}

}  // namespace keel::net::dds
