// Data-driven executor scenarios: each file in tests/scenarios/ is a story of commands, each
// followed by `----` and the output it must print. KEEL_REWRITE=1 rewrites the expected
// output from what the executor does (then review the diff).
//
// Commands:
//   task NAME port=N component=C [inputs=A,B] [period=MS] [checkpoint] [min=X] [max=X]
//        [deadline=MS] [param.KEY=INT]     declare a mission task (prints nothing)
//   start                   instantiate, add and activate every declared task
//   advance MS              move the clock
//   run                     run_ready(); prints each task that ran: count and triggers
//   event NAME              raise an event for NAME
//   post PORT VALUE         deliver a counter sample from port PORT to its local consumers
//   stats NAME              the task's counters
//   health                  take_health_events()
//   checkpoints             take_checkpoints()
//   deactivate NAME         prints the final snapshot and keeps it
//   activate NAME           activates again, from the kept snapshot when there is one
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/tasking/builtin.hpp"
#include "core/tasking/executor.hpp"

namespace keel::tasking {
namespace {

namespace fs = std::filesystem;

struct Block {
    std::vector<std::string> comments;  // lines before the command
    std::string command;
    std::string expected;
};

std::vector<Block> parse(const std::string& path) {
    std::ifstream file(path);
    std::vector<Block> blocks;
    Block current;
    std::string line;
    enum { seeking, in_output } state = seeking;
    while (std::getline(file, line)) {
        if (state == seeking) {
            if (line.empty() || line[0] == '#') {
                current.comments.push_back(line);
            } else if (line == "----") {
                state = in_output;
            } else {
                current.command = line;
            }
        } else if (line.empty()) {
            blocks.push_back(current);
            current = Block{};
            state = seeking;
        } else {
            current.expected += line + "\n";
        }
    }
    if (state == in_output || !current.command.empty()) blocks.push_back(current);
    return blocks;
}

std::string hex(const std::vector<std::uint8_t>& bytes) {
    static const char* digits = "0123456789abcdef";
    std::string out;
    for (std::uint8_t byte : bytes) {
        out += digits[byte >> 4];
        out += digits[byte & 15];
    }
    return out;
}

std::string number(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

class Scenario {
  public:
    Scenario() : executor_(clock_) {
        register_builtin_components(registry_);
        mission_.path = "scenario.yaml";
    }

    std::string execute(const std::string& command) {
        std::istringstream words(command);
        std::string verb;
        words >> verb;
        std::vector<std::string> args;
        for (std::string arg; words >> arg;) args.push_back(arg);
        std::ostringstream out;
        if (verb == "task") {
            declare(args);
        } else if (verb == "start") {
            for (InstantiateResult& instance : registry_.instantiate_all(mission_, "")) {
                if (!instance.ok()) {
                    out << instance.error << "\n";
                    continue;
                }
                const std::string name = instance.instance->spec.name;
                const Executor::AddResult added = executor_.add(std::move(*instance.instance));
                if (!added.id) {
                    out << name << ": " << added.result.message << "\n";
                    continue;
                }
                ids_[name] = *added.id;
                const LifecycleResult result = executor_.activate(*added.id);
                out << name << ": " << (result.succeeded() ? "active" : result.message) << "\n";
            }
        } else if (verb == "advance") {
            clock_.advance_ms(std::stoll(args.at(0)));
        } else if (verb == "run") {
            std::map<std::string, TaskStats> before;
            for (const auto& [name, id] : ids_) before[name] = executor_.stats(id);
            const std::size_t executed = executor_.run_ready();
            for (const auto& [name, id] : ids_) {
                const TaskStats after = executor_.stats(id);
                const TaskStats& was = before[name];
                if (after.executions == was.executions) continue;
                out << name << ": ran " << after.executions - was.executions << " (";
                const char* separator = "";
                for (auto [label, count] : {std::pair{"inputs", after.by_inputs - was.by_inputs},
                                            std::pair{"timer", after.by_timer - was.by_timer},
                                            std::pair{"event", after.by_event - was.by_event}}) {
                    if (count == 0) continue;
                    out << separator << label << " " << count;
                    separator = ", ";
                }
                out << ")";
                if (after.last_control_value) {
                    out << " control " << number(*after.last_control_value);
                }
                out << "\n";
            }
            out << "executed " << executed << "\n";
        } else if (verb == "event") {
            out << (executor_.raise_event(ids_.at(args.at(0))) ? "raised" : "refused") << "\n";
        } else if (verb == "post") {
            Sample sample;
            sample.type_id = counter_type_id;
            sample.source_port = std::stoll(args.at(0));
            sample.payload = make_payload(counter_payload(std::stoll(args.at(1))));
            out << "delivered to " << executor_.deliver(sample) << "\n";
        } else if (verb == "stats") {
            const TaskStats stats = executor_.stats(ids_.at(args.at(0)));
            out << "executions " << stats.executions << " successes " << stats.successes
                << " failures " << stats.failures << " errors " << stats.errors << "\n"
                << "inputs received " << stats.inputs_received << " dropped "
                << stats.inputs_dropped << " mistyped " << stats.inputs_mistyped << "\n"
                << "outputs " << stats.outputs << " periods missed " << stats.periods_missed
                << "\n";
        } else if (verb == "health") {
            const auto events = executor_.take_health_events();
            if (events.empty()) out << "none\n";
            for (const HealthEvent& event : events) {
                out << event.at_ms << " " << event.task << " " << to_string(event.kind) << ": "
                    << event.detail << "\n";
            }
        } else if (verb == "checkpoints") {
            const auto taken = executor_.take_checkpoints();
            if (taken.empty()) out << "none\n";
            for (const Snapshot& snapshot : taken) {
                out << snapshot.task << " #" << snapshot.sequence << " v" << snapshot.format_version
                    << " " << hex(snapshot.payload) << "\n";
            }
        } else if (verb == "deactivate") {
            const auto state = executor_.deactivate(ids_.at(args.at(0)));
            if (!state) {
                out << "not active\n";
            } else {
                out << state->task << " #" << state->sequence << " v" << state->format_version
                    << " " << hex(state->payload) << "\n";
                kept_[args.at(0)] = *state;
            }
        } else if (verb == "activate") {
            const auto kept = kept_.find(args.at(0));
            const std::optional<Snapshot> from =
                kept == kept_.end() ? std::nullopt : std::optional<Snapshot>(kept->second);
            const LifecycleResult result = executor_.activate(ids_.at(args.at(0)), from);
            out << (result.succeeded()
                        ? "active"
                        : std::string(to_string(result.outcome)) + ": " + result.message)
                << (from ? " (restored)" : "") << "\n";
        } else {
            out << "unknown command '" << verb << "'\n";
        }
        return out.str();
    }

  private:
    void declare(const std::vector<std::string>& args) {
        mission::Task task;
        task.name = args.at(0);
        task.line = static_cast<int>(mission_.tasks.size() + 1);
        for (std::size_t index = 1; index < args.size(); ++index) {
            const std::string& arg = args[index];
            const auto equals = arg.find('=');
            const std::string key = arg.substr(0, equals);
            const std::string value = equals == std::string::npos ? "" : arg.substr(equals + 1);
            auto health = [&]() -> mission::Health& {
                if (!task.health) task.health = mission::Health{};
                return *task.health;
            };
            if (key == "port") {
                task.port = std::stoll(value);
            } else if (key == "component") {
                task.component = value;
            } else if (key == "inputs") {
                std::istringstream names(value);
                for (std::string name; std::getline(names, name, ',');) task.inputs.push_back(name);
            } else if (key == "period") {
                task.period_ms = std::stoll(value);
            } else if (key == "checkpoint") {
                task.checkpoint = true;
            } else if (key == "min") {
                health().min = std::stod(value);
            } else if (key == "max") {
                health().max = std::stod(value);
            } else if (key == "deadline") {
                health().deadline_ms = std::stoll(value);
            } else if (key.starts_with("param.")) {
                task.params.emplace_back(key.substr(6), std::int64_t{std::stoll(value)});
            } else {
                ADD_FAILURE() << "unknown task attribute '" << key << "'";
            }
        }
        mission_.tasks.push_back(task);
    }

    ManualClock clock_;
    Executor executor_;
    ComponentRegistry registry_;
    mission::Mission mission_;
    std::map<std::string, TaskId> ids_;
    std::map<std::string, Snapshot> kept_;
};

fs::path scenario_dir() {
    const char* root = std::getenv("KEEL_ROOT");
    return fs::path(root != nullptr ? root : ".") / "core/tasking/tests/scenarios";
}

class ScenarioTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ScenarioTest, MatchesItsGoldenOutput) {
    const fs::path path = scenario_dir() / GetParam();
    const std::vector<Block> blocks = parse(path.string());
    ASSERT_FALSE(blocks.empty()) << "no commands in " << path;
    Scenario scenario;
    const bool rewrite = std::getenv("KEEL_REWRITE") != nullptr;
    std::ostringstream rewritten;
    for (const Block& block : blocks) {
        const std::string actual = scenario.execute(block.command);
        if (!rewrite) {
            EXPECT_EQ(actual, block.expected) << path.filename().string() << ": " << block.command;
        }
        for (const std::string& comment : block.comments) rewritten << comment << "\n";
        rewritten << block.command << "\n----\n" << actual << "\n";
    }
    if (rewrite) {
        std::string text = rewritten.str();
        text.pop_back();  // no blank line after the last block
        std::ofstream(path) << text;
    }
}

INSTANTIATE_TEST_SUITE_P(Scenarios, ScenarioTest,
                         ::testing::Values("prototype3.txt", "health.txt", "overflow.txt"),
                         [](const ::testing::TestParamInfo<std::string>& param_info) {
                             return param_info.param.substr(0, param_info.param.find('.'));
                         });

}  // namespace
}  // namespace keel::tasking
