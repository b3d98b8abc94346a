// The earth-observation libraries (sensor, ACCA, sink, AOCS) as tasking components, and
// the sample formats they exchange. DESIGN.md explains how the image stream is split
// between the ACCA workers and why no image is lost or classified twice across a failover.
//
//   sensor    periodic; emits one scene (type scene_type_id, the KSCN wire format) per
//             period from a pool of distinct synthetic scenes generated in the background;
//             keeps every scene it emitted until the sink's accounting says it was recorded,
//             and emits it again when it was not recorded within `resend_after_ms`.
//   acca      classifies the scenes whose sequence number is its own (worker_index modulo
//             worker_count); emits a classified image (classified_type_id). Control value:
//             the cloud fraction.
//   sink      records every classified image once (overlay PNG + a stats.ndjson line) and
//             emits its accounting (accounting_type_id) after each execution that recorded
//             something.
//   aocs      the attitude filter against a truth simulator running on the wall clock;
//             checkpointed; after a migration restores, fast-forwards the simulator and
//             replays the missed gyro samples. Control value: attitude one-sigma (rad).
//   downlink  takes the sink's accounting and records what is ready to send.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/tasking/registry.hpp"
#include "core/tasking/sample.hpp"
#include "keel/eo/acca.hpp"
#include "keel/eo/scene.hpp"
#include "keel/eo/sink.hpp"

namespace keel::eo::components {

inline constexpr tasking::TypeId scene_type_id = 0x454F0001;       // KSCN scene
inline constexpr tasking::TypeId classified_type_id = 0x454F0002;  // ClassifiedImage
inline constexpr tasking::TypeId accounting_type_id = 0x454F0003;  // Accounting
inline constexpr tasking::TypeId attitude_type_id = 0x454F0004;    // AttitudeReport

// Reads the sequence number from a KSCN header without decoding (or checksumming) the
// pixels: a worker skips the scenes that are not its own at the cost of a few bytes.
// Nothing when the bytes are not a KSCN header.
std::optional<std::uint64_t> peek_scene_sequence(std::span<const std::uint8_t> bytes);

// A scene's KSCN bytes with its sequence number replaced and the checksum fixed, given
// the CRC-32 of everything after the header (pixels and mask), so re-stamping a 20 MB
// scene costs a copy, not a checksum over it.
std::vector<std::uint8_t> restamp_scene(std::span<const std::uint8_t> scene_bytes,
                                        std::uint64_t sequence, std::uint32_t body_crc);
// The CRC-32 of a KSCN buffer's body (after the header, before the trailing checksum).
std::uint32_t scene_body_crc(std::span<const std::uint8_t> scene_bytes);

// What an ACCA worker sends the sink for one scene. Little-endian:
//   u32 magic 'KCLS' | u16 version (1) | u16 flags (bit 0 truth, bit 1 resent result)
//   u64 sequence | u64 seed | u32 worker_pid | u32 classified_count | string worker task
//   f64 truth_cloud_fraction | u64 tp, fp, fn, tn | bytes acca result (KMSK)
//   bytes quick-look scene (KSCN, bands and truth reduced) | u32 CRC-32
struct ClassifiedImage {
    std::uint64_t sequence = 0;
    std::uint64_t seed = 0;
    std::string worker;                           // the ACCA task
    std::uint32_t worker_pid = 0;                 // the process (node) that classified it
    std::uint32_t classified = 0;                 // how many times this instance classified it (1)
    bool resent = false;                          // a cached result sent again for a resent scene
    std::optional<sink::Confusion> versus_truth;  // full resolution, computed by the worker
    double truth_cloud_fraction = 0;
    acca::Result result;  // full-resolution mask and counts
    Scene quicklook;      // reduced scene (and truth) for the overlay
};
inline constexpr std::uint32_t kClassifiedMagic = 0x534C434BU;  // "KCLS"
std::vector<std::uint8_t> serialise(const ClassifiedImage& image);
// Throws keel::eo::DecodeError for malformed, truncated or corrupt buffers.
ClassifiedImage deserialise_classified(std::span<const std::uint8_t> bytes);

// The sink's accounting: every sequence number up to `watermark` is recorded, and so are
// `recorded_above` (sorted, at most accounting_list_max). Little-endian:
//   u32 magic 'KACC' | u16 version (1) | u16 count | u64 watermark | u64 recorded
//   u64 duplicates | count x u64 | u32 CRC-32
struct Accounting {
    std::uint64_t watermark = 0;
    std::uint64_t recorded = 0;    // images recorded in total
    std::uint64_t duplicates = 0;  // results received for an image already recorded
    std::vector<std::uint64_t> recorded_above;

    bool covers(std::uint64_t sequence) const;
};
inline constexpr std::uint32_t kAccountingMagic = 0x4343414BU;  // "KACC"
inline constexpr std::size_t accounting_list_max = 512;
std::vector<std::uint8_t> serialise(const Accounting& accounting);
Accounting deserialise_accounting(std::span<const std::uint8_t> bytes);

tasking::ComponentPtr make_sensor_component();
tasking::ComponentPtr make_acca_component();
tasking::ComponentPtr make_sink_component();
tasking::ComponentPtr make_aocs_component();
tasking::ComponentPtr make_downlink_component();

// Registers sensor, acca, sink, aocs and downlink. False if any name was taken.
bool register_eo_components(tasking::ComponentRegistry& registry);

// Where components write files (overlays, stats.ndjson, aocs.ndjson): the `out_dir`
// parameter, else $KEEL_EO_OUT_DIR, else ./eo-out.
std::string output_directory(const std::string& parameter);

}  // namespace keel::eo::components
