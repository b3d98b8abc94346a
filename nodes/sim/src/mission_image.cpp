#include "nodes/sim/src/mission_image.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <iterator>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include "core/mission/image.hpp"

extern char** environ;

namespace keel::sim {
namespace {

// How many compiled images $TMPDIR/keel-sim-images keeps (a few kB each).
constexpr std::size_t kCachedImages = 256;

std::string errors_text(const mission::LoadResult& loaded) {
    std::string text;
    for (const auto& error : loaded.errors) text += (text.empty() ? "" : "\n") + error.to_string();
    return text;
}

// keel-verify compile `yaml` -o `image`, its report on stderr; the exit code, or -1.
int compile(const std::string& python, const std::string& yaml, const std::string& image) {
    std::vector<std::string> args = {python, "-m", "keel_verify.cli", "compile", yaml, "-o", image};
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);  // keel-sim's stdout is its own
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, python.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) return -1;
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) return -1;
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Keeps the kCachedImages most recently used images of `cache` (a hit refreshes an image's
// time): the oldest beyond them are removed, never `kept`. Errors leave the cache as it is.
void prune(const std::string& cache, const std::string& kept) {
    namespace fs = std::filesystem;
    std::vector<std::pair<fs::file_time_type, fs::path>> images;
    std::error_code error;
    for (fs::directory_iterator it(cache, error), end; !error && it != end; it.increment(error)) {
        if (it->path().extension() != ".json") continue;
        std::error_code time_error;
        const auto time = it->last_write_time(time_error);
        if (!time_error) images.emplace_back(time, it->path());
    }
    if (error || images.size() <= kCachedImages) return;
    std::sort(images.begin(), images.end());  // oldest first
    for (std::size_t i = 0; i + kCachedImages < images.size(); ++i) {
        if (images[i].second != kept) fs::remove(images[i].second, error);
    }
}

}  // namespace

std::optional<mission::Mission> load_flown_mission(const std::string& path, std::string* error) {
    std::string image = path;
    if (!mission::is_mission_image(path)) {
        std::ifstream in(path, std::ios::binary);
        if (!in) {
            *error = path + ": cannot read: " + std::strerror(errno);
            return std::nullopt;
        }
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const char* tmp = std::getenv("TMPDIR");
        const std::string cache = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/keel-sim-images";
        ::mkdir(cache.c_str(), 0700);
        const char* env = std::getenv("KEEL_PYTHON");
        const std::string python = env != nullptr && *env != '\0' ? env : KEEL_SIM_PYTHON;
        // Named by what it was compiled from and with: the YAML, Keel's version, the Python.
        image = cache + "/" + mission::sha256_text(bytes + '\n' + KEEL_VERSION + '\n' + python) + ".json";
        // An image cached by another build of the verifier that this loader no longer reads
        // is compiled again.
        if (::access(image.c_str(), R_OK) == 0 && !mission::load_mission_image(image).ok()) {
            ::unlink(image.c_str());
        }
        if (::access(image.c_str(), R_OK) == 0) {
            ::utimensat(AT_FDCWD, image.c_str(), nullptr, 0);  // used now: kept longest
        } else {
            if (::access(python.c_str(), X_OK) != 0) {
                *error = path + ": a mission YAML is compiled to an image before it flies, with " +
                         python + ", which is not there (run ./keel setup, set KEEL_PYTHON, or " +
                         "give keel-sim an image: keel-verify compile " + path + " -o IMAGE)";
                return std::nullopt;
            }
            const std::string partial = image + "." + std::to_string(::getpid()) + ".tmp";
            const int code = compile(python, path, partial);
            if (code != 0) {
                ::unlink(partial.c_str());
                *error = path + ": keel-verify compile exited " + std::to_string(code) +
                         ": keel-sim flies only a proven mission (its report is above)";
                return std::nullopt;
            }
            if (std::rename(partial.c_str(), image.c_str()) != 0) {
                *error = image + ": cannot keep the compiled image: " + std::strerror(errno);
                ::unlink(partial.c_str());
                return std::nullopt;
            }
            prune(cache, image);
        }
    }
    mission::LoadResult loaded = mission::load_mission_image(image);
    if (!loaded.ok()) {
        *error = errors_text(loaded) + (image == path ? "" : "\n(compiled from " + path + ")");
        return std::nullopt;
    }
    return std::move(*loaded.mission);
}

}  // namespace keel::sim
