// keel-sim flies what a node flies: a proven mission image.
//
// Given a mission image (keel-verify compile's output), keel-sim loads it as keel-node
// does. Given a mission YAML, it compiles it first with keel-verify (the project venv's
// Python, or $KEEL_PYTHON), once per content: the image is kept under
// $TMPDIR/keel-sim-images/SHA256.json, named by the SHA-256 of the YAML's bytes, Keel's
// version and the Python, so later runs of the same file load it at once (a cached image
// this loader refuses is compiled again). The cache keeps the 256 most recently used
// images and removes older ones when it adds one. A mission compile does not prove is
// refused: its report goes to stderr and nothing runs.
#pragma once

#include <optional>
#include <string>

#include "core/mission/mission.hpp"

namespace keel::sim {

// The mission at `path` as the runtime loads it, or nothing with `error` saying why.
std::optional<mission::Mission> load_flown_mission(const std::string& path, std::string* error);

}  // namespace keel::sim
