#include "test_mission.hpp"

#include <stdexcept>

namespace keel::fsm::testing {

namespace {

keel::mission::Configuration config(const std::string& name, const std::string& phase,
                                     const std::string& master,
                                     std::vector<std::string> observers,
                                     const std::string& task_a, const std::string& task_b) {
    keel::mission::Configuration c;
    c.name = name;
    c.phase = phase;
    c.master = master;
    c.observers = std::move(observers);
    c.placement = {{"taskA", task_a}, {"taskB", task_b}};
    return c;
}

}  // namespace

keel::mission::Mission prototype3() {
    using namespace keel::mission;
    Mission m;
    m.name = "prototype3";
    m.heartbeat = {100, 3};
    m.tolerance.node_failures = 1;
    m.tolerance.nodes = {"PN1", "PN2", "PN3"};
    for (const char* name : {"PN1", "PN2", "PN3"}) {
        Node node;
        node.name = name;
        node.kind = NodeKind::processing;
        m.nodes.push_back(node);
    }
    Node storage;
    storage.name = "ST1";
    storage.kind = NodeKind::interface;
    storage.role = NodeRole::storage;
    m.nodes.push_back(storage);
    Task a;
    a.name = "taskA";
    a.port = 100;
    Task b;
    b.name = "taskB";
    b.port = 101;
    b.essential = true;
    b.checkpoint = true;
    m.tasks = {a, b};

    Phase nominal;
    nominal.name = "nominal";
    nominal.tasks = {"taskA", "taskB"};
    nominal.initial = "P1";
    nominal.configurations = {config("P1", "nominal", "PN1", {"PN2", "PN3"}, "PN2", "PN3"),
                              config("P2", "nominal", "PN2", {"PN3"}, "PN2", "PN3"),
                              config("P3", "nominal", "PN1", {"PN3"}, "PN1", "PN3"),
                              config("P4", "nominal", "PN1", {"PN2"}, "PN2", "PN1")};
    nominal.on_failure = {{"P1", "PN1", "P2"}, {"P1", "PN2", "P3"}, {"P1", "PN3", "P4"},
                          {"P2", "PN2", "SAFE"}, {"P2", "PN3", "SAFE"}, {"P3", "PN1", "SAFE"},
                          {"P3", "PN3", "SAFE"}, {"P4", "PN1", "SAFE"}, {"P4", "PN2", "SAFE"}};
    for (const char* from : {"1", "2", "3", "4"}) {
        nominal.on_phase.push_back({"science", std::string("P") + from, std::string("S") + from});
    }
    Phase science;
    science.name = "science";
    science.tasks = {"taskA", "taskB"};
    science.initial = "S1";
    science.configurations = {config("S1", "science", "PN1", {"PN2", "PN3"}, "PN3", "PN2"),
                              config("S2", "science", "PN2", {"PN3"}, "PN3", "PN2"),
                              config("S3", "science", "PN1", {"PN3"}, "PN3", "PN1"),
                              config("S4", "science", "PN1", {"PN2"}, "PN1", "PN2")};
    science.on_failure = {{"S1", "PN1", "S2"}, {"S1", "PN2", "S3"}, {"S1", "PN3", "S4"},
                          {"S2", "PN2", "SAFE"}, {"S2", "PN3", "SAFE"}, {"S3", "PN1", "SAFE"},
                          {"S3", "PN3", "SAFE"}, {"S4", "PN1", "SAFE"}, {"S4", "PN2", "SAFE"}};
    for (const char* from : {"1", "2", "3", "4"}) {
        science.on_phase.push_back({"nominal", std::string("S") + from, std::string("P") + from});
    }
    m.phases = {nominal, science};
    return m;
}

Topology topology_of(const keel::mission::Mission& mission) {
    std::string error;
    auto topology = Topology::build(mission, &error);
    if (!topology) throw std::runtime_error(error);
    return *topology;
}

Topology prototype3_topology() { return topology_of(prototype3()); }

}  // namespace keel::fsm::testing
