// keel-mission FILE [--json]: load a mission file (YAML) or image with the C++ readers, and
// build the runtime's topology from it as keel-node does at boot: what loads here is what a
// node accepts (but for its components: keel-node --list-components).
//
// The C++ side of the loader contract (config/schema/README.md); `keel-verify load` is the
// Python side. On success: exit 0, and with --json the normalised mission on stdout (the
// same JSON `keel-verify load --json` prints). On failure: every error as
// `FILE:LINE:COL: RULE: message` on stderr, nothing on stdout, exit 2 for input (shape)
// errors and 1 when the only errors are unknown references or port conflicts.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

#include "core/fsm/topology.hpp"
#include "core/mission/mission.hpp"

int main(int argc, char** argv) {
    CLI::App app{"Load a Keel mission file (schema 1) and print it normalised.", "keel-mission"};
    std::string path;
    bool json = false;
    app.add_option("mission", path, "mission file (YAML, schema 1)")->required();
    app.add_flag("--json", json, "print the normalised mission as JSON");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);
        return code == 0 ? 0 : 2;
    }

    try {
        const keel::mission::LoadResult result = keel::mission::load_mission_file(path);
        if (!result.ok()) {
            for (const keel::mission::LoadError& error : result.errors) {
                std::cerr << error.to_string() << '\n';
            }
            return result.exit_code();
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
        std::cerr << path << ":1:1: yaml-syntax: " << error.what() << '\n';
        return 2;
    }
}
