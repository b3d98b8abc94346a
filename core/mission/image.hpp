// The mission image loader: what a node flies.
//
// `keel-verify compile MISSION.yaml -o MISSION.json` proves a mission and writes its image
// (config/schema/README.md, "The mission image"; config/schema/image.schema.json): the
// fully resolved mission, the proof's result, a SHA-256 of the canonical encoding of the
// image and, when compiled with a signing key, an Ed25519 signature over the same bytes.
// This loader is the C++ twin of verify/keel_verify/image.py's `load_image`. It makes the
// same checks in the same order and refuses an image with the first that fails, under the
// same reason ids:
//
//   unreadable      the file cannot be read
//   over-limit      a file over 64 MiB (checked before parsing)
//   not-json        not UTF-8 JSON, a duplicate key, NaN or Infinity, a byte-order mark
//   format-version  no `keel_image` field, or a format other than 1
//   tampered        no `sha256`, or it differs from the hash of the canonical re-encoding
//   unsigned        a public key is configured and the image carries no signature
//   wrong-key       the signature's key id is not the configured key's
//   bad-signature   the signature does not verify with the configured key
//   schema          the image breaks image.schema.json, or holds a float where an
//                   integer belongs
//   inconsistent    content.mission is not mission, or an id is not its entry's index
//   over-limit      more nodes or tasks than this runtime holds or the image's own capacity
//
// After those, it makes the checks the verifier's reader guarantees of every compiled
// image and the runtime relies on (unique names, every reference defined, unique ports,
// roles that fit kinds, health.min <= health.max), reported as `inconsistent`: a forged
// image with a recomputed hash cannot make a node look up a name that is not there. A
// key file that cannot be used is refused with `public-key`.
//
// Every refusal is one LoadError: the image's path, the reason id as its rule, and a
// message; loading never throws for bad input.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "core/fsm/types.hpp"
#include "core/mission/mission.hpp"

namespace keel::mission {

// The image format this loader reads; it refuses every other.
inline constexpr int kImageFormatVersion = 1;
// A loader reads at most this much (keel_verify.image.MAX_IMAGE_BYTES).
inline constexpr std::size_t kMaxImageBytes = 64u * 1024u * 1024u;
// JSON nested deeper than this is refused as not-json (Python's reader gives up near 1,000).
inline constexpr std::size_t kMaxImageDepth = 512;

// The capacity this runtime was compiled with: its node and task sets are bitsets of this
// many bits (core/fsm/types.hpp). An image the verifier checked against a larger capacity
// is refused with over-limit when its mission needs more.
inline constexpr std::size_t kRuntimeMaxNodes = static_cast<std::size_t>(fsm::kMaxNodes);
inline constexpr std::size_t kRuntimeMaxTasks = static_cast<std::size_t>(fsm::kMaxTasks);

struct ImageOptions {
    // An Ed25519 public key (PEM, `openssl pkey -in mission.key -pubout`). Empty: the
    // signature is not checked (the hash still is). Given: only images signed with the
    // matching private key load.
    std::string public_key_path;
    std::size_t max_nodes = kRuntimeMaxNodes;
    std::size_t max_tasks = kRuntimeMaxTasks;
};

// What a loaded image says about itself, for logs.
struct ImageSummary {
    std::string sha256;          // the verified hash of the canonical encoding
    std::string verifier;        // the keel-verify version that proved the mission
    std::string source_file;     // the YAML it was compiled from (file name only)
    std::string key_id;          // the signature's key id; empty when unsigned
    bool signature_verified = false;  // true only when a public key was configured
};

// Loads a mission image. On success the Mission is the one the verifier's reader built
// from the YAML (names, order, defaults), with `path` the image's path and every `line` 0
// (an image has no source positions). `summary`, when given, is filled on success.
LoadResult load_mission_image(const std::string& path, const ImageOptions& options = {},
                              ImageSummary* summary = nullptr);

// The same checks on bytes already read; `path` names them in messages.
LoadResult load_mission_image_bytes(std::string_view bytes, const std::string& path,
                                    const ImageOptions& options = {},
                                    ImageSummary* summary = nullptr);

// True when `bytes` starts, after optional whitespace (and a byte-order mark), with `{`:
// a mission image rather than a YAML mission (which keel-node and keel-mission refuse,
// saying how to compile it).
bool looks_like_image(std::string_view bytes);
// looks_like_image on the start of a regular file; false when it cannot be read or is not
// a regular file (a pipe could not be read again after the look: keel-node and
// keel-mission load it with load_mission_image, which reads it once; keel-sim has
// keel-verify compile it).
bool is_mission_image(const std::string& path);
// The SHA-256 of `bytes` in lowercase hex, as the image's `sha256` is written; empty if
// OpenSSL refuses.
std::string sha256_text(std::string_view bytes);

// The canonical encoding (config/schema/README.md) of a JSON text: sorted keys, no
// whitespace, the image's string escaping, shortest round-trip floats in Python's
// notation. std::nullopt when the text is not JSON the image loader accepts.
std::optional<std::string> canonical_json(std::string_view json_text);

// A double as Python's repr() writes it: the shortest decimal that reads back as the
// same double, positional when 1e-4 <= |x| < 1e16 (`0.0001`, `3.0`), otherwise
// `d[.ddd]e±XX` (`1e+16`, `2.5e-05`). `x` must be finite.
std::string canonical_float(double x);

}  // namespace keel::mission
