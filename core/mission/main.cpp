// keel-mission IMAGE [--json] [--public-key KEY]: load a mission image as keel-node does at
// boot (the image loader's checks, then the runtime's topology): what loads here is what a
// node accepts, but for its components (keel-node --list-components).
//
// On success: exit 0, and with --json the normalised mission on stdout (the JSON
// `keel-verify load --json` prints for the YAML the image was compiled from, up to
// whitespace and key order). On failure: the refusal as `FILE:LINE:COL: REASON: message` on
// stderr (the reasons of core/mission/image.hpp), nothing on stdout, exit 2. A mission YAML
// is refused the same way, saying how to compile it: only the verifier reads YAML.
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <system_error>
#include <iostream>
#include <string>

#include "core/fsm/topology.hpp"
#include "core/mission/image.hpp"
#include "core/mission/mission.hpp"

int main(int argc, char** argv) {
    CLI::App app{"Load a Keel mission image as a node loads it and print what it holds.",
                 "keel-mission"};
    std::string path;
    std::string public_key;
    bool json = false;
    app.add_option("image", path, "mission image (keel-verify compile MISSION.yaml -o IMAGE.json)")
        ->required();
    app.add_option("--public-key", public_key,
                   "Ed25519 public key (PEM): refuse an image not signed with its private key");
    app.add_flag("--json", json, "print the normalised mission as JSON");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);
        return code == 0 ? 0 : 2;
    }

    try {
        std::error_code ignored;
        if (!keel::mission::is_mission_image(path) && ::access(path.c_str(), R_OK) == 0 &&
            std::filesystem::is_regular_file(path, ignored)) {
            std::cerr << path << ":1:1: not-an-image: a mission YAML is read by keel-verify "
                      << "only; compile it: keel-verify compile " << path << " -o IMAGE.json\n";
            return 2;
        }
        keel::mission::ImageOptions options;
        options.public_key_path = public_key;
        const keel::mission::LoadResult result = keel::mission::load_mission_image(path, options);
        if (!result.ok()) {
            for (const keel::mission::LoadError& error : result.errors) {
                std::cerr << error.to_string() << '\n';
            }
            return 2;
        }
        const keel::mission::Mission& mission = *result.mission;
        std::string why;
        if (!keel::fsm::Topology::build(mission, &why)) {
            std::cerr << path << ":1:1: topology: " << why << '\n';
            return 2;
        }
        if (json) {
            std::cout << keel::mission::to_json(mission) << '\n';
        } else {
            std::size_t configurations = 0;
            for (const auto& phase : mission.phases) configurations += phase.configurations.size();
            std::cout << path << ": mission " << mission.name << ": " << mission.nodes.size()
                      << " nodes, " << mission.tasks.size() << " tasks, " << mission.phases.size()
                      << " phases, " << configurations << " configurations\n";
        }
        std::cout.flush();
        return std::cout ? 0 : 2;
    } catch (const std::exception& error) {
        std::cerr << path << ":1:1: unreadable: " << error.what() << '\n';
        return 2;
    }
}
