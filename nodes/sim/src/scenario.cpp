#include "nodes/sim/src/scenario.hpp"

#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

#include "core/fsm/json.hpp"
#include "core/mission/mission.hpp"
#include "nodes/sim/src/mission_image.hpp"
#include "nodes/sim/src/simulation.hpp"
#include "nodes/sim/src/util.hpp"

namespace keel::sim {

namespace {

struct Block {
    std::vector<std::string> comments;
    std::string command;
    std::string expected;
    int line = 0;
};

std::vector<Block> parse_blocks(const std::string& text) {
    std::vector<Block> blocks;
    std::istringstream in(text);
    std::string line;
    int number = 0;
    Block current;
    enum { command, separator, output } state = command;
    auto flush = [&] {
        if (!current.command.empty()) blocks.push_back(current);
        current = Block{};
        state = command;
    };
    while (std::getline(in, line)) {
        ++number;
        if (line.empty()) {
            if (state == output) flush();
            continue;
        }
        if (state == command) {
            if (line[0] == '#') {
                current.comments.push_back(line);
                continue;
            }
            current.command = line;
            current.line = number;
            state = separator;
        } else if (state == separator) {
            if (line == "----") {
                state = output;
            } else {
                current.expected += "";  // a command without expected output yet
                flush();
                current.command = line;
                current.line = number;
                state = separator;
            }
        } else {
            current.expected += line + "\n";
        }
    }
    if (!current.command.empty()) blocks.push_back(current);
    return blocks;
}

std::string seconds(TimeNs t) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.3fs", static_cast<double>(t) / 1e9);
    return buffer;
}

class ScenarioRunner {
public:
    ScenarioRunner(std::string root, std::ofstream* trace, ScenarioVariant variant)
        : root_(std::move(root)), trace_(trace), variant_(variant) {}

    std::string run(const std::string& command_line) {
        output_.clear();
        const auto words = split_words(command_line);
        if (words.empty()) return "error: empty command\n";
        const std::string& verb = words[0];
        if (verb == "mission") return load(words);
        if (!topology_) return "error: the first command must be `mission PATH`\n";
        const auto& topology = *topology_;
        auto node_arg = [&](std::size_t index) -> std::optional<NodeId> {
            if (index >= words.size()) return std::nullopt;
            return topology.node_id(words[index]);
        };
        if (verb == "boot") {
            // boot NODE at DURATION: the node's process starts late (before anything runs).
            if (words.size() != 4 || words[2] != "at") return "error: boot NODE at DURATION\n";
            if (sim_) return "error: boot must come before the first command that runs the cluster\n";
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            auto at = parse_duration(words[3]);
            if (!at || *at < 0) return "error: bad duration " + words[3] + "\n";
            options_.boot_ns.resize(static_cast<std::size_t>(topology.node_count()), 0);
            options_.boot_ns[*node] = *at;
            return "ok\n";
        }
        // The cluster boots at the first command that is not `boot`.
        if (!sim_) start();
        if (verb == "tick" && words.size() == 2) {
            auto duration = parse_duration(words[1]);
            if (!duration) return "error: bad duration " + words[1] + "\n";
            sim_->run_for(*duration);
        } else if (verb == "restart" && words.size() == 3 && words[2] == "rolled-back") {
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            sim_->restart(*node, true);
        } else if ((verb == "crash" || verb == "restart" || verb == "resign") && words.size() == 2) {
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            if (verb == "crash") {
                sim_->crash(*node);
            } else if (verb == "restart") {
                sim_->restart(*node);
            } else {
                sim_->resign(*node);
            }
        } else if ((verb == "disk-fail" || verb == "disk-full") && words.size() == 2) {
            // The node's disk fails every write from now, or (full) every checkpoint write.
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            if (verb == "disk-fail") {
                sim_->fail_disk(*node);
            } else {
                sim_->fill_disk(*node);
            }
        } else if (verb == "power-loss" && (words.size() == 2 || (words.size() == 3 && words[2] == "checkpoint"))) {
            // Power is lost at the node's next write (or its next checkpoint write).
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            sim_->power_loss_at_write(*node, words.size() == 3);
        } else if (verb == "disk" && words.size() == 3) {
            // How long a checkpoint write takes: `disk 50ms 200ms` (a slow disk).
            auto low = parse_duration(words[1]);
            auto high = parse_duration(words[2]);
            if (!low || !high || *low < 0 || *high < *low) return "error: bad write latency\n";
            sim_->set_disk(DiskModel{*low, *high});
        } else if (verb == "deaf" && words.size() == 2) {
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            sim_->deaf(*node);
        } else if (verb == "pause" && words.size() == 3) {
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            auto duration = parse_duration(words[2]);
            if (!duration || *duration <= 0) return "error: bad duration " + words[2] + "\n";
            sim_->pause(*node, *duration);
        } else if (verb == "partition") {
            return partition(words);
        } else if (verb == "heal") {
            sim_->heal();
        } else if (verb == "loss" && words.size() == 2) {
            auto rate = parse_rate(words[1]);
            if (!rate) return "error: bad rate " + words[1] + "\n";
            auto network = sim_->network();
            network.loss = *rate;
            sim_->set_network(network);
        } else if (verb == "phase" && words.size() == 2) {
            auto phase = topology.phase_id(words[1]);
            if (!phase) return "error: unknown phase " + words[1] + "\n";
            sim_->request_phase(*phase);
        } else if (verb == "recover" && words.size() == 2) {
            auto config = topology.config_id(words[1]);
            if (!config || *config == fsm::kSafeConfig) return "error: unknown configuration " + words[1] + "\n";
            const std::string why = sim_->request_recovery(*config);
            if (!why.empty()) output_ += "refused: " + why + "\n";
        } else if ((verb == "exclude" || verb == "readmit") && words.size() == 2) {
            // A ground command, as every node takes it (core/node/ground.hpp).
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            const std::string why = sim_->ground_hold(*node, verb == "exclude");
            if (!why.empty()) output_ += "refused: " + why + "\n";
        } else if (verb == "designate" && (words.size() == 2 || words.size() == 4)) {
            // The ground's vote (spec/Designate.tla): `designate NODE [WAIT SPAN]`, in
            // periods (default: as the ground computes them, Simulation::ground_designate).
            auto node = node_arg(1);
            if (!node) return "error: unknown node " + words[1] + "\n";
            std::string why;
            if (words.size() == 2) {
                why = sim_->ground_designate(*node);
            } else {
                int wait = 0;
                int span = 0;
                try {
                    wait = std::stoi(words[2]);
                    span = std::stoi(words[3]);
                } catch (const std::exception&) {
                    return "error: designate NODE [WAIT SPAN], both whole periods\n";
                }
                why = sim_->ground_designate(*node, wait, span);
            }
            if (!why.empty()) output_ += "refused: " + why + "\n";
        } else if ((verb == "pause-task" || verb == "resume-task") && words.size() == 2) {
            // The ground's pause of a task, as every node takes it (core/node/ground.hpp).
            auto task = topology.task_id(words[1]);
            if (!task) return "error: unknown task " + words[1] + "\n";
            const std::string why = sim_->ground_pause(*task, verb == "pause-task");
            if (!why.empty()) output_ += "refused: " + why + "\n";
        } else if (verb == "stabilize") {
            const auto took = sim_->stabilize(std::max<TimeNs>(20'000 * kMs, 100 * topology.heartbeat_period_ns()));
            report_violations();
            if (took) output_ += "agreement after " + std::to_string(*took / kMs) + "ms\n";
            return finish();
        } else if (verb == "status") {
            return output_ + status();  // the boot lines first when this command booted the cluster
        } else if (verb == "checkpoints") {
            return output_ + checkpoints();
        } else if (verb == "overlaps") {
            // Fault model 2's overlap measures so far (Simulation::two_masters_ns, double_run_ns).
            char line[160];
            std::snprintf(line, sizeof line, "two running Masters %.1f ms, a task on two running nodes %.1f ms\n",
                          static_cast<double>(sim_->two_masters_ns()) / 1e6,
                          static_cast<double>(sim_->double_run_ns()) / 1e6);
            return output_ + line;
        } else {
            return "error: unknown command: " + command_line + "\n";
        }
        report_violations();
        return finish();
    }

private:
    std::string finish() {
        return output_.empty() ? "ok\n" : output_;
    }

    void report_violations() {
        const auto& violations = sim_->violations();
        for (; reported_ < violations.size(); ++reported_) {
            const auto& v = violations[reported_];
            output_ += seconds(v.t_ns) + " VIOLATION " + v.invariant + ": " + v.message + "\n";
        }
        // Scenarios go on after a violation so the whole story is visible.
        sim_->stop_on_violation = false;
    }

    std::string load(const std::vector<std::string>& words) {
        if (words.size() < 2) return "error: mission PATH\n";
        const std::string path = words[1].front() == '/' ? words[1] : root_ + "/" + words[1];
        std::string error;
        auto loaded = load_flown_mission(path, &error);
        if (!loaded) return error + "\n";
        mission_ = std::make_unique<keel::mission::Mission>(std::move(*loaded));
        auto topology = fsm::Topology::build(*mission_, &error);
        if (!topology) return "error: " + error + "\n";
        topology_ = std::make_unique<fsm::Topology>(*topology);
        options_ = SimOptions{};
        options_.tracing = true;
        for (std::size_t i = 2; i < words.size(); ++i) {
            const auto& word = words[i];
            if (word.rfind("seed=", 0) == 0) {
                options_.seed = std::stoull(word.substr(5));
            } else {
                return "error: unknown option " + word + "\n";
            }
        }
        if (variant_.seed) options_.seed = *variant_.seed;
        options_.mutant = variant_.mutant;
        sim_.reset();
        reported_ = 0;
        return "mission " + std::string(topology_->mission_name()) + ": " +
               std::to_string(topology_->node_count()) + " nodes, " +
               std::to_string(topology_->task_count()) + " tasks, heartbeat " +
               std::to_string(topology_->heartbeat_period_ns() / kMs) + "ms x " +
               std::to_string(topology_->miss_limit()) + "\n";
    }

    // Builds the cluster (every node whose process starts at time zero boots now).
    void start() {
        sim_ = std::make_unique<Simulation>(*topology_, options_, [this](Simulation& sim) {
            sim.stop_on_violation = false;
            sim.on_action = [this](TimeNs t, NodeId node, const fsm::Action& action) {
                note(t, node, action);
                const auto* event = std::get_if<fsm::act::Trace>(&action);
                if (trace_ != nullptr && event != nullptr) {
                    write_trace_line(*trace_, t, topology_->node_name(node), event->fsm,
                                     event->action, event->args, event->vars);
                }
            };
            sim.on_environment = [this](TimeNs t, const char* action, const std::string& args) {
                if (trace_ != nullptr) write_env_line(*trace_, t, action, args);
                // A late boot happens inside a tick: say when.
                if (std::string(action) == "Boot") {
                    output_ += seconds(t) + " boot " + flat_json_to_words(args) + "\n";
                }
            };
        });
    }

    void note(TimeNs t, NodeId node, const fsm::Action& action) {
        if (std::holds_alternative<fsm::act::EnterSafeMode>(action)) {
            output_ += seconds(t) + " " + topology_->node_name(node) + " EnterSafeMode\n";
            return;
        }
        const auto* trace = std::get_if<fsm::act::Trace>(&action);
        if (trace == nullptr) return;
        const std::string fsm_name = trace->fsm;
        const std::string name = trace->action;
        const bool notable =
            (fsm_name == "heartbeat" && name == "DeclareFailed") ||
            (fsm_name == "election" && (name == "BecomeMaster" || name == "WarmBoot")) ||
            (fsm_name == "switch" &&
             (name == "Exclude" || name == "RequestPhase" || name == "BroadcastCommand" ||
              name == "CompleteSwitch" || name == "Activate" || name == "Deactivate" ||
              name == "Resign" || name == "Resigned" || name == "AskExclusion" ||
              name == "Readmit" || name == "HandOver" || name == "AskHolders" ||
              name == "StateOutOfReach" || name == "GroundRecovery"));
        if (!notable) return;
        output_ += seconds(t) + " " + topology_->node_name(node) + " " + fsm_name + "." + name +
                   " " + flat_json_to_words(trace->args) + "\n";
    }

    std::string partition(const std::vector<std::string>& words) {
        NodeSet a;
        NodeSet b;
        bool one_way = false;
        bool second = false;
        for (std::size_t i = 1; i < words.size(); ++i) {
            if (words[i] == "|" || words[i] == "->") {
                if (second) return "error: partition A B | C D, or partition A -> B C\n";
                second = true;
                one_way = words[i] == "->";
                continue;
            }
            auto node = topology_->node_id(words[i]);
            if (!node) return "error: unknown node " + words[i] + "\n";
            (second ? b : a).insert(*node);
        }
        if (!second || a.empty() || b.empty()) return "error: partition A B | C D, or partition A -> B C\n";
        if (one_way) {
            a.for_each([&](NodeId x) { b.for_each([&](NodeId y) { sim_->block(x, y); }); });
        } else {
            sim_->partition(a, b);
        }
        report_violations();
        return finish();
    }

    // Per checkpointed task: the latest version the Storage node holds, and where the task
    // runs with its counter (the fake task's state, one step per period).
    std::string checkpoints() {
        std::string out;
        const auto& topology = *topology_;
        const NodeId storage = topology.storage_node();
        for (TaskId task = 0; task < topology.task_count(); ++task) {
            if (!topology.task(task).checkpoint) continue;
            out += topology.task(task).name + ": ";
            if (storage == fsm::kNoNode || !sim_->booted(storage) || !sim_->alive(storage)) {
                out += "no storage node up";
            } else {
                const auto stored = sim_->node(storage).store()->latest_version(task);
                out += topology.node_name(storage) + " holds " +
                       (stored ? "version " + fsm::version_text(*stored) : std::string("nothing"));
            }
            std::string runs;
            for (NodeId n = 0; n < topology.node_count(); ++n) {
                if (!sim_->alive(n) || !sim_->running(n).contains(task)) continue;
                runs += (runs.empty() ? "" : ", ") + topology.node_name(n) + " at step " +
                        std::to_string(sim_->counter(n, task));
            }
            out += "; runs on " + (runs.empty() ? std::string("no node") : runs) + "\n";
        }
        return out.empty() ? "no checkpointed task\n" : out;
    }

    std::string status() {
        std::string out;
        const auto& topology = *topology_;
        for (NodeId n = 0; n < topology.node_count(); ++n) {
            out += topology.node_name(n) + " ";
            if (!sim_->booted(n)) {
                out += "not booted\n";
                continue;
            }
            if (!sim_->alive(n)) {
                out += "down\n";
                continue;
            }
            const auto& protocol = sim_->node(n);
            const auto& view = protocol.view();
            out += std::string(protocol.config_switch().excluded() ? "excluded" : fsm::to_string(protocol.role())) +
                   " epoch=" + std::to_string(protocol.epoch()) + " view=" +
                   topology.config_name(view.config) + "/" + std::to_string(view.epoch) + "." +
                   std::to_string(view.seq) + " " + fsm::to_string(protocol.config_switch().stage()) +
                   " tasks=" + fsm::json_tasks(topology, sim_->running(n));
            if (!view.failed.empty()) out += " failed=" + fsm::json_nodes(topology, view.failed);
            out += "\n";
        }
        return out;
    }

    std::string root_;
    std::unique_ptr<keel::mission::Mission> mission_;
    std::unique_ptr<fsm::Topology> topology_;
    SimOptions options_;
    std::unique_ptr<Simulation> sim_;
    std::ofstream* trace_ = nullptr;  // NDJSON trace of the scenario, when asked for
    ScenarioVariant variant_;
    std::string output_;
    std::size_t reported_ = 0;
};

}  // namespace

ScenarioResult run_scenario_file(const std::string& path, const std::string& root,
                                 const std::string& trace_path, const ScenarioVariant& variant) {
    ScenarioResult result;
    std::ifstream in(path);
    if (!in) {
        result.diff = path + ": cannot read\n";
        return result;
    }
    std::stringstream buffer;
    buffer << in.rdbuf();
    const auto blocks = parse_blocks(buffer.str());
    std::ofstream trace;
    if (!trace_path.empty()) {
        trace.open(trace_path);
        if (!trace) {
            result.diff = trace_path + ": cannot write the trace\n";
            return result;
        }
    }
    ScenarioRunner runner(root, trace.is_open() ? &trace : nullptr, variant);
    bool first = true;
    result.passed = true;
    for (const auto& block : blocks) {
        const std::string actual = runner.run(block.command);
        for (std::size_t at = actual.find(" VIOLATION "); at != std::string::npos;
             at = actual.find(" VIOLATION ", at + 1)) {
            ++result.violations;
        }
        if (actual != block.expected) {
            result.passed = false;
            result.diff += path + ":" + std::to_string(block.line) + ": " + block.command +
                           "\n--- expected\n" + block.expected + "--- actual\n" + actual;
        }
        if (!first) result.rewritten += "\n";
        first = false;
        for (const auto& comment : block.comments) result.rewritten += comment + "\n";
        result.rewritten += block.command + "\n----\n" + actual;
    }
    return result;
}

}  // namespace keel::sim
