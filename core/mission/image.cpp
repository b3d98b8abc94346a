// The mission image loader (image.hpp): verify/keel_verify/image.py's `load_image` in C++.
//
//   read         at most 64 MiB                                (unreadable, over-limit)
//   parse        strict UTF-8 JSON, no duplicate keys           (not-json)
//   version      keel_image == 1                                (format-version)
//   hash         SHA-256 of the canonical re-encoding           (tampered)
//   signature    Ed25519, when a public key is configured       (unsigned, wrong-key,
//                                                                bad-signature)
//   schema       image.schema.json, integers where they belong  (schema)
//   consistency  names and ids                                  (inconsistent)
//   capacity     this runtime's and the image's own             (over-limit)
//   build        the Mission, then what the runtime relies on   (inconsistent)
//
// Each step throws a Refusal naming its reason; load_mission_image_bytes turns the first
// one into the LoadResult. Everything is checked before anything is built, so building
// reads the JSON without looking again.
#include "core/mission/image.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <limits>
#include <memory>
#include <new>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "core/mission/json_string.hpp"

namespace keel::mission {
namespace {

using Json = nlohmann::json;

// Python's int() reads integers of at most this many digits (sys.int_info's
// default_max_str_digits); json.loads refuses a longer one, and so does this loader.
constexpr std::size_t kMaxIntegerDigits = 4300;
// An integer token beyond 64 bits is kept as its digits, in a binary value of this subtype
// (JSON text never makes a binary value), so that the hash covers it exactly as Python's
// arbitrary-precision reader does.
constexpr std::uint8_t kBigIntegerSubtype = 0x49;
// A public key file is read up to this size (keel_verify.image._read_key_file).
constexpr std::size_t kMaxKeyFileBytes = 64 * 1024;
constexpr const char* kSignatureAlgorithm = "ed25519";
constexpr std::size_t kKeyIdHexDigits = 16;
// Shown values in schema messages are cut to this many bytes.
constexpr std::size_t kShownBytesMax = 60;

// Why an image is refused: thrown by a check, caught once in load_mission_image_bytes.
struct Refusal {
    Refusal() = default;
    Refusal(std::string reason_id, std::string text, int at_line = 1, int at_col = 1,
            std::string in_file = {})
        : reason(std::move(reason_id)),
          message(std::move(text)),
          line(at_line),
          col(at_col),
          file(std::move(in_file)) {}

    std::string reason;
    std::string message;
    int line = 1;
    int col = 1;
    std::string file;  // empty: the image's path
};

[[noreturn]] void refuse(std::string reason, std::string message) {
    throw Refusal{std::move(reason), std::move(message)};
}

// --------------------------------------------------------------------------------------
// Reading

class FileDescriptor {
public:
    explicit FileDescriptor(int fd) : fd_(fd) {}
    ~FileDescriptor() {
        if (fd_ >= 0) ::close(fd_);
    }
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    int get() const { return fd_; }

private:
    int fd_;
};

// At most `limit + 1` bytes of the file (one more than the limit tells the caller it is
// over), or the errno of the failure.
std::pair<std::string, int> read_bounded(const std::string& path, std::size_t limit) {
    FileDescriptor file(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (file.get() < 0) return {{}, errno};
    std::string bytes;
    char buffer[65536];
    while (bytes.size() <= limit) {
        const std::size_t want = std::min(sizeof buffer, limit + 1 - bytes.size());
        const ssize_t n = ::read(file.get(), buffer, want);
        if (n < 0) {
            if (errno == EINTR) continue;
            return {{}, errno};
        }
        if (n == 0) break;
        bytes.append(buffer, static_cast<std::size_t>(n));
    }
    return {std::move(bytes), 0};
}

std::string read_image(const std::string& path) {
    auto [bytes, error] = read_bounded(path, kMaxImageBytes);
    if (error != 0) refuse("unreadable", std::string("cannot read: ") + std::strerror(error));
    if (bytes.size() > kMaxImageBytes) {
        refuse("over-limit", "the file is larger than " +
                                 std::to_string(kMaxImageBytes / (1024 * 1024)) + " MiB");
    }
    return std::move(bytes);
}

// --------------------------------------------------------------------------------------
// Parsing

// The offset of the first byte that is not part of well-formed UTF-8 (Python's decoder:
// no overlong forms, no surrogates, nothing above U+10FFFF), or nullopt.
std::optional<std::size_t> first_invalid_utf8(std::string_view text) {
    std::size_t i = 0;
    while (i < text.size()) {
        const auto lead = static_cast<unsigned char>(text[i]);
        if (lead < 0x80) {
            ++i;
            continue;
        }
        std::size_t length = 0;
        unsigned char low = 0x80;
        unsigned char high = 0xBF;
        if (lead >= 0xC2 && lead <= 0xDF) {
            length = 2;
        } else if (lead >= 0xE0 && lead <= 0xEF) {
            length = 3;
            if (lead == 0xE0) low = 0xA0;
            if (lead == 0xED) high = 0x9F;
        } else if (lead >= 0xF0 && lead <= 0xF4) {
            length = 4;
            if (lead == 0xF0) low = 0x90;
            if (lead == 0xF4) high = 0x8F;
        } else {
            return i;
        }
        if (i + length > text.size()) return i;
        const auto second = static_cast<unsigned char>(text[i + 1]);
        if (second < low || second > high) return i;
        for (std::size_t k = 2; k < length; ++k) {
            if ((static_cast<unsigned char>(text[i + k]) & 0xC0) != 0x80) return i;
        }
        i += length;
    }
    return std::nullopt;
}

// Line and column (in characters, 1-based) of a byte offset, as Python's decoder counts.
std::pair<int, int> line_and_column(std::string_view text, std::size_t offset) {
    offset = std::min(offset, text.size());
    int line = 1;
    std::size_t line_start = 0;
    for (std::size_t i = 0; i < offset; ++i) {
        if (text[i] == '\n') {
            ++line;
            line_start = i + 1;
        }
    }
    int column = 1;
    for (std::size_t i = line_start; i < offset; ++i) {
        if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80) ++column;
    }
    return {line, column};
}

bool is_integer_token(const std::string& token) {
    return token.find_first_of(".eE") == std::string::npos;
}

// nlohmann-json's SAX events to a document, refusing what json.loads (with the image
// loader's hooks) refuses: duplicate keys, integers of more digits than Python reads,
// and nesting deeper than kMaxImageDepth. Integers beyond 64 bits keep their digits.
class DocumentBuilder {
public:
    using number_integer_t = Json::number_integer_t;
    using number_unsigned_t = Json::number_unsigned_t;
    using number_float_t = Json::number_float_t;
    using string_t = Json::string_t;
    using binary_t = Json::binary_t;

    Json root;
    std::string error;                      // why parsing stopped; empty while it goes on
    std::optional<std::size_t> error_offset;  // byte offset of a syntax error

    bool null() { return add(Json(nullptr)); }
    bool boolean(bool value) { return add(Json(value)); }
    bool number_integer(number_integer_t value) { return add(Json(value)); }
    bool number_unsigned(number_unsigned_t value) { return add(Json(value)); }
    bool number_float(number_float_t value, const string_t& token) {
        if (!is_integer_token(token)) return add(Json(value));
        const std::size_t digits = token.size() - (token[0] == '-' ? 1 : 0);
        if (digits > kMaxIntegerDigits) {
            return fail("an integer of " + std::to_string(digits) + " digits (at most " +
                        std::to_string(kMaxIntegerDigits) + ")");
        }
        return add(Json::binary(std::vector<std::uint8_t>(token.begin(), token.end()),
                                kBigIntegerSubtype));
    }
    bool string(string_t& value) { return add(Json(std::move(value))); }
    bool binary(binary_t&) { return fail("binary data is not JSON"); }
    bool start_object(std::size_t) { return open(Json::object()); }
    bool key(string_t& name) {
        const Json::object_t& object = open_.back()->get_ref<const Json::object_t&>();
        if (object.count(name) != 0) {
            // Two JSON readers may keep different ones of two equal keys.
            return fail("duplicate key '" + name + "'");
        }
        key_ = std::move(name);
        return true;
    }
    bool end_object() { return close(); }
    bool start_array(std::size_t) { return open(Json::array()); }
    bool end_array() { return close(); }
    bool parse_error(std::size_t position, const std::string&,
                     const nlohmann::detail::exception& exception) {
        // "[json.exception.parse_error.101] parse error at line 1, column 2: syntax error
        // while parsing value - invalid literal; last read: '{x'": keep the description (the
        // position is reported as Python reports it, from `position`).
        std::string text = exception.what();
        const std::size_t bracket = text.find("] ");
        if (bracket != std::string::npos) text = text.substr(bracket + 2);
        if (text.rfind("parse error at line ", 0) == 0) {
            const std::size_t described = text.find(": ");
            if (described != std::string::npos) text = text.substr(described + 2);
        }
        error_offset = position > 0 ? position - 1 : 0;
        error = text;
        return false;
    }

private:
    std::vector<Json*> open_;  // the containers being filled, outermost first
    std::string key_;

    bool fail(std::string message) {
        error = std::move(message);
        return false;
    }

    Json* add(Json&& value) {
        if (open_.empty()) {
            root = std::move(value);
            return &root;
        }
        Json& parent = *open_.back();
        if (parent.is_array()) {
            parent.get_ref<Json::array_t&>().push_back(std::move(value));
            return &parent.get_ref<Json::array_t&>().back();
        }
        auto& object = parent.get_ref<Json::object_t&>();
        return &object.emplace(std::move(key_), std::move(value)).first->second;
    }

    bool open(Json&& container) {
        if (open_.size() >= kMaxImageDepth) {
            return fail("nested more than " + std::to_string(kMaxImageDepth) + " levels deep");
        }
        open_.push_back(add(std::move(container)));
        return true;
    }

    bool close() {
        open_.pop_back();
        return true;
    }
};

Json parse(std::string_view bytes) {
    if (const auto bad = first_invalid_utf8(bytes)) {
        refuse("not-json", "not UTF-8 text (byte " + std::to_string(*bad) + ")");
    }
    if (bytes.substr(0, 3) == "\xEF\xBB\xBF") {
        // nlohmann-json would skip it; json.loads refuses it.
        refuse("not-json", "line 1 column 1: Unexpected UTF-8 BOM (decode using utf-8-sig)");
    }
    DocumentBuilder builder;
    const bool parsed = Json::sax_parse(bytes.begin(), bytes.end(), &builder,
                                        Json::input_format_t::json, /*strict=*/true,
                                        /*ignore_comments=*/false);
    if (!parsed || !builder.error.empty()) {
        const std::string what = builder.error.empty() ? "not JSON" : builder.error;
        if (!builder.error_offset) refuse("not-json", what);  // e.g. a duplicate key
        const auto [line, column] = line_and_column(bytes, *builder.error_offset);
        throw Refusal{"not-json",
                      "line " + std::to_string(line) + " column " + std::to_string(column) +
                          ": " + what,
                      line, column};
    }
    return std::move(builder.root);
}

// --------------------------------------------------------------------------------------
// Canonical encoding

void append_integer(std::string& out, auto value) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    out.append(buffer, result.ptr);
}

void encode(const Json& value, std::string& out);

// An object's members in key order (the map's: bytewise, which for UTF-8 is code-point
// order, as Python's sort_keys), skipping the keys in `skip`.
void encode_object(const Json::object_t& object, std::string& out,
                   std::initializer_list<std::string_view> skip = {}) {
    out += '{';
    bool first = true;
    for (const auto& [key, member] : object) {
        if (std::find(skip.begin(), skip.end(), key) != skip.end()) continue;
        if (!first) out += ',';
        first = false;
        append_json_string(out, key);
        out += ':';
        encode(member, out);
    }
    out += '}';
}

void encode(const Json& value, std::string& out) {
    switch (value.type()) {
        case Json::value_t::null:
            out += "null";
            return;
        case Json::value_t::boolean:
            out += value.get<bool>() ? "true" : "false";
            return;
        case Json::value_t::number_integer:
            append_integer(out, value.get<std::int64_t>());
            return;
        case Json::value_t::number_unsigned:
            append_integer(out, value.get<std::uint64_t>());
            return;
        case Json::value_t::number_float:
            out += canonical_float(value.get<double>());
            return;
        case Json::value_t::string:
            append_json_string(out, value.get_ref<const std::string&>());
            return;
        case Json::value_t::binary: {  // an integer beyond 64 bits: its digits
            const auto& digits = value.get_binary();
            out.append(digits.begin(), digits.end());
            return;
        }
        case Json::value_t::array: {
            out += '[';
            bool first = true;
            for (const Json& item : value.get_ref<const Json::array_t&>()) {
                if (!first) out += ',';
                first = false;
                encode(item, out);
            }
            out += ']';
            return;
        }
        case Json::value_t::object:
            encode_object(value.get_ref<const Json::object_t&>(), out);
            return;
        case Json::value_t::discarded:
            return;  // the parser keeps nothing discarded
    }
}

std::string canonical(const Json& value) {
    std::string out;
    encode(value, out);
    return out;
}

// A value as messages show it: its canonical encoding, cut short.
std::string shown(const Json& value) {
    std::string text = canonical(value);
    if (text.size() > kShownBytesMax) {
        std::size_t cut = kShownBytesMax;
        while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
        text = text.substr(0, cut) + "...";
    }
    return text;
}

// --------------------------------------------------------------------------------------
// Hash and signature

std::string hex(const unsigned char* bytes, std::size_t size) {
    static const char digits[] = "0123456789abcdef";
    std::string out;
    out.reserve(size * 2);
    for (std::size_t i = 0; i < size; ++i) {
        out += digits[bytes[i] >> 4];
        out += digits[bytes[i] & 0x0F];
    }
    return out;
}

std::string sha256_hex(std::string_view bytes) {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned int size = 0;
    if (EVP_Digest(bytes.data(), bytes.size(), digest, &size, EVP_sha256(), nullptr) != 1) {
        ERR_clear_error();
        refuse("tampered", "cannot compute SHA-256 (OpenSSL refused)");
    }
    return hex(digest, size);
}

// The bytes the hash and the signature cover: the image without sha256 and signature.
std::string hashed_bytes(const Json& image) {
    std::string out;
    encode_object(image.get_ref<const Json::object_t&>(), out, {"sha256", "signature"});
    return out;
}

struct KeyDeleter {
    void operator()(EVP_PKEY* key) const { EVP_PKEY_free(key); }
};
struct BioDeleter {
    void operator()(BIO* bio) const { BIO_free(bio); }
};
struct DigestContextDeleter {
    void operator()(EVP_MD_CTX* context) const { EVP_MD_CTX_free(context); }
};

struct PublicKey {
    std::unique_ptr<EVP_PKEY, KeyDeleter> key;
    std::string key_id;  // first 16 hex digits of the SHA-256 of the raw 32-byte key
};

[[noreturn]] void refuse_key(const std::string& path, std::string message) {
    ERR_clear_error();
    throw Refusal{"public-key", std::move(message), 1, 1, path};
}

PublicKey load_public_key(const std::string& path) {
    auto [data, error] = read_bounded(path, kMaxKeyFileBytes);
    if (error != 0) refuse_key(path, std::string("cannot read: ") + std::strerror(error));
    std::unique_ptr<BIO, BioDeleter> bio(
        BIO_new_mem_buf(data.data(), static_cast<int>(data.size())));
    if (!bio) refuse_key(path, "cannot read the key (OpenSSL refused)");
    PublicKey result;
    result.key.reset(PEM_read_bio_PUBKEY(bio.get(), nullptr, nullptr, nullptr));
    if (!result.key) {
        const bool is_private = data.find("PRIVATE KEY") != std::string::npos;
        refuse_key(path, std::string("not a PEM public key") +
                             (is_private ? " (this file holds a private key)" : "") +
                             "; make one with: openssl pkey -in mission.key -pubout -out "
                             "mission.pub");
    }
    if (EVP_PKEY_get_id(result.key.get()) != EVP_PKEY_ED25519) {
        refuse_key(path, "not an Ed25519 public key (mission images are signed with Ed25519)");
    }
    unsigned char raw[32];
    std::size_t raw_size = sizeof raw;
    if (EVP_PKEY_get_raw_public_key(result.key.get(), raw, &raw_size) != 1 ||
        raw_size != sizeof raw) {
        refuse_key(path, "cannot read the Ed25519 key's raw bytes");
    }
    result.key_id = sha256_hex({reinterpret_cast<const char*>(raw), raw_size})
                        .substr(0, kKeyIdHexDigits);
    return result;
}

// Strict base64 (RFC 4648 alphabet, padded to a multiple of four), or nullopt.
std::optional<std::string> base64_decode(std::string_view text) {
    if (text.size() % 4 != 0) return std::nullopt;
    auto value = [](char c) -> int {
        if (c >= 'A' && c <= 'Z') return c - 'A';
        if (c >= 'a' && c <= 'z') return c - 'a' + 26;
        if (c >= '0' && c <= '9') return c - '0' + 52;
        if (c == '+') return 62;
        if (c == '/') return 63;
        return -1;
    };
    std::string out;
    out.reserve(text.size() / 4 * 3);
    for (std::size_t i = 0; i < text.size(); i += 4) {
        const bool last = i + 4 == text.size();
        const int padding = last ? (text[i + 3] == '=' ? (text[i + 2] == '=' ? 2 : 1) : 0) : 0;
        std::uint32_t group = 0;
        for (std::size_t k = 0; k < 4; ++k) {
            const int v = k >= 4 - static_cast<std::size_t>(padding) ? 0 : value(text[i + k]);
            if (v < 0) return std::nullopt;
            group = (group << 6) | static_cast<std::uint32_t>(v);
        }
        out += static_cast<char>((group >> 16) & 0xFF);
        if (padding < 2) out += static_cast<char>((group >> 8) & 0xFF);
        if (padding < 1) out += static_cast<char>(group & 0xFF);
    }
    return out;
}

bool ed25519_verifies(const PublicKey& key, std::string_view signature, std::string_view message) {
    std::unique_ptr<EVP_MD_CTX, DigestContextDeleter> context(EVP_MD_CTX_new());
    const bool verified =
        context &&
        EVP_DigestVerifyInit(context.get(), nullptr, nullptr, nullptr, key.key.get()) == 1 &&
        EVP_DigestVerify(context.get(), reinterpret_cast<const unsigned char*>(signature.data()),
                         signature.size(), reinterpret_cast<const unsigned char*>(message.data()),
                         message.size()) == 1;
    ERR_clear_error();
    return verified;
}

const Json* member(const Json& object, std::string_view key) {
    if (!object.is_object()) return nullptr;
    const auto& map = object.get_ref<const Json::object_t&>();
    const auto found = map.find(std::string(key));
    return found == map.end() ? nullptr : &found->second;
}

// --------------------------------------------------------------------------------------
// The checks before the schema, in image.py's order

void check_version(const Json& image) {
    const Json* version = member(image, "keel_image");
    if (version == nullptr) {
        refuse("format-version", "not a Keel mission image (no keel_image field at the top)");
    }
    // An integer token 1: not 1.0, not true (Python: type(version) is int).
    const bool one =
        version->is_number_integer() && version->get<std::int64_t>() == kImageFormatVersion;
    if (!one) {
        refuse("format-version", "image format " + shown(*version) + "; this loader reads format " +
                                     std::to_string(kImageFormatVersion) +
                                     " (compile the mission again with the keel-verify that "
                                     "matches this runtime)");
    }
}

void check_hash(const Json& image, const std::string& computed) {
    const Json* recorded = member(image, "sha256");
    if (recorded == nullptr || !recorded->is_string()) {
        refuse("tampered", "the image carries no sha256 of its content");
    }
    const std::string& text = recorded->get_ref<const std::string&>();
    if (text != computed) {
        refuse("tampered", "sha256 mismatch: the image records " + text +
                               " but its content hashes to " + computed +
                               "; it was changed after it was compiled");
    }
}

void check_signature(const Json& image, std::string_view hashed, const PublicKey& key) {
    const Json* signature = member(image, "signature");
    if (signature == nullptr || signature->is_null()) {
        refuse("unsigned", "the image is not signed, and a public key (key id " + key.key_id +
                               ") was given");
    }
    const Json* algorithm = member(*signature, "alg");
    if (algorithm == nullptr || !algorithm->is_string() ||
        algorithm->get_ref<const std::string&>() != kSignatureAlgorithm) {
        refuse("bad-signature", std::string("the signature is not an ") + kSignatureAlgorithm +
                                    " signature object");
    }
    const Json* key_id = member(*signature, "key_id");
    if (key_id == nullptr || !key_id->is_string() ||
        key_id->get_ref<const std::string&>() != key.key_id) {
        refuse("wrong-key", "signed with key id " + (key_id == nullptr ? "None" : shown(*key_id)) +
                                ", but the public key given has key id " + key.key_id);
    }
    const Json* value = member(*signature, "value");
    const std::optional<std::string> bytes =
        value != nullptr && value->is_string()
            ? base64_decode(value->get_ref<const std::string&>())
            : std::nullopt;
    if (!bytes) refuse("bad-signature", "the signature value is not base64");
    if (!ed25519_verifies(key, *bytes, hashed)) {
        refuse("bad-signature",
               "the Ed25519 signature does not verify with key id " + key.key_id);
    }
}

// --------------------------------------------------------------------------------------
// Schema: config/schema/image.schema.json, keyword by keyword. Integers are integer
// tokens of 64 bits (a float where an integer belongs is refused, as image.py's float
// check refuses it; a wider integer is more than this runtime holds).

enum class Text { any, non_empty, name, version, sha256, key_id, signature };

bool matches(std::string_view text, Text rule) {
    auto all = [&](std::string_view part, auto allowed) {
        return std::all_of(part.begin(), part.end(), allowed);
    };
    auto digit = [](char c) { return c >= '0' && c <= '9'; };
    auto lower_hex = [&](char c) { return digit(c) || (c >= 'a' && c <= 'f'); };
    auto letter = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); };
    switch (rule) {
        case Text::any:
            return true;
        case Text::non_empty:
            return !text.empty();
        case Text::name:  // ^[A-Za-z][A-Za-z0-9_-]{0,62}$
            return !text.empty() && text.size() <= 63 && letter(text[0]) &&
                   all(text.substr(1), [&](char c) {
                       return letter(c) || digit(c) || c == '_' || c == '-';
                   });
        case Text::version: {  // ^[0-9]+\.[0-9]+\.[0-9]+$
            const std::size_t first = text.find('.');
            const std::size_t second =
                first == std::string_view::npos ? first : text.find('.', first + 1);
            if (second == std::string_view::npos) return false;
            const std::string_view parts[] = {text.substr(0, first),
                                              text.substr(first + 1, second - first - 1),
                                              text.substr(second + 1)};
            return std::all_of(std::begin(parts), std::end(parts), [&](std::string_view part) {
                return !part.empty() && all(part, digit);
            });
        }
        case Text::sha256:
            return text.size() == 64 && all(text, lower_hex);
        case Text::key_id:
            return text.size() == kKeyIdHexDigits && all(text, lower_hex);
        case Text::signature:  // ^[A-Za-z0-9+/]{86}==$
            return text.size() == 88 && text.substr(86) == "==" &&
                   all(text.substr(0, 86),
                       [&](char c) { return letter(c) || digit(c) || c == '+' || c == '/'; });
    }
    return false;
}

const char* pattern_of(Text rule) {
    switch (rule) {
        case Text::name:
            return "^[A-Za-z][A-Za-z0-9_-]{0,62}$";
        case Text::version:
            return "^[0-9]+\\.[0-9]+\\.[0-9]+$";
        case Text::sha256:
            return "^[0-9a-f]{64}$";
        case Text::key_id:
            return "^[0-9a-f]{16}$";
        case Text::signature:
            return "^[A-Za-z0-9+/]{86}==$";
        case Text::any:
        case Text::non_empty:
            break;
    }
    return "";
}

struct Range {
    std::optional<std::int64_t> minimum;
    std::optional<std::int64_t> maximum;
};

class SchemaCheck {
public:
    struct Error {
        std::vector<std::string> path;
        std::string message;
    };
    std::vector<Error> errors;

    void image(const Json& image) {
        if (!object(image, {"keel_image", "mission", "verifier", "source", "proof", "capacity",
                            "content", "sha256"},
                    {"signature"})) {
            return;
        }
        in(image, "keel_image", [&](const Json& v) { constant_one(v); });
        in(image, "mission", [&](const Json& v) { string(v, Text::non_empty); });
        in(image, "verifier", [&](const Json& v) { string(v, Text::version); });
        in(image, "source", [&](const Json& source) {
            if (!object(source, {"file", "sha256"})) return;
            in(source, "file", [&](const Json& v) { string(v, Text::non_empty); });
            in(source, "sha256", [&](const Json& v) { string(v, Text::sha256); });
        });
        in(image, "proof", [&](const Json& proof) { this->proof(proof); });
        in(image, "capacity", [&](const Json& capacity) {
            if (!object(capacity, {"max_nodes", "max_tasks"})) return;
            in(capacity, "max_nodes", [&](const Json& v) { integer(v, {1, {}}); });
            in(capacity, "max_tasks", [&](const Json& v) { integer(v, {1, {}}); });
        });
        in(image, "content", [&](const Json& content) { this->content(content); });
        in(image, "sha256", [&](const Json& v) { string(v, Text::sha256); });
        in(image, "signature", [&](const Json& signature) {
            if (!object(signature, {"alg", "key_id", "value"})) return;
            in(signature, "alg", [&](const Json& v) {
                if (!v.is_string() || v.get_ref<const std::string&>() != kSignatureAlgorithm) {
                    error(shown(v) + " is not \"" + kSignatureAlgorithm + "\"");
                }
            });
            in(signature, "key_id", [&](const Json& v) { string(v, Text::key_id); });
            in(signature, "value", [&](const Json& v) { string(v, Text::signature); });
        });
    }

private:
    std::vector<std::string> path_;

    void error(std::string message) {
        std::string where;
        for (const std::string& part : path_) where += (where.empty() ? "" : ".") + part;
        if (where.empty()) where = "the image";
        errors.push_back({path_, where + ": " + std::move(message)});
    }

    // Runs `check` on object[key] with the path extended, when the member is there.
    template <typename Check>
    void in(const Json& object, std::string_view key, Check check) {
        const Json* value = member(object, key);
        if (value == nullptr) return;
        path_.emplace_back(key);
        check(*value);
        path_.pop_back();
    }

    template <typename Check>
    void each(const Json& array, Check check) {
        const auto& items = array.get_ref<const Json::array_t&>();
        for (std::size_t i = 0; i < items.size(); ++i) {
            path_.push_back(std::to_string(i));
            check(items[i]);
            path_.pop_back();
        }
    }

    // type object, required members, no others (`optional` are allowed too).
    bool object(const Json& value, std::initializer_list<const char*> required,
                std::initializer_list<const char*> optional = {}) {
        if (!value.is_object()) {
            error(shown(value) + " is not of type \"object\"");
            return false;
        }
        for (const char* key : required) {
            if (member(value, key) == nullptr) {
                error("\"" + std::string(key) + "\" is a required property");
            }
        }
        for (const auto& [key, unused] : value.get_ref<const Json::object_t&>()) {
            auto same = [&](const char* known) { return key == known; };
            if (std::none_of(required.begin(), required.end(), same) &&
                std::none_of(optional.begin(), optional.end(), same)) {
                std::string quoted;
                append_json_string(quoted, key);
                error("Additional properties are not allowed (" + quoted + " was unexpected)");
            }
        }
        return true;
    }

    bool array(const Json& value, std::size_t min_items = 0) {
        if (!value.is_array()) {
            error(shown(value) + " is not of type \"array\"");
            return false;
        }
        if (value.size() < min_items) error(shown(value) + " should be non-empty");
        return true;
    }

    void integer(const Json& value, Range range) {
        if (value.is_binary()) {
            error(shown(value) + " is beyond the 64-bit integers this loader holds");
            return;
        }
        if (value.is_number_float()) {
            const double number = value.get<double>();
            error(shown(value) + (std::trunc(number) == number
                                      ? " is a float where an integer is expected"
                                      : " is not of type \"integer\""));
            return;
        }
        if (!value.is_number_integer()) {
            error(shown(value) + " is not of type \"integer\"");
            return;
        }
        if (value.is_number_unsigned() &&
            value.get<std::uint64_t>() >
                static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
            error(shown(value) + " is beyond the 64-bit integers this loader holds");
            return;
        }
        const std::int64_t number = value.get<std::int64_t>();
        if (range.minimum && number < *range.minimum) {
            error(shown(value) + " is less than the minimum of " + std::to_string(*range.minimum));
        }
        if (range.maximum && number > *range.maximum) {
            error(shown(value) + " is greater than the maximum of " +
                  std::to_string(*range.maximum));
        }
    }

    void nullable_integer(const Json& value, Range range) {
        if (!value.is_null()) integer(value, range);
    }

    void number(const Json& value, bool nullable) {
        if (nullable && value.is_null()) return;
        if (value.is_binary()) {
            error(shown(value) + " is beyond the 64-bit integers this loader holds");
        } else if (value.is_number_unsigned() &&
                   value.get<std::uint64_t>() >
                       static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
            error(shown(value) + " is beyond the 64-bit integers this loader holds");
        } else if (!value.is_number()) {
            error(shown(value) + (nullable ? " is not of types \"number\", \"null\""
                                           : " is not of type \"number\""));
        }
    }

    void boolean(const Json& value) {
        if (!value.is_boolean()) error(shown(value) + " is not of type \"boolean\"");
    }

    void string(const Json& value, Text rule) {
        if (!value.is_string()) {
            error(shown(value) + " is not of type \"string\"");
            return;
        }
        const std::string& text = value.get_ref<const std::string&>();
        if (rule == Text::non_empty && text.empty()) {
            error("\"\" should be non-empty");
        } else if (!matches(text, rule)) {
            error(shown(value) + " does not match \"" + pattern_of(rule) + "\"");
        }
    }

    void names(const Json& value) {
        if (!array(value)) return;
        each(value, [&](const Json& item) { string(item, Text::name); });
    }

    void constant_one(const Json& value) {
        if (!(value.is_number_integer() && value.get<std::int64_t>() == 1)) {
            error("1 was expected, not " + shown(value));
        }
    }

    void one_of(const Json& value, std::initializer_list<const char*> allowed, bool nullable) {
        if (nullable && value.is_null()) return;
        if (value.is_string()) {
            const std::string& text = value.get_ref<const std::string&>();
            for (const char* option : allowed) {
                if (text == option) return;
            }
        }
        std::string options;
        for (const char* option : allowed) {
            options += (options.empty() ? "\"" : ", \"") + std::string(option) + "\"";
        }
        error(shown(value) + " is not one of [" + options + (nullable ? ", null]" : "]"));
    }

    // propertyNames: $defs/name
    void property_names(const Json& object) {
        for (const auto& [key, unused] : object.get_ref<const Json::object_t&>()) {
            if (!matches(key, Text::name)) {
                std::string quoted;
                append_json_string(quoted, key);
                error(quoted + " does not match \"" + pattern_of(Text::name) + "\"");
            }
        }
    }

    void params(const Json& value) {
        if (!value.is_object()) {
            error(shown(value) + " is not of type \"object\"");
            return;
        }
        property_names(value);
        for (const auto& [key, item] : value.get_ref<const Json::object_t&>()) {
            path_.push_back(key);
            if (!item.is_string() && !item.is_boolean()) number(item, false);
            path_.pop_back();
        }
    }

    void proof(const Json& proof) {
        if (!object(proof, {"result", "max_failures", "depth", "node_failures", "tolerance_nodes",
                            "phases", "configurations", "levels", "states_bound"})) {
            return;
        }
        in(proof, "result", [&](const Json& v) { one_of(v, {"proved"}, false); });
        in(proof, "max_failures", [&](const Json& v) { nullable_integer(v, {0, {}}); });
        for (const char* count : {"depth", "node_failures", "tolerance_nodes", "phases",
                                  "configurations", "levels", "states_bound"}) {
            in(proof, count, [&](const Json& v) { integer(v, {0, {}}); });
        }
    }

    void content(const Json& content) {
        if (!object(content,
                    {"mission", "schema", "heartbeat", "tolerance", "nodes", "tasks", "phases"},
                    {"revision"})) {
            return;
        }
        in(content, "mission", [&](const Json& v) { string(v, Text::non_empty); });
        in(content, "schema", [&](const Json& v) { constant_one(v); });
        in(content, "revision", [&](const Json& v) { integer(v, {0, 2147483647}); });
        in(content, "heartbeat", [&](const Json& heartbeat) {
            if (!object(heartbeat, {"period_ms", "miss_limit", "startup_grace_ms"},
                        {"tie_grace"})) {
                return;
            }
            in(heartbeat, "period_ms", [&](const Json& v) { integer(v, {1, 600000}); });
            in(heartbeat, "miss_limit", [&](const Json& v) { integer(v, {1, 1000}); });
            in(heartbeat, "startup_grace_ms", [&](const Json& v) { integer(v, {0, 3600000}); });
            in(heartbeat, "tie_grace", [&](const Json& v) { integer(v, {0, 1000}); });
        });
        in(content, "tolerance", [&](const Json& tolerance) {
            if (!object(tolerance, {"node_failures", "nodes"})) return;
            in(tolerance, "node_failures", [&](const Json& v) { integer(v, {0, 64}); });
            in(tolerance, "nodes", [&](const Json& v) { names(v); });
        });
        in(content, "nodes", [&](const Json& nodes) {
            if (array(nodes, 1)) each(nodes, [&](const Json& node) { this->node(node); });
        });
        in(content, "tasks", [&](const Json& tasks) {
            if (array(tasks)) each(tasks, [&](const Json& task) { this->task(task); });
        });
        in(content, "phases", [&](const Json& phases) {
            if (array(phases, 1)) each(phases, [&](const Json& phase) { this->phase(phase); });
        });
    }

    void resources(const Json& value, bool nullable) {
        if (!object(value, {"cpu", "mem_mb"})) return;
        for (const char* key : {"cpu", "mem_mb"}) {
            in(value, key, [&](const Json& v) {
                if (nullable) {
                    nullable_integer(v, {0, {}});
                } else {
                    integer(v, {0, {}});
                }
            });
        }
    }

    void node(const Json& node) {
        if (!object(node, {"id", "name", "kind", "role", "capabilities", "capacity"})) return;
        in(node, "id", [&](const Json& v) { integer(v, {0, {}}); });
        in(node, "name", [&](const Json& v) { string(v, Text::name); });
        in(node, "kind", [&](const Json& v) { one_of(v, {"processing", "interface"}, false); });
        in(node, "role", [&](const Json& v) { one_of(v, {"storage", "interface"}, true); });
        in(node, "capabilities", [&](const Json& v) { names(v); });
        in(node, "capacity", [&](const Json& v) { resources(v, true); });
    }

    void task(const Json& task) {
        if (!object(task, {"id", "name", "port", "component", "requires", "load", "essential",
                           "checkpoint", "inputs", "period_ms", "health", "params"},
                    {"max_sample_bytes", "max_state_bytes", "priority", "group"})) {
            return;
        }
        in(task, "id", [&](const Json& v) { integer(v, {0, {}}); });
        in(task, "name", [&](const Json& v) { string(v, Text::name); });
        in(task, "port", [&](const Json& v) { integer(v, {1, 65535}); });
        in(task, "component", [&](const Json& v) { string(v, Text::name); });
        in(task, "requires", [&](const Json& v) { names(v); });
        in(task, "load", [&](const Json& v) { resources(v, false); });
        in(task, "essential", [&](const Json& v) { boolean(v); });
        in(task, "checkpoint", [&](const Json& v) { boolean(v); });
        in(task, "inputs", [&](const Json& v) { names(v); });
        in(task, "period_ms", [&](const Json& v) { nullable_integer(v, {1, 600000}); });
        in(task, "health", [&](const Json& health) {
            if (health.is_null() || !object(health, {"min", "max", "deadline_ms"})) return;
            in(health, "min", [&](const Json& v) { number(v, true); });
            in(health, "max", [&](const Json& v) { number(v, true); });
            in(health, "deadline_ms", [&](const Json& v) { nullable_integer(v, {1, 600000}); });
        });
        in(task, "params", [&](const Json& v) { params(v); });
        in(task, "max_sample_bytes", [&](const Json& v) { integer(v, {1, 67108844}); });
        in(task, "max_state_bytes", [&](const Json& v) { integer(v, {0, 16777204}); });
        in(task, "priority", [&](const Json& v) { integer(v, {0, 1000000}); });
        in(task, "group", [&](const Json& v) { string(v, Text::name); });
    }

    void configuration(const Json& configuration) {
        if (!object(configuration, {"name", "master", "observers", "tasks"})) return;
        in(configuration, "name", [&](const Json& v) { string(v, Text::name); });
        in(configuration, "master", [&](const Json& v) { string(v, Text::name); });
        in(configuration, "observers", [&](const Json& v) { names(v); });
        in(configuration, "tasks", [&](const Json& placements) {
            if (!array(placements)) return;
            each(placements, [&](const Json& pair) {
                if (!array(pair)) return;
                if (pair.size() != 2) {
                    error(shown(pair) + (pair.size() < 2 ? " is too short" : " is too long") +
                          " (a placement is [task, node])");
                }
                each(pair, [&](const Json& name) { string(name, Text::name); });
            });
        });
    }

    void edges(const Json& value, std::initializer_list<const char*> keys) {
        if (!array(value)) return;
        each(value, [&](const Json& edge) {
            if (!object(edge, keys)) return;
            for (const char* key : keys) {
                in(edge, key, [&](const Json& v) { string(v, Text::name); });
            }
        });
    }

    void phase(const Json& phase) {
        if (!object(phase, {"name", "tasks", "initial", "configurations", "on_failure", "on_phase",
                            "params"},
                    {"on_recovery", "placement"})) {
            return;
        }
        in(phase, "placement",
           [&](const Json& v) { one_of(v, {"graph", "online", "graph+online"}, false); });
        in(phase, "name", [&](const Json& v) { string(v, Text::name); });
        in(phase, "tasks", [&](const Json& v) { names(v); });
        in(phase, "initial", [&](const Json& v) { string(v, Text::name); });
        in(phase, "configurations", [&](const Json& configurations) {
            if (array(configurations, 1)) {
                each(configurations, [&](const Json& c) { configuration(c); });
            }
        });
        in(phase, "on_failure", [&](const Json& v) { edges(v, {"config", "node", "next"}); });
        in(phase, "on_recovery", [&](const Json& v) { edges(v, {"config", "node", "next"}); });
        in(phase, "on_phase", [&](const Json& v) { edges(v, {"phase", "from", "to"}); });
        in(phase, "params", [&](const Json& value) {
            if (!value.is_object()) {
                error(shown(value) + " is not of type \"object\"");
                return;
            }
            property_names(value);
            for (const auto& [task, task_params] : value.get_ref<const Json::object_t&>()) {
                path_.push_back(task);
                params(task_params);
                path_.pop_back();
            }
        });
    }
};

void check_schema(const Json& image) {
    SchemaCheck check;
    check.image(image);
    if (check.errors.empty()) return;
    // The first by position, as image.py orders jsonschema's errors.
    const auto first = std::min_element(
        check.errors.begin(), check.errors.end(),
        [](const SchemaCheck::Error& a, const SchemaCheck::Error& b) { return a.path < b.path; });
    const std::size_t more = check.errors.size() - 1;
    refuse("schema", first->message +
                         (more > 0 ? " (and " + std::to_string(more) + " more)" : std::string()));
}

// --------------------------------------------------------------------------------------
// Consistency and capacity (the image has passed the schema)

const std::string& text(const Json& value) { return value.get_ref<const std::string&>(); }

std::string python_repr(const std::string& value) {
    const bool single = value.find('\'') != std::string::npos;
    const bool double_quote = value.find('"') != std::string::npos;
    const char quote = single && !double_quote ? '"' : '\'';
    std::string out(1, quote);
    for (const char c : value) {
        if (c == quote || c == '\\') out += '\\';
        out += c;
    }
    return out + quote;
}

void check_consistency(const Json& image) {
    const Json& content = image.at("content");
    if (text(content.at("mission")) != text(image.at("mission"))) {
        refuse("inconsistent", "mission " + python_repr(text(image.at("mission"))) +
                                   " but content.mission " +
                                   python_repr(text(content.at("mission"))));
    }
    for (const char* what : {"nodes", "tasks"}) {
        const Json& items = content.at(what);
        for (std::size_t index = 0; index < items.size(); ++index) {
            const Json& id = items[index].at("id");
            if (id.get<std::int64_t>() != static_cast<std::int64_t>(index)) {
                refuse("inconsistent", "content." + std::string(what) + "." +
                                           std::to_string(index) + " (" +
                                           text(items[index].at("name")) + ") has id " +
                                           shown(id) + "; the id of an entry is its index");
            }
        }
    }
}

void check_capacity(const Json& image, const ImageOptions& options) {
    const Json& content = image.at("content");
    const Json& declared = image.at("capacity");
    const struct {
        const char* what;
        std::size_t ours;
        std::int64_t theirs;
    } limits[] = {
        {"nodes", options.max_nodes, declared.at("max_nodes").get<std::int64_t>()},
        {"tasks", options.max_tasks, declared.at("max_tasks").get<std::int64_t>()},
    };
    for (const auto& limit : limits) {
        const std::size_t count = content.at(limit.what).size();
        const auto theirs = static_cast<std::uint64_t>(limit.theirs);
        if (limit.ours <= theirs && count > limit.ours) {
            refuse("over-limit", "the image has " + std::to_string(count) + " " + limit.what +
                                     "; this runtime holds at most " + std::to_string(limit.ours) +
                                     " (its compile-time capacity; the image was checked "
                                     "against a capacity of " +
                                     std::to_string(limit.theirs) + ")");
        }
        if (theirs < limit.ours && count > theirs) {
            refuse("over-limit", "the image has " + std::to_string(count) + " " + limit.what +
                                     "; the image's own capacity allows at most " +
                                     std::to_string(limit.theirs));
        }
    }
}

// --------------------------------------------------------------------------------------
// Building the Mission from content

std::vector<std::string> strings(const Json& list) {
    std::vector<std::string> out;
    out.reserve(list.size());
    for (const Json& item : list) out.push_back(text(item));
    return out;
}

std::optional<std::int64_t> optional_integer(const Json& value) {
    if (value.is_null()) return std::nullopt;
    return value.get<std::int64_t>();
}

std::optional<double> optional_number(const Json& value) {
    if (value.is_null()) return std::nullopt;
    return value.is_number_float() ? value.get<double>()
                                   : static_cast<double>(value.get<std::int64_t>());
}

Params params(const Json& object) {
    Params out;
    for (const auto& [key, value] : object.get_ref<const Json::object_t&>()) {
        ParamValue param;
        if (value.is_string()) {
            param = text(value);
        } else if (value.is_boolean()) {
            param = value.get<bool>();
        } else if (value.is_number_float()) {
            param = value.get<double>();
        } else {
            param = value.get<std::int64_t>();
        }
        out.emplace_back(key, std::move(param));
    }
    return out;
}

Node build_node(const Json& raw) {
    Node node;
    node.name = text(raw.at("name"));
    node.kind = text(raw.at("kind")) == "processing" ? NodeKind::processing : NodeKind::interface;
    const Json& role = raw.at("role");
    node.role = role.is_null()                ? NodeRole::none
                : text(role) == "storage" ? NodeRole::storage
                                          : NodeRole::interface;
    node.capabilities = strings(raw.at("capabilities"));
    node.capacity.cpu = optional_integer(raw.at("capacity").at("cpu"));
    node.capacity.mem_mb = optional_integer(raw.at("capacity").at("mem_mb"));
    return node;
}

Task build_task(const Json& raw) {
    Task task;
    task.name = text(raw.at("name"));
    task.port = raw.at("port").get<std::int64_t>();
    task.component = text(raw.at("component"));
    task.requires_capabilities = strings(raw.at("requires"));
    task.load.cpu = raw.at("load").at("cpu").get<std::int64_t>();
    task.load.mem_mb = raw.at("load").at("mem_mb").get<std::int64_t>();
    task.essential = raw.at("essential").get<bool>();
    task.checkpoint = raw.at("checkpoint").get<bool>();
    task.inputs = strings(raw.at("inputs"));
    task.period_ms = optional_integer(raw.at("period_ms"));
    const Json& health = raw.at("health");
    if (!health.is_null()) {
        task.health = Health{optional_number(health.at("min")), optional_number(health.at("max")),
                             optional_integer(health.at("deadline_ms"))};
    }
    task.params = params(raw.at("params"));
    if (const auto bound = raw.find("max_sample_bytes"); bound != raw.end()) {
        task.max_sample_bytes = bound->get<std::int64_t>();
    }
    if (const auto bound = raw.find("max_state_bytes"); bound != raw.end()) {
        task.max_state_bytes = bound->get<std::int64_t>();
    }
    if (const auto priority = raw.find("priority"); priority != raw.end()) {
        task.priority = priority->get<std::int64_t>();
    }
    if (const auto group = raw.find("group"); group != raw.end()) task.group = text(*group);
    return task;
}

Phase build_phase(const Json& raw) {
    Phase phase;
    phase.name = text(raw.at("name"));
    phase.tasks = strings(raw.at("tasks"));
    phase.initial = text(raw.at("initial"));
    if (const auto placement = raw.find("placement"); placement != raw.end()) {
        const std::string mode = text(*placement);
        phase.placement = mode == "online"         ? PlacementMode::online
                          : mode == "graph+online" ? PlacementMode::graph_online
                                                   : PlacementMode::graph;
    }
    for (const Json& rc : raw.at("configurations")) {
        Configuration configuration;
        configuration.name = text(rc.at("name"));
        configuration.phase = phase.name;
        configuration.master = text(rc.at("master"));
        configuration.observers = strings(rc.at("observers"));
        for (const Json& pair : rc.at("tasks")) {
            configuration.placement.emplace_back(text(pair.at(0)), text(pair.at(1)));
        }
        phase.configurations.push_back(std::move(configuration));
    }
    for (const Json& edge : raw.at("on_failure")) {
        phase.on_failure.push_back(
            FailureEdge{text(edge.at("config")), text(edge.at("node")), text(edge.at("next")), 0});
    }
    if (const auto recovery = raw.find("on_recovery"); recovery != raw.end()) {
        for (const Json& edge : *recovery) {
            phase.on_recovery.push_back(FailureEdge{text(edge.at("config")), text(edge.at("node")),
                                                    text(edge.at("next")), 0});
        }
    }
    for (const Json& edge : raw.at("on_phase")) {
        phase.on_phase.push_back(
            PhaseEdge{text(edge.at("phase")), text(edge.at("from")), text(edge.at("to")), 0});
    }
    for (const auto& [task, task_params] : raw.at("params").get_ref<const Json::object_t&>()) {
        phase.params.emplace_back(task, params(task_params));
    }
    return phase;
}

Mission build(const Json& content, const std::string& path) {
    Mission mission;
    mission.name = text(content.at("mission"));
    mission.path = path;
    if (const auto revision = content.find("revision"); revision != content.end()) {
        mission.revision = revision->get<std::int64_t>();
    }
    const Json& heartbeat = content.at("heartbeat");
    mission.heartbeat.period_ms = heartbeat.at("period_ms").get<std::int64_t>();
    mission.heartbeat.miss_limit = heartbeat.at("miss_limit").get<std::int64_t>();
    mission.heartbeat.startup_grace_ms = heartbeat.at("startup_grace_ms").get<std::int64_t>();
    if (const auto tie_grace = heartbeat.find("tie_grace"); tie_grace != heartbeat.end()) {
        mission.heartbeat.tie_grace = tie_grace->get<std::int64_t>();
    }
    const Json& tolerance = content.at("tolerance");
    mission.tolerance.node_failures = tolerance.at("node_failures").get<std::int64_t>();
    mission.tolerance.nodes = strings(tolerance.at("nodes"));
    for (const Json& node : content.at("nodes")) mission.nodes.push_back(build_node(node));
    for (const Json& task : content.at("tasks")) mission.tasks.push_back(build_task(task));
    for (const Json& phase : content.at("phases")) mission.phases.push_back(build_phase(phase));
    return mission;
}

// --------------------------------------------------------------------------------------
// What the verifier's reader guarantees of every compiled image and the runtime relies on:
// names are unique and not SAFE, every name refers to something defined, ports are unique,
// roles fit kinds, health bounds are ordered. image.py leaves these to the reader that
// wrote the image; a node checks them too, since a hash alone does not say who wrote it.

class Structure {
public:
    explicit Structure(const Mission& mission) : mission_(mission) {}

    void check() {
        unique_names();
        for (const Node& node : mission_.nodes) check_node(node);
        std::set<std::string> capabilities;
        for (const Node& node : mission_.nodes) {
            capabilities.insert(node.capabilities.begin(), node.capabilities.end());
        }
        for (const std::string& node : mission_.tolerance.nodes) {
            defined(nodes_, node, "tolerance.nodes", "node");
        }
        std::set<std::int64_t> ports;
        for (const Task& task : mission_.tasks) {
            const std::string where = "task " + task.name;
            for (const std::string& capability : task.requires_capabilities) {
                if (capabilities.count(capability) == 0) {
                    refuse("inconsistent",
                           where + ": no node offers capability '" + capability + "'");
                }
            }
            for (const std::string& input : task.inputs) {
                defined(tasks_, input, where, "input task");
            }
            if (!ports.insert(task.port).second) {
                refuse("inconsistent", where + ": port " + std::to_string(task.port) +
                                           " is used by another task");
            }
            if (task.health && task.health->min && task.health->max &&
                *task.health->min > *task.health->max) {
                refuse("inconsistent", where + ": health.max is below health.min");
            }
            if (task.max_state_bytes && !task.checkpoint) {
                refuse("inconsistent", where + ": max_state_bytes on a task that is not checkpointed");
            }
        }
        for (const Phase& phase : mission_.phases) check_phase(phase);
    }

private:
    const Mission& mission_;
    std::set<std::string> nodes_;
    std::set<std::string> tasks_;
    std::set<std::string> configurations_;

    void unique(std::set<std::string>& names, const std::string& name, const char* what) {
        if (name == kSafe) {
            refuse("inconsistent",
                   std::string("'") + kSafe + "' is reserved and cannot name a " + what);
        }
        if (!names.insert(name).second) {
            refuse("inconsistent", std::string(what) + " '" + name + "' is defined twice");
        }
    }

    void unique_names() {
        std::set<std::string> phases;
        for (const Node& node : mission_.nodes) unique(nodes_, node.name, "node");
        for (const Task& task : mission_.tasks) unique(tasks_, task.name, "task");
        for (const Phase& phase : mission_.phases) {
            unique(phases, phase.name, "phase");
            for (const Configuration& c : phase.configurations) {
                unique(configurations_, c.name, "configuration");
            }
        }
    }

    static void defined(const std::set<std::string>& names, const std::string& name,
                        const std::string& where, const char* what) {
        if (names.count(name) == 0) {
            refuse("inconsistent", where + ": " + what + " '" + name + "' is not defined");
        }
    }

    static void check_node(const Node& node) {
        if (node.kind == NodeKind::processing && node.role != NodeRole::none) {
            refuse("inconsistent", "node " + node.name + ": role is only for interface nodes");
        }
        if (node.kind == NodeKind::interface && node.role == NodeRole::none) {
            refuse("inconsistent", "node " + node.name + ": an interface node has a role");
        }
    }

    void check_phase(const Phase& phase) {
        const std::string where = "phase " + phase.name;
        std::set<std::string> own;
        for (const Configuration& c : phase.configurations) own.insert(c.name);
        for (const std::string& task : phase.tasks) defined(tasks_, task, where + " tasks", "task");
        defined(own, phase.initial, where + " initial", "configuration");
        if (phase.placement == PlacementMode::online &&
            (phase.configurations.size() != 1 || !phase.on_failure.empty() ||
             !phase.on_recovery.empty())) {
            refuse("inconsistent", where + ": an online phase has only its initial configuration "
                                           "and no on_failure or on_recovery edges");
        }
        for (const Configuration& c : phase.configurations) {
            const std::string at = where + ", configuration " + c.name;
            defined(nodes_, c.master, at + " master", "node");
            for (const std::string& observer : c.observers) {
                defined(nodes_, observer, at, "observer");
            }
            std::set<std::string> placed;
            for (const auto& [task, node] : c.placement) {
                defined(tasks_, task, at, "placed task");
                defined(nodes_, node, at + " task " + task, "node");
                if (!placed.insert(task).second) {
                    refuse("inconsistent", at + ": task " + task + " is placed twice");
                }
            }
        }
        std::set<std::pair<std::string, std::string>> failures;
        for (const FailureEdge& edge : phase.on_failure) {
            const std::string at = where + " on_failure " + edge.config;
            defined(own, edge.config, where + " on_failure", "configuration");
            defined(nodes_, edge.node, at, "node");
            if (edge.next != kSafe) defined(own, edge.next, at + " " + edge.node, "configuration");
            if (!failures.emplace(edge.config, edge.node).second) {
                refuse("inconsistent", at + ": two edges for node " + edge.node);
            }
        }
        std::set<std::pair<std::string, std::string>> recoveries;
        for (const FailureEdge& edge : phase.on_recovery) {
            const std::string at = where + " on_recovery " + edge.config;
            defined(own, edge.config, where + " on_recovery", "configuration");
            defined(nodes_, edge.node, at, "node");
            defined(own, edge.next, at + " " + edge.node, "configuration");
            if (!recoveries.emplace(edge.config, edge.node).second) {
                refuse("inconsistent", at + ": two edges for node " + edge.node);
            }
        }
        std::set<std::pair<std::string, std::string>> switches;
        for (const PhaseEdge& edge : phase.on_phase) {
            const std::string at = where + " on_phase " + edge.phase;
            const Phase* target = mission_.phase(edge.phase);
            if (target == nullptr) {
                refuse("inconsistent",
                       where + " on_phase: phase '" + edge.phase + "' is not defined");
            }
            defined(own, edge.from, at, "configuration");
            if (target->configuration(edge.to) == nullptr) {
                refuse("inconsistent", at + " " + edge.from + ": configuration '" + edge.to +
                                           "' of phase " + edge.phase + " is not defined");
            }
            if (!switches.emplace(edge.phase, edge.from).second) {
                refuse("inconsistent", at + ": two edges from configuration " + edge.from);
            }
        }
        for (const auto& entry : phase.params) {
            defined(tasks_, entry.first, where + " params", "task");
        }
    }
};

// --------------------------------------------------------------------------------------
// The normalised form of a Mission, as keel-verify load --json prints it

Json strings_json(const std::vector<std::string>& values) {
    Json out = Json::array();
    for (const std::string& value : values) out.push_back(value);
    return out;
}

Json optional_json(const auto& value) {
    return value ? Json(*value) : Json(nullptr);
}

Json resources_json(const Resources& resources) {
    return Json{{"cpu", optional_json(resources.cpu)}, {"mem_mb", optional_json(resources.mem_mb)}};
}

Json params_json(const Params& params) {
    Json out = Json::object();
    for (const auto& [key, value] : params) {
        std::visit([&out, &key](const auto& v) { out[key] = v; }, value);
    }
    return out;
}

Json edges_json(const std::vector<FailureEdge>& edges) {
    Json out = Json::array();
    for (const FailureEdge& e : edges) {
        out.push_back(Json{{"config", e.config}, {"node", e.node}, {"next", e.next}});
    }
    return out;
}

Json mission_json(const Mission& mission) {
    Json nodes = Json::array();
    for (const Node& n : mission.nodes) {
        nodes.push_back(Json{
            {"name", n.name},
            {"kind", n.is_processing() ? "processing" : "interface"},
            {"role", n.role == NodeRole::none      ? Json(nullptr)
                     : n.role == NodeRole::storage ? Json("storage")
                                                   : Json("interface")},
            {"capabilities", strings_json(n.capabilities)},
            {"capacity", resources_json(n.capacity)}});
    }
    Json tasks = Json::array();
    for (const Task& t : mission.tasks) {
        Json health(nullptr);
        if (t.health) {
            health = Json{{"min", optional_json(t.health->min)},
                          {"max", optional_json(t.health->max)},
                          {"deadline_ms", optional_json(t.health->deadline_ms)}};
        }
        Json task{{"name", t.name},
                  {"port", t.port},
                  {"component", t.component},
                  {"requires", strings_json(t.requires_capabilities)},
                  {"load", resources_json(t.load)},
                  {"essential", t.essential},
                  {"checkpoint", t.checkpoint},
                  {"inputs", strings_json(t.inputs)},
                  {"period_ms", optional_json(t.period_ms)},
                  {"health", std::move(health)},
                  {"params", params_json(t.params)}};
        // Absent when not stated, as in the image.
        if (t.max_sample_bytes) task["max_sample_bytes"] = *t.max_sample_bytes;
        if (t.max_state_bytes) task["max_state_bytes"] = *t.max_state_bytes;
        if (t.priority) task["priority"] = *t.priority;
        if (t.group) task["group"] = *t.group;
        tasks.push_back(std::move(task));
    }
    Json phases = Json::array();
    for (const Phase& p : mission.phases) {
        Json configurations = Json::array();
        for (const Configuration& c : p.configurations) {
            Json placement = Json::array();
            for (const auto& [task, node] : c.placement) placement.push_back(Json::array({task, node}));
            configurations.push_back(Json{{"name", c.name},
                                          {"master", c.master},
                                          {"observers", strings_json(c.observers)},
                                          {"tasks", std::move(placement)}});
        }
        Json on_phase = Json::array();
        for (const PhaseEdge& e : p.on_phase) {
            on_phase.push_back(Json{{"phase", e.phase}, {"from", e.from}, {"to", e.to}});
        }
        Json phase_params = Json::object();
        for (const auto& [task, params] : p.params) phase_params[task] = params_json(params);
        Json phase{{"name", p.name},
                   {"tasks", strings_json(p.tasks)},
                   {"initial", p.initial},
                   {"configurations", std::move(configurations)},
                   {"on_failure", edges_json(p.on_failure)},
                   {"on_phase", std::move(on_phase)},
                   {"params", std::move(phase_params)}};
        // Absent when empty, as keel-verify load prints it.
        if (!p.on_recovery.empty()) phase["on_recovery"] = edges_json(p.on_recovery);
        // Absent for graph, so that the images of graph missions keep their hashes.
        if (p.placement != PlacementMode::graph) phase["placement"] = placement_name(p.placement);
        phases.push_back(std::move(phase));
    }
    Json out{{"mission", mission.name},
             {"schema", 1},
             {"heartbeat", Json{{"period_ms", mission.heartbeat.period_ms},
                                {"miss_limit", mission.heartbeat.miss_limit},
                                {"startup_grace_ms", mission.heartbeat.startup_grace_ms}}},
             {"tolerance", Json{{"node_failures", mission.tolerance.node_failures},
                                {"nodes", strings_json(mission.tolerance.nodes)}}},
             {"nodes", std::move(nodes)},
             {"tasks", std::move(tasks)},
             {"phases", std::move(phases)}};
    // Absent when the mission states none, as keel-verify load prints it.
    if (mission.revision) out["revision"] = *mission.revision;
    // Absent when 0, as keel-verify load prints it, so that images of missions that leave
    // it at 0 keep their bytes and hash.
    if (mission.heartbeat.tie_grace != 0) {
        out["heartbeat"]["tie_grace"] = mission.heartbeat.tie_grace;
    }
    return out;
}

// --------------------------------------------------------------------------------------

std::optional<PublicKey> configured_key(const ImageOptions& options) {
    if (options.public_key_path.empty()) return std::nullopt;
    return load_public_key(options.public_key_path);
}

LoadResult checked(std::string_view bytes, const std::string& path,
                   const std::optional<PublicKey>& key, const ImageOptions& options,
                   ImageSummary* summary) {
    if (bytes.size() > kMaxImageBytes) {
        refuse("over-limit", "the file is larger than " +
                                 std::to_string(kMaxImageBytes / (1024 * 1024)) + " MiB");
    }
    const Json image = parse(bytes);
    check_version(image);
    const std::string hashed = hashed_bytes(image);
    const std::string computed = sha256_hex(hashed);
    check_hash(image, computed);
    if (key) check_signature(image, hashed, *key);
    check_schema(image);
    check_consistency(image);
    check_capacity(image, options);
    LoadResult result;
    result.mission = build(image.at("content"), path);
    Structure(*result.mission).check();
    if (summary != nullptr) {
        summary->sha256 = computed;
        summary->verifier = text(image.at("verifier"));
        summary->source_file = text(image.at("source").at("file"));
        const Json* signature = member(image, "signature");
        summary->key_id = signature != nullptr ? text(signature->at("key_id")) : std::string();
        summary->signature_verified = key.has_value();
    }
    return result;
}

// Runs `load`, turning a refusal (or anything thrown) into the one LoadError it means.
LoadResult guarded(const std::string& path, const std::function<LoadResult()>& load) {
    Refusal refusal;
    try {
        return load();
    } catch (const Refusal& caught) {
        refusal = caught;
    } catch (const std::bad_alloc&) {
        refusal = Refusal{"over-limit", "out of memory while loading the image"};
    } catch (const std::exception& error) {
        // The checks above leave nothing for nlohmann-json to refuse; should a case slip
        // through, it is still a refusal, not a crash.
        refusal = Refusal{"schema", std::string("the image cannot be read as a mission: ") +
                                        error.what()};
    }
    LoadResult result;
    result.errors.push_back(LoadError{refusal.file.empty() ? path : refusal.file, refusal.line,
                                      refusal.col, refusal.reason, refusal.message});
    return result;
}

}  // namespace

std::string to_json(const Mission& mission) {
    return canonical(mission_json(mission));
}

std::string canonical_float(double x) {
    char buffer[64];
    // Shortest round-trip digits, e.g. "-1.5e+03".
    const auto result =
        std::to_chars(buffer, buffer + sizeof buffer, x, std::chars_format::scientific);
    std::string_view scientific(buffer, static_cast<std::size_t>(result.ptr - buffer));
    const bool negative = scientific.front() == '-';
    if (negative) scientific.remove_prefix(1);
    const std::size_t e = scientific.find('e');
    int exponent = 0;
    std::from_chars(scientific.data() + e + 1 + (scientific[e + 1] == '+' ? 1 : 0),
                    scientific.data() + scientific.size(), exponent);
    std::string digits;
    for (const char c : scientific.substr(0, e)) {
        if (c != '.') digits += c;
    }
    std::string out = negative ? "-" : "";
    if (exponent >= -4 && exponent < 16) {
        const int point = exponent + 1;  // digits before the decimal point
        if (point <= 0) {
            out += "0." + std::string(static_cast<std::size_t>(-point), '0') + digits;
        } else if (static_cast<std::size_t>(point) >= digits.size()) {
            const auto zeros = static_cast<std::size_t>(point) - digits.size();
            out += digits + std::string(zeros, '0') + ".0";
        } else {
            const auto split = static_cast<std::size_t>(point);
            out += digits.substr(0, split) + "." + digits.substr(split);
        }
        return out;
    }
    out += digits.substr(0, 1);
    if (digits.size() > 1) out += "." + digits.substr(1);
    char exponent_text[16];
    std::snprintf(exponent_text, sizeof exponent_text, "e%c%02d", exponent < 0 ? '-' : '+',
                  exponent < 0 ? -exponent : exponent);
    return out + exponent_text;
}

std::optional<std::string> canonical_json(std::string_view json_text) {
    try {
        return canonical(parse(json_text));
    } catch (...) {
        return std::nullopt;
    }
}

bool looks_like_image(std::string_view bytes) {
    if (bytes.substr(0, 3) == "\xEF\xBB\xBF") bytes.remove_prefix(3);
    const std::size_t first = bytes.find_first_not_of(" \t\r\n");
    return first != std::string_view::npos && bytes[first] == '{';
}

std::string sha256_text(std::string_view bytes) {
    try {
        return sha256_hex(bytes);
    } catch (const Refusal&) {
        return {};
    }
}

bool is_mission_image(const std::string& path) {
    FileDescriptor file(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (file.get() < 0) return false;
    // Only a regular file can be read twice (a pipe would lose what the look consumed).
    struct stat info {};
    if (::fstat(file.get(), &info) != 0 || !S_ISREG(info.st_mode)) return false;
    std::string start;
    char buffer[4096];
    // Whitespace may go on for a while; stop at the first other byte or at the image limit.
    while (start.size() <= kMaxImageBytes) {
        const ssize_t n = ::read(file.get(), buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        start.append(buffer, static_cast<std::size_t>(n));
        const std::string_view view(start);
        const std::size_t skip = view.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
        if (view.find_first_not_of(" \t\r\n", skip) != std::string_view::npos) break;
    }
    return looks_like_image(start);
}

LoadResult load_mission_image_bytes(std::string_view bytes, const std::string& path,
                                    const ImageOptions& options, ImageSummary* summary) {
    return guarded(path, [&] {
        const std::optional<PublicKey> key = configured_key(options);
        return checked(bytes, path, key, options, summary);
    });
}

LoadResult load_mission_image(const std::string& path, const ImageOptions& options,
                              ImageSummary* summary) {
    return guarded(path, [&] {
        // The key first, as image.py: a bad key file is the operator's error, whatever the image.
        const std::optional<PublicKey> key = configured_key(options);
        const std::string bytes = read_image(path);
        return checked(bytes, path, key, options, summary);
    });
}

}  // namespace keel::mission
