// The mission image loader (core/mission/image.hpp) on the fixtures of
// tests/missions/images/ (compiled by keel-verify compile; tests/missions/test_images.py
// regenerates them and fails when one is stale) and on hostile bytes.
#include <fcntl.h>
#include <openssl/evp.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/mission/image.hpp"
#include "core/mission/mission.hpp"

namespace keel::mission {
namespace {

const std::string kRoot = KEEL_SOURCE_DIR;
const std::string kImages = kRoot + "/tests/missions/images/";

std::string read(const std::string& path) {
    std::ifstream stream(path, std::ios::binary);
    std::stringstream bytes;
    bytes << stream.rdbuf();
    return bytes.str();
}

class TempFile {
public:
    explicit TempFile(const std::string& bytes) {
        char name[] = "/tmp/keel-image-test-XXXXXX";
        const int fd = ::mkstemp(name);
        EXPECT_GE(fd, 0);
        path_ = name;
        if (fd >= 0) {
            EXPECT_EQ(::write(fd, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
            ::close(fd);
        }
    }
    ~TempFile() { std::remove(path_.c_str()); }
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

// The reason id of a refused load, or "ok".
std::string verdict(const LoadResult& result) {
    if (result.ok()) return "ok";
    EXPECT_EQ(result.errors.size(), 1u);
    return result.errors.empty() ? "?" : result.errors[0].rule;
}

std::string verdict_of_bytes(const std::string& bytes, const ImageOptions& options = {}) {
    return verdict(load_mission_image_bytes(bytes, "test.json", options));
}

std::string sha256_hex(const std::string& bytes) {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned int size = 0;
    EXPECT_EQ(EVP_Digest(bytes.data(), bytes.size(), digest, &size, EVP_sha256(), nullptr), 1);
    std::string out;
    char buffer[3];
    for (unsigned int i = 0; i < size; ++i) {
        std::snprintf(buffer, sizeof buffer, "%02x", digest[i]);
        out += buffer;
    }
    return out;
}

// An image text (without sha256) sealed with a correct hash, by this loader's encoding.
std::string sealed(const std::string& json_without_hash) {
    const std::optional<std::string> canonical = canonical_json(json_without_hash);
    EXPECT_TRUE(canonical.has_value()) << json_without_hash;
    if (!canonical) return {};
    return canonical->substr(0, canonical->size() - 1) + ",\"sha256\":\"" + sha256_hex(*canonical) +
           "\"}";
}

// The prototype3 image without its sha256, with `from` replaced by `to` once.
std::string prototype3_with(const std::string& from, const std::string& to) {
    std::string text = read(kImages + "good/prototype3.json");
    const std::size_t hash = text.find(",\"sha256\":\"");
    EXPECT_NE(hash, std::string::npos);
    text.erase(hash, std::string(",\"sha256\":\"").size() + 64 + 1);
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

// ---------------------------------------------------------------------------------------
// The canonical encoding: byte for byte what keel_verify.image.canonical_bytes writes (the
// expected strings were printed by it).

TEST(ImageCanonical, FloatsAsPythonWritesThem) {
    const std::pair<double, const char*> cases[] = {
        {0.1, "0.1"},
        {1e-05, "1e-05"},
        {1e16, "1e+16"},
        {123456789012345680.0, "1.2345678901234568e+17"},
        {-0.0, "-0.0"},
        {2.5e-05, "2.5e-05"},
        {1e+16, "1e+16"},
        {0.0001, "0.0001"},
        {9999999999999998.0, "9999999999999998.0"},
        {0.00009999, "9.999e-05"},
        {5e-324, "5e-324"},
        {1.7976931348623157e308, "1.7976931348623157e+308"},
        {3.0, "3.0"},
        {1e22, "1e+22"},
        {100.0, "100.0"},
        {-1.5, "-1.5"},
        {0.30000000000000004, "0.30000000000000004"},
        {9.999999e-05, "9.999999e-05"},
        {9223372036854775808.0, "9.223372036854776e+18"},
        {1e-07, "1e-07"},
        {12345.678, "12345.678"},
    };
    for (const auto& [value, python] : cases) EXPECT_EQ(canonical_float(value), python) << python;
}

TEST(ImageCanonical, DocumentsAsPythonWritesThem) {
    const std::pair<const char*, std::string> cases[] = {
        {R"({"b": [1, -0, 1E5, 1.50, -2.5e-3, 18446744073709551615, -9223372036854775808,
                  123456789012345678901234567890, -99999999999999999999],
             "a": {"z": null, "y": true, "x": false}})",
         R"({"a":{"x":false,"y":true,"z":null},"b":[1,0,100000.0,1.5,-0.0025,)"
         R"(18446744073709551615,-9223372036854775808,123456789012345678901234567890,)"
         R"(-99999999999999999999]})"},
        {R"({"s": "quote \" backslash \\ slash \/ controls \u0000\u0001\b\f\n\r\t\u001f )"
         R"(del \u007f latin \u00e9 \u2028 astral \ud83d\ude00 raw é😀", "": "", "é": 1, )"
         R"("Z": 2, "a": 3})",
         std::string(R"({"":"","Z":2,"a":3,"s":"quote \" backslash \\ slash / controls )"
                     R"(\u0000\u0001\b\f\n\r\t\u001f del )") +
             "\x7f" + " latin é " + "\xE2\x80\xA8" + R"( astral 😀 raw é😀","é":1})"},
        {"[]", "[]"},
        {" [ { } ] ", "[{}]"},
        {"\"x\"", "\"x\""},
        {"0", "0"},
        {"1.0", "1.0"},
        {"-0.0", "-0.0"},
    };
    for (const auto& [text, python] : cases) {
        const std::optional<std::string> canonical = canonical_json(text);
        ASSERT_TRUE(canonical.has_value()) << text;
        EXPECT_EQ(*canonical, python);
    }
}

TEST(ImageCanonical, EveryCompiledImageIsItsOwnCanonicalEncoding) {
    // compile writes the canonical encoding of the whole image and a line feed.
    for (const char* name : {"prototype3", "earth_observation", "floats", "prototype3.signed"}) {
        const std::string bytes = read(kImages + "good/" + name + ".json");
        ASSERT_FALSE(bytes.empty()) << name;
        EXPECT_EQ(canonical_json(bytes), bytes.substr(0, bytes.size() - 1)) << name;
    }
}

TEST(ImageCanonical, RefusesWhatPythonRefuses) {
    for (const char* text : {"", "{", "{\"a\":1,\"a\":2}", "[NaN]", "[Infinity]", "[1e400]",
                             "[\"\\ud800\"]", "{} {}", "\xEF\xBB\xBF{}", "[\"\xC0\x80\"]",
                             "{'a':1}", "[01]", "[1.]", "[.5]", "[\"a\nb\"]"}) {
        EXPECT_FALSE(canonical_json(text).has_value()) << text;
    }
}

// ---------------------------------------------------------------------------------------
// Good images load; what they hold is what the verifier read (tests/missions/test_images.py
// compares keel-mission --json with keel-verify load --json)

TEST(ImageLoader, ShippedMissionsLoadWithTheirSummary) {
    for (const char* name : {"prototype3", "earth_observation", "floats"}) {
        SCOPED_TRACE(name);
        const std::string image_path = kImages + "good/" + name + ".json";
        ImageSummary summary;
        const LoadResult image = load_mission_image(image_path, {}, &summary);
        ASSERT_TRUE(image.ok()) << image.errors[0].to_string();
        EXPECT_EQ(image.mission->path, image_path);
        EXPECT_EQ(summary.sha256.size(), 64u);
        EXPECT_EQ(summary.source_file, std::string(name) + ".yaml");
        EXPECT_TRUE(summary.key_id.empty());
        EXPECT_FALSE(summary.signature_verified);
    }
}

TEST(ImageLoader, FloatsAndStringsSurviveExactly) {
    const LoadResult result = load_mission_image(kImages + "good/floats.json");
    ASSERT_TRUE(result.ok()) << result.errors[0].to_string();
    const Task& probe = result.mission->tasks.at(0);
    auto param = [&](const std::string& name) {
        for (const auto& [key, value] : probe.params) {
            if (key == name) return value;
        }
        ADD_FAILURE() << "no param " << name;
        return ParamValue{};
    };
    EXPECT_EQ(std::get<double>(param("tenth")), 0.1);
    EXPECT_EQ(std::get<double>(param("whole")), 3.0);
    EXPECT_EQ(std::get<std::int64_t>(param("integer")), 3);
    EXPECT_EQ(std::get<std::int64_t>(param("max_int")), INT64_MAX);
    EXPECT_EQ(std::get<std::int64_t>(param("min_int")), INT64_MIN);
    EXPECT_TRUE(std::signbit(std::get<double>(param("negative_zero"))));
    EXPECT_EQ(std::get<std::string>(param("text")),
              "line\nbreak \x01 \x7f \\ \"q\" é 😀 \xE2\x80\xA8 \b\f\r\t");
    EXPECT_EQ(result.mission->name, "floats and strings: \"quoted\", tab\t, é, 😀");
}

TEST(ImageLoader, DispatchLooksAtTheFirstByteAfterWhitespace) {
    EXPECT_TRUE(looks_like_image("{}"));
    EXPECT_TRUE(looks_like_image(" \n\t\r{"));
    EXPECT_TRUE(looks_like_image("\xEF\xBB\xBF {"));
    EXPECT_FALSE(looks_like_image("# comment\n{"));
    EXPECT_FALSE(looks_like_image("mission: x"));
    EXPECT_FALSE(looks_like_image(""));
    EXPECT_FALSE(looks_like_image("   "));
    EXPECT_FALSE(is_mission_image("/nonexistent/keel/image.json"));
    const TempFile spaced(std::string(10000, ' ') + "{");
    EXPECT_TRUE(is_mission_image(spaced.path()));
}

// ---------------------------------------------------------------------------------------
// Refusals: the reason ids of image.py, the file named

TEST(ImageLoader, BadFixturesAreRefusedWithTheirReason) {
    const std::pair<const char*, const char*> fixtures[] = {
        {"tampered", "tampered"},
        {"tampered-no-sha256", "tampered"},
        {"format-version", "format-version"},
        {"format-version-missing", "format-version"},
        {"not-json", "not-json"},
        {"not-json-duplicate-key", "not-json"},
        {"not-json-nan", "not-json"},
        {"schema-float-port", "schema"},
        {"schema-unknown-key", "schema"},
        {"inconsistent-id", "inconsistent"},
        {"inconsistent-reference", "inconsistent"},
        {"over-limit-own-capacity", "over-limit"},
        {"over-limit-nodes", "over-limit"},
        {"over-limit-tasks", "over-limit"},
    };
    for (const auto& [name, reason] : fixtures) {
        const std::string path = kImages + "bad/" + name + ".json";
        const LoadResult result = load_mission_image(path);
        EXPECT_EQ(verdict(result), reason) << name;
        if (result.errors.empty()) continue;
        EXPECT_EQ(result.errors[0].file, path);
        EXPECT_EQ(result.exit_code(), 2) << name;
        EXPECT_EQ(result.errors[0].to_string().rfind(path + ":", 0), 0u) << name;
    }
}

TEST(ImageLoader, OverLimitNamesTheCountAndTheRuntimeCapacity) {
    const LoadResult nodes = load_mission_image(kImages + "bad/over-limit-nodes.json");
    ASSERT_FALSE(nodes.ok());
    EXPECT_EQ(nodes.errors[0].message,
              "the image has 257 nodes; this runtime holds at most 256 (its compile-time "
              "capacity; the image was checked against a capacity of 512)");
    const LoadResult tasks = load_mission_image(kImages + "bad/over-limit-tasks.json");
    ASSERT_FALSE(tasks.ok());
    EXPECT_NE(tasks.errors[0].message.find("1025 tasks; this runtime holds at most 1024"),
              std::string::npos)
        << tasks.errors[0].message;
    // A runtime built with a larger capacity flies the same image.
    ImageOptions larger;
    larger.max_nodes = 512;
    larger.max_tasks = 2048;
    EXPECT_EQ(verdict(load_mission_image(kImages + "bad/over-limit-nodes.json", larger)), "ok");
    EXPECT_EQ(verdict(load_mission_image(kImages + "bad/over-limit-tasks.json", larger)), "ok");
}

TEST(ImageLoader, TamperedNamesBothHashes) {
    const LoadResult result = load_mission_image(kImages + "bad/tampered.json");
    ASSERT_FALSE(result.ok());
    EXPECT_NE(result.errors[0].message.find("sha256 mismatch: the image records "),
              std::string::npos);
    EXPECT_NE(result.errors[0].message.find("changed after it was compiled"), std::string::npos);
}

TEST(ImageLoader, UnreadableAndOversizedFiles) {
    EXPECT_EQ(verdict(load_mission_image("/nonexistent/keel/image.json")), "unreadable");
    EXPECT_EQ(verdict(load_mission_image(kImages)), "unreadable");  // a directory
    char name[] = "/tmp/keel-image-big-XXXXXX";
    const int fd = ::mkstemp(name);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::write(fd, "{", 1), 1);
    ASSERT_EQ(::ftruncate(fd, static_cast<off_t>(kMaxImageBytes) + 1), 0);
    ::close(fd);
    const LoadResult big = load_mission_image(name);
    std::remove(name);
    EXPECT_EQ(verdict(big), "over-limit");
}

TEST(ImageLoader, HostileBytesAreRefusedAsNotJson) {
    EXPECT_EQ(verdict_of_bytes("{ this is not JSON"), "not-json");
    EXPECT_EQ(verdict_of_bytes("{\"keel_image\": 1,}"), "not-json");
    EXPECT_EQ(verdict_of_bytes("\xEF\xBB\xBF{\"keel_image\": 1}"), "not-json");
    EXPECT_EQ(verdict_of_bytes("{\"keel_image\": \"\xFF\"}"), "not-json");
    EXPECT_EQ(verdict_of_bytes("{\"x\": 1e999, \"keel_image\": 1}"), "not-json");
    EXPECT_EQ(verdict_of_bytes("{\"x\": \"\\udc00\", \"keel_image\": 1}"), "not-json");
    EXPECT_EQ(verdict_of_bytes("{\"x\": " + std::string(5000, '9') + ", \"keel_image\": 1}"),
              "not-json");
    std::string deep = "{\"keel_image\": 1, \"x\": ";
    deep += std::string(kMaxImageDepth + 10, '[') + std::string(kMaxImageDepth + 10, ']') + "}";
    EXPECT_EQ(verdict_of_bytes(deep), "not-json");
    const LoadResult garbage = load_mission_image_bytes("{\n  \"a\": 1,\n  oops\n}", "g.json");
    ASSERT_FALSE(garbage.ok());
    EXPECT_EQ(garbage.errors[0].line, 3);
    EXPECT_EQ(garbage.errors[0].to_string().rfind("g.json:3:", 0), 0u);
    // JSON, but not an image.
    EXPECT_EQ(verdict_of_bytes("[]"), "format-version");
    EXPECT_EQ(verdict_of_bytes("{\"keel_image\": 1.0}"), "format-version");
    EXPECT_EQ(verdict_of_bytes("{\"keel_image\": true}"), "format-version");
    EXPECT_EQ(verdict_of_bytes("{\"keel_image\": 1}"), "tampered");
}

TEST(ImageLoader, ResealedImagesReachTheLaterChecks) {
    const std::string good = prototype3_with("\"period_ms\":100", "\"period_ms\":100");
    // The prototype3 image with `from` replaced by `to`, sealed again: its verdict.
    auto resealed = [](const std::string& from, const std::string& to) {
        return verdict_of_bytes(sealed(prototype3_with(from, to)));
    };
    EXPECT_EQ(verdict_of_bytes(sealed(good)), "ok");
    // The schema, with integers of 64 bits where integers belong.
    EXPECT_EQ(resealed("\"port\":100", "\"port\":100.5"), "schema");
    EXPECT_EQ(resealed("\"port\":100", "\"port\":70000"), "schema");
    EXPECT_EQ(resealed("\"cpu\":100", "\"cpu\":1" + std::string(30, '0')), "schema");
    EXPECT_EQ(resealed("\"cpu\":100", "\"cpu\":18446744073709551615"), "schema");
    EXPECT_EQ(resealed("\"name\":\"PN1\"", "\"name\":\"P N1\""), "schema");
    EXPECT_EQ(resealed("\"role\":null", "\"role\":\"worker\""), "schema");
    EXPECT_EQ(resealed("[\"taskA\",\"PN2\"]", "[\"taskA\"]"), "schema");
    EXPECT_EQ(resealed("\"verifier\":\"0.2.0\"", "\"verifier\":\"0.2\""), "schema");
    EXPECT_EQ(resealed("\"schema\":1", "\"schema\":1.0"), "schema");
    // Consistency: image.py's, then what the runtime relies on.
    EXPECT_EQ(resealed("\"mission\":\"prototype3\"", "\"mission\":\"other\""), "inconsistent");
    EXPECT_EQ(resealed("\"name\":\"PN2\"", "\"name\":\"PN1\""), "inconsistent");
    EXPECT_EQ(resealed("\"name\":\"PN2\"", "\"name\":\"SAFE\""), "inconsistent");
    EXPECT_EQ(resealed("\"port\":101", "\"port\":100"), "inconsistent");
    EXPECT_EQ(resealed("\"next\":\"P2\"", "\"next\":\"S2\""), "inconsistent");
    EXPECT_EQ(resealed("\"inputs\":[\"taskA\"]", "\"inputs\":[\"taskC\"]"), "inconsistent");
    EXPECT_EQ(resealed("\"role\":\"storage\"", "\"role\":null"), "inconsistent");
    EXPECT_EQ(resealed("\"to\":\"S1\"", "\"to\":\"P1\""), "inconsistent");
    // Capacity, after consistency (as image.py orders them).
    ImageOptions small;
    small.max_nodes = 3;
    EXPECT_EQ(verdict_of_bytes(sealed(good), small), "over-limit");
}

TEST(ImageLoader, TieGraceIsReadWhenStatedAndWrittenOnlyWhenNotZero) {
    // Absent (every shipped image): 0, and the normalised JSON states none, so an image of a
    // mission without it keeps its bytes and hash.
    const LoadResult absent = load_mission_image(kImages + "good/prototype3.json");
    ASSERT_TRUE(absent.ok()) << absent.errors[0].to_string();
    EXPECT_EQ(absent.mission->heartbeat.tie_grace, 0);
    EXPECT_EQ(to_json(*absent.mission).find("tie_grace"), std::string::npos);
    // Stated: read, and written back where keel-verify load writes it.
    const std::string grace = "\"startup_grace_ms\":2000";
    auto with_tie_grace = [&](const std::string& value) {
        const std::string stated = grace + ",\"tie_grace\":" + value;
        return load_mission_image_bytes(sealed(prototype3_with(grace, stated)), "test.json");
    };
    const LoadResult three = with_tie_grace("3");
    ASSERT_TRUE(three.ok()) << three.errors[0].to_string();
    EXPECT_EQ(three.mission->heartbeat.tie_grace, 3);
    EXPECT_NE(to_json(*three.mission).find("\"startup_grace_ms\":2000,\"tie_grace\":3}"),
              std::string::npos);
    const LoadResult most = with_tie_grace("1000");
    ASSERT_TRUE(most.ok()) << most.errors[0].to_string();
    EXPECT_EQ(most.mission->heartbeat.tie_grace, 1000);
    // Out of range or not an integer: refused by the schema, which names the field.
    const std::pair<const char*, const char*> refused[] = {
        {"-1", "content.heartbeat.tie_grace: -1 is less than the minimum of 0"},
        {"1001", "content.heartbeat.tie_grace: 1001 is greater than the maximum of 1000"},
        {"3.5", "content.heartbeat.tie_grace: 3.5 is not of type \"integer\""},
        {"\"3\"", "content.heartbeat.tie_grace: \"3\" is not of type \"integer\""},
    };
    for (const auto& [value, message] : refused) {
        const LoadResult result = with_tie_grace(value);
        EXPECT_EQ(verdict(result), "schema") << value;
        if (!result.errors.empty()) {
            EXPECT_EQ(result.errors[0].message, message) << value;
        }
    }
}

TEST(ImageLoader, PlacementIsReadWhenStatedAndWrittenOnlyWhenNotGraph) {
    // Absent (every graph mission): graph, and the normalised JSON states none.
    const LoadResult absent = load_mission_image(kImages + "good/prototype3.json");
    ASSERT_TRUE(absent.ok()) << absent.errors[0].to_string();
    for (const Phase& phase : absent.mission->phases) {
        EXPECT_EQ(phase.placement, PlacementMode::graph) << phase.name;
    }
    EXPECT_EQ(to_json(*absent.mission).find("\"placement\""), std::string::npos);
    const std::string initial = "\"initial\":\"P1\"";
    auto with_placement = [&](const std::string& value) {
        return load_mission_image_bytes(
            sealed(prototype3_with(initial, initial + ",\"placement\":" + value)), "test.json");
    };
    const LoadResult both = with_placement("\"graph+online\"");
    ASSERT_TRUE(both.ok()) << both.errors[0].to_string();
    EXPECT_EQ(both.mission->phases[0].placement, PlacementMode::graph_online);
    EXPECT_EQ(both.mission->phases[1].placement, PlacementMode::graph);
    EXPECT_NE(to_json(*both.mission).find("\"placement\":\"graph+online\""), std::string::npos);
    const LoadResult graph = with_placement("\"graph\"");
    ASSERT_TRUE(graph.ok()) << graph.errors[0].to_string();
    EXPECT_EQ(to_json(*graph.mission).find("\"placement\""), std::string::npos);
    // The phase has configurations beyond its initial one and failure edges: not online.
    const LoadResult online = with_placement("\"online\"");
    EXPECT_EQ(verdict(online), "inconsistent");
    if (!online.errors.empty()) {
        EXPECT_NE(online.errors[0].message.find("phase nominal: an online phase has only its initial"),
                  std::string::npos)
            << online.errors[0].message;
    }
    const LoadResult unknown = with_placement("\"anywhere\"");
    EXPECT_EQ(verdict(unknown), "schema");
    if (!unknown.errors.empty()) {
        EXPECT_NE(unknown.errors[0].message.find("\"anywhere\" is not one of"), std::string::npos)
            << unknown.errors[0].message;
    }
}

// ---------------------------------------------------------------------------------------
// Signatures

ImageOptions with_key(const std::string& name) {
    ImageOptions options;
    options.public_key_path = kImages + "keys/" + name;
    return options;
}

TEST(ImageSignature, SignedImageVerifiesWithItsKey) {
    ImageSummary summary;
    const LoadResult result =
        load_mission_image(kImages + "good/prototype3.signed.json", with_key("test.pub"), &summary);
    ASSERT_TRUE(result.ok()) << result.errors[0].to_string();
    EXPECT_TRUE(summary.signature_verified);
    EXPECT_EQ(summary.key_id.size(), 16u);
    // Without a key the signature is not checked, and the image still loads.
    EXPECT_EQ(verdict(load_mission_image(kImages + "good/prototype3.signed.json")), "ok");
}

TEST(ImageSignature, RefusedWithAnotherKeyUnsignedOrForged) {
    EXPECT_EQ(verdict(load_mission_image(kImages + "good/prototype3.signed.json",
                                         with_key("other.pub"))),
              "wrong-key");
    const LoadResult unsigned_image =
        load_mission_image(kImages + "good/prototype3.json", with_key("test.pub"));
    EXPECT_EQ(verdict(unsigned_image), "unsigned");
    EXPECT_EQ(verdict(load_mission_image(kImages + "bad/bad-signature.json", with_key("test.pub"))),
              "bad-signature");
    // The same forgery without a key: its hash is right, so it loads; a node that flies
    // only signed images is given the key.
    EXPECT_EQ(verdict(load_mission_image(kImages + "bad/bad-signature.json")), "ok");
}

TEST(ImageSignature, SignatureValueMustDecodeAndVerify) {
    const std::string signed_image = read(kImages + "good/prototype3.signed.json");
    const std::size_t value = signed_image.find("\"value\":\"");
    ASSERT_NE(value, std::string::npos);
    std::string flipped = signed_image;
    char& first = flipped[value + 9];
    first = first == 'A' ? 'B' : 'A';
    EXPECT_EQ(verdict_of_bytes(flipped, with_key("test.pub")), "bad-signature");
    std::string not_base64 = signed_image;
    not_base64[value + 9] = '!';
    EXPECT_EQ(verdict_of_bytes(not_base64, with_key("test.pub")), "bad-signature");
}

TEST(ImageSignature, UnusableKeyFilesAreNamed) {
    ImageOptions missing;
    missing.public_key_path = "/nonexistent/mission.pub";
    const LoadResult result = load_mission_image(kImages + "good/prototype3.json", missing);
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.errors[0].rule, "public-key");
    EXPECT_EQ(result.errors[0].file, "/nonexistent/mission.pub");
    const LoadResult private_key =
        load_mission_image(kImages + "good/prototype3.json", with_key("test.key"));
    ASSERT_FALSE(private_key.ok());
    EXPECT_EQ(private_key.errors[0].rule, "public-key");
    EXPECT_NE(private_key.errors[0].message.find("holds a private key"), std::string::npos);
    EXPECT_EQ(verdict(load_mission_image(kImages + "good/prototype3.json",
                                         with_key("../sources/floats.yaml"))),
              "public-key");
}

// ---------------------------------------------------------------------------------------
// No crash on any byte: seeded mutations of a signed image all end in a verdict.

TEST(ImageLoader, MutatedImagesEndInAVerdict) {
    const std::string signed_image = read(kImages + "good/prototype3.signed.json");
    const std::set<std::string> reasons = {"ok",           "not-json",      "format-version",
                                           "tampered",     "unsigned",      "wrong-key",
                                           "bad-signature", "schema",       "inconsistent",
                                           "over-limit"};
    const ImageOptions key = with_key("test.pub");
    const LoadResult loaded = load_mission_image_bytes(signed_image, "mutant.json", key);
    ASSERT_TRUE(loaded.ok());
    const std::string original = to_json(*loaded.mission);
    std::mt19937 rng(20240601);
    for (int round = 0; round < 600; ++round) {
        std::string bytes = signed_image;
        const int edits = 1 + static_cast<int>(rng() % 3);
        for (int e = 0; e < edits; ++e) {
            const std::size_t at = rng() % bytes.size();
            switch (rng() % 3) {
                case 0:
                    bytes[at] = static_cast<char>(rng() % 256);
                    break;
                case 1:
                    bytes.erase(at, 1 + rng() % 20);
                    break;
                default:
                    bytes.insert(at, bytes.substr(rng() % bytes.size(), 1 + rng() % 20));
                    break;
            }
        }
        const LoadResult with = load_mission_image_bytes(bytes, "mutant.json", key);
        const std::string without = verdict_of_bytes(bytes);
        EXPECT_EQ(reasons.count(verdict(with)), 1u) << verdict(with);
        EXPECT_EQ(reasons.count(without), 1u) << without;
        // Nothing changed in what is hashed and signed, or the image is refused.
        if (with.ok()) {
            EXPECT_EQ(to_json(*with.mission), original);
        }
    }
}

}  // namespace
}  // namespace keel::mission
