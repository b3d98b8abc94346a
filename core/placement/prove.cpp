#include "core/placement/prove.hpp"

#include <algorithm>
#include <cassert>
#include <unordered_map>
#include <unordered_set>

#include "core/placement/check.hpp"
#include "core/placement/place.hpp"

namespace keel::placement {

namespace {

// A graph edge's target: a configuration's index in the phase, or one of these.
constexpr int kEdgeMissing = -1;
constexpr int kEdgeSafe = -2;

std::size_t index(int id) { return static_cast<std::size_t>(id); }

// Outcomes of a failed set, worst last.
enum class Outcome : std::uint8_t { running, shedding, safe };

struct FailedSetOutcome {
    Outcome worst = Outcome::running;
    std::vector<bool> shed;  // per task id, over every order
};

// What a failure leads to.
struct Step {
    enum class Kind { graph, online, safe, mismatch, invalid } kind = Kind::safe;
    int graph = kNone;      // Kind::graph: the configuration's index
    Configuration config;   // Kind::graph and Kind::online
    std::vector<Finding> findings;  // Kind::invalid
    int elected = kNone;    // Kind::mismatch
};

class Explorer {
  public:
    Explorer(const mission::Mission& mission, const Model& model, int phase, int failures,
             std::int64_t max_transitions, PhaseProof& out)
        : mission_(mission), model_(model), phase_(phase), failures_(failures),
          max_transitions_(max_transitions), out_(out) {
        const PhaseInfo& info = model.phase(phase);
        const mission::Phase& source = mission.phases[static_cast<std::size_t>(phase)];
        for (const std::string& name : info.configurations) {
            configs_.push_back(*model.configuration(mission, name));
        }
        const auto nodes = static_cast<std::size_t>(model.node_count());
        edges_.assign(configs_.size(), std::vector<int>(nodes, kEdgeMissing));
        for (const mission::FailureEdge& edge : source.on_failure) {
            const int from = index_of(edge.config);
            const int node = model.node_id(edge.node);
            if (from == kNone || node == kNone) continue;  // the loader checked every name
            edges_[static_cast<std::size_t>(from)][static_cast<std::size_t>(node)] =
                edge.next == mission::kSafe ? kEdgeSafe : index_of(edge.next);
        }
        tolerated_.assign(nodes, mission.tolerance.nodes.empty());
        for (const std::string& name : mission.tolerance.nodes) {
            const int node = model.node_id(name);
            if (node != kNone) tolerated_[static_cast<std::size_t>(node)] = true;
        }
    }

    void run() {
        FailedSet failed = model_.no_failures();
        std::vector<int> sequence;
        const int initial = model_.phase(phase_).initial;
        assert(initial != kNone);
        visit(true, initial, configs_[static_cast<std::size_t>(initial)], failed, sequence);
        tally(within_sets_, out_.within);
        tally(beyond_sets_, out_.beyond);
    }

  private:
    int index_of(const std::string& name) const {
        const auto& names = model_.phase(phase_).configurations;
        const auto it = std::find(names.begin(), names.end(), name);
        return it == names.end() ? kNone : static_cast<int>(it - names.begin());
    }

    bool within_tolerance(const std::vector<int>& sequence) const {
        const auto size = static_cast<std::int64_t>(sequence.size());
        if (size > mission_.tolerance.node_failures) return false;
        return std::all_of(sequence.begin(), sequence.end(),
                           [&](int n) { return static_cast<bool>(tolerated_[index(n)]); });
    }

    static void append(std::string& key, int value) {
        const auto v = static_cast<std::uint16_t>(value);  // ids are below 1,024; kNone is 0xFFFF
        key.push_back(static_cast<char>(v & 0xFF));
        key.push_back(static_cast<char>(v >> 8));
    }

    static std::string failed_key(const std::vector<int>& sequence) {
        std::vector<int> sorted = sequence;
        std::sort(sorted.begin(), sorted.end());
        std::string key;
        for (const int n : sorted) append(key, n);
        return key;
    }

    // The state's key: the failed set, whether the configuration is the graph's, and it.
    static std::string state_key(const std::vector<int>& sequence, bool graph,
                                 const Configuration& config) {
        std::string key = failed_key(sequence);
        key.push_back(graph ? 'g' : 'o');
        append(key, config.master);
        append(key, static_cast<int>(config.observers.size()));
        for (const int o : config.observers) append(key, o);
        for (const int h : config.host) append(key, h);
        return key;
    }

    // The runtime's `matters` (Topology::build): the master, an observer, a task's host,
    // and a storage node where a checkpointed task is placed.
    bool matters(const Configuration& config, int node) const {
        if (config.master == node) return true;
        const auto& observers = config.observers;
        if (std::find(observers.begin(), observers.end(), node) != observers.end()) return true;
        if (std::find(config.host.begin(), config.host.end(), node) != config.host.end()) return true;
        if (!model_.node(node).storage) return false;
        for (int t = 0; t < model_.task_count(); ++t) {
            if (config.host[index(t)] != kNone && model_.task(t).checkpoint) return true;
        }
        return false;
    }

    // Topology::recovery_target's walk: from the phase's initial configuration through the
    // failed set in id order, each pass the first node with an edge or that matters; the
    // index reached, or kEdgeSafe (an edge to SAFE, a missing edge, or a configuration whose
    // master or a task's host has failed).
    int walk_from_initial(const FailedSet& failed) const {
        int at = model_.phase(phase_).initial;
        std::vector<int> pending;
        for (int n = 0; n < model_.node_count(); ++n) {
            if (failed[index(n)]) pending.push_back(n);
        }
        for (std::size_t guard = 0; guard <= pending.size(); ++guard) {
            const Configuration& config = configs_[index(at)];
            const auto it = std::find_if(pending.begin(), pending.end(), [&](int n) {
                return matters(config, n) || edges_[index(at)][index(n)] != kEdgeMissing;
            });
            if (it == pending.end()) break;
            const int edge = edges_[index(at)][index(*it)];
            pending.erase(it);
            if (edge < 0) return kEdgeSafe;
            at = edge;
        }
        return hosts_failed(configs_[index(at)], failed) ? kEdgeSafe : at;
    }

    // A readmission of `node` in the state (failed, config) (spec/Rejoin.tla, as
    // core/fsm/online.hpp's recovery_target answers it): in a graph+online phase the
    // graph's configuration of the smaller failed set where it is not SAFE and its master
    // is the current one or the node that comes back (a state the failure exploration
    // proves, or the mission's on_recovery edge the verifier proves); the placer otherwise,
    // from the current configuration, its master staying. Within the tolerance of the
    // smaller set, safe mode, another master or a checker finding is a violation.
    void readmissions(bool graph, int graph_index, const Configuration& config, FailedSet& failed,
                      const std::vector<int>& sequence) {
        for (const int node : sequence) {
            failed[index(node)] = false;
            std::vector<int> rest;
            for (const int n : sequence) {
                if (n != node) rest.push_back(n);
            }
            bool by_graph = false;
            if (mode() == mission::PlacementMode::graph_online) {
                const int edge = graph ? recovery_edge(graph_index, node) : kNone;
                const int target = edge != kNone ? edge : walk_from_initial(failed);
                by_graph = target >= 0 && (configs_[index(target)].master == config.master ||
                                           configs_[index(target)].master == node);
            }
            if (!by_graph) {
                ++out_.readmissions;
                const Step step = placed(config, failed, config.master);
                if (step.kind != Step::Kind::online && within_tolerance(rest)) {
                    std::string why = step.kind == Step::Kind::safe
                                          ? std::string("the placer finds no placement of the essential tasks")
                                      : step.kind == Step::Kind::mismatch
                                          ? "the placer names " + model_.node(step.config.master).name +
                                                " Master, not the current one"
                                          : "the placer's configuration fails the checker: " +
                                                step.findings.front().message;
                    violation(step.kind == Step::Kind::safe       ? "safe-mode-within-tolerance"
                              : step.kind == Step::Kind::mismatch ? "master-mismatch"
                                                                  : step.findings.front().kind.c_str(),
                              sequence, "readmitting " + model_.node(node).name + ": " + why);
                }
            }
            failed[index(node)] = true;
        }
    }

    // The mission's on_recovery edge of `node` from the graph's configuration, or kNone.
    int recovery_edge(int graph_index, int node) const {
        const mission::Phase& source = mission_.phases[index(phase_)];
        const std::string& config = model_.phase(phase_).configurations[index(graph_index)];
        const std::string& name = model_.node(node).name;
        for (const mission::FailureEdge& e : source.on_recovery) {
            if (e.config == config && e.node == name) return index_of(e.next);
        }
        return kNone;
    }

    static bool hosts_failed(const Configuration& config, const FailedSet& failed) {
        if (failed[index(config.master)]) return true;
        return std::any_of(config.host.begin(), config.host.end(),
                           [&](int host) { return host != kNone && failed[index(host)]; });
    }

    // The master the election makes: the current one if alive, else the first alive observer.
    static int elected(const Configuration& config, const FailedSet& failed) {
        if (config.master != kNone && !failed[index(config.master)]) return config.master;
        for (const int o : config.observers) {
            if (!failed[index(o)]) return o;
        }
        return kNone;
    }

    Step placed(const Configuration& current, const FailedSet& failed, int master) {
        ++out_.placements;
        Placement answer = place(model_, phase_, failed, current);
        Step step;
        if (answer.safe) return step;
        if (answer.config.master != master) {
            step.kind = Step::Kind::mismatch;
            step.elected = master;
            step.config = std::move(answer.config);
            return step;
        }
        step.findings = check(model_, phase_, failed, answer.config, Shedding::allowed);
        step.kind = step.findings.empty() ? Step::Kind::online : Step::Kind::invalid;
        step.config = std::move(answer.config);
        return step;
    }

    Step next(bool graph, int graph_index, const Configuration& current, int node,
              const FailedSet& failed) {
        const int master = elected(current, failed);
        if (graph && mode() == mission::PlacementMode::graph_online) {
            const int edge = edges_[index(graph_index)][index(node)];
            if (edge == kEdgeMissing && !matters(current, node)) {
                return Step{Step::Kind::graph, graph_index, current, {}, kNone};
            }
            if (edge >= 0) {
                const Configuration& target = configs_[static_cast<std::size_t>(edge)];
                // As the runtime's walk (Topology::walk): a target whose master or a task's
                // host has failed (beyond the verifier's proof of the graph) is not taken,
                // nor one of another master.
                if (target.master == master && !hosts_failed(target, failed)) {
                    return Step{Step::Kind::graph, edge, target, {}, kNone};
                }
            }
        }
        return placed(current, failed, master);
    }

    mission::PlacementMode mode() const { return mission_.phases[index(phase_)].placement; }

    std::string sequence_text(const std::vector<int>& sequence) const {
        std::string text;
        for (const int n : sequence) text += (text.empty() ? "" : ", ") + model_.node(n).name;
        return text;
    }

    void violation(const char* kind, const std::vector<int>& sequence, std::string message) {
        ++out_.violation_count;
        if (out_.violations.size() >= static_cast<std::size_t>(kMaxListedViolations)) return;
        std::string text = "phase " + model_.phase(phase_).name + ", " + sequence_text(sequence) +
                           " failed in this order: " + std::move(message);
        out_.violations.push_back(ProveViolation{kind, sequence, std::move(text)});
    }

    void record(const std::vector<int>& sequence, Outcome outcome, const Configuration* config) {
        auto& sets = within_tolerance(sequence) ? within_sets_ : beyond_sets_;
        FailedSetOutcome& set = sets[failed_key(sequence)];
        if (set.shed.empty()) set.shed.assign(static_cast<std::size_t>(model_.task_count()), false);
        if (config != nullptr) {
            for (const int t : model_.phase(phase_).tasks) {
                if (config->host[static_cast<std::size_t>(t)] == kNone) {
                    set.shed[static_cast<std::size_t>(t)] = true;
                    outcome = std::max(outcome, Outcome::shedding);
                }
            }
        }
        set.worst = std::max(set.worst, outcome);
    }

    void tally(const std::unordered_map<std::string, FailedSetOutcome>& sets, Outcomes& out) const {
        out.shed_by_task.assign(static_cast<std::size_t>(model_.task_count()), 0);
        for (const auto& [key, set] : sets) {
            ++out.failed_sets;
            switch (set.worst) {
                case Outcome::running: ++out.running_every_task; break;
                case Outcome::shedding: ++out.shedding; break;
                case Outcome::safe: ++out.safe; break;
            }
            for (std::size_t t = 0; t < set.shed.size(); ++t) {
                if (set.shed[t]) ++out.shed_by_task[t];
            }
        }
    }

    // Expands the state (failed, config) once: every failure of an alive node from it.
    void visit(bool graph, int graph_index, const Configuration& config, FailedSet& failed,
               std::vector<int>& sequence) {
        if (!expanded_.insert(state_key(sequence, graph, config)).second) return;
        readmissions(graph, graph_index, config, failed, sequence);
        if (static_cast<int>(sequence.size()) >= failures_) return;
        ++out_.states;
        for (int node = 0; node < model_.node_count(); ++node) {
            if (failed[static_cast<std::size_t>(node)]) continue;
            if (out_.transitions >= max_transitions_) {
                out_.complete = false;
                return;
            }
            failed[static_cast<std::size_t>(node)] = true;
            sequence.push_back(node);
            ++out_.transitions;
            apply(next(graph, graph_index, config, node, failed), failed, sequence);
            sequence.pop_back();
            failed[static_cast<std::size_t>(node)] = false;
        }
    }

    void apply(const Step& step, FailedSet& failed, std::vector<int>& sequence) {
        const bool within = within_tolerance(sequence);
        switch (step.kind) {
            case Step::Kind::safe:
                record(sequence, Outcome::safe, nullptr);
                if (within) {
                    violation("safe-mode-within-tolerance", sequence,
                              "the placer finds no placement of the essential tasks: safe mode");
                }
                return;
            case Step::Kind::mismatch: {
                record(sequence, Outcome::safe, nullptr);  // the nodes go to SAFE
                const std::string who = step.elected == kNone ? "no node (no observer is alive)"
                                                              : model_.node(step.elected).name;
                if (within) violation("master-mismatch", sequence,
                                      "the placer names " + model_.node(step.config.master).name +
                                          " Master, the election makes " + who);
                return;
            }
            case Step::Kind::invalid: {
                record(sequence, Outcome::safe, nullptr);  // every node refuses it
                std::string text;
                for (const Finding& f : step.findings) {
                    text += (text.empty() ? "" : "; ") + f.message;
                }
                violation(step.findings.front().kind.c_str(), sequence,
                          "the placer's configuration fails the checker: " + text);
                return;
            }
            case Step::Kind::graph:
            case Step::Kind::online:
                record(sequence, Outcome::running, &step.config);
                visit(step.kind == Step::Kind::graph, step.graph, step.config, failed, sequence);
                return;
        }
    }

    const mission::Mission& mission_;
    const Model& model_;
    const int phase_;
    const int failures_;
    const std::int64_t max_transitions_;
    PhaseProof& out_;
    std::vector<Configuration> configs_;       // the graph's, by index
    std::vector<std::vector<int>> edges_;      // [configuration][node]: on_failure target
    std::vector<bool> tolerated_;              // per node: in tolerance.nodes
    std::unordered_set<std::string> expanded_;  // state keys
    std::unordered_map<std::string, FailedSetOutcome> within_sets_;
    std::unordered_map<std::string, FailedSetOutcome> beyond_sets_;
};

}  // namespace

bool proved_online(const mission::Mission& mission, int phase) {
    return mission.phases[index(phase)].placement != mission::PlacementMode::graph;
}

PhaseProof prove_phase(const mission::Mission& mission, const Model& model, int phase, int failures,
                       std::int64_t max_transitions) {
    assert(phase >= 0 && phase < model.phase_count());
    assert(failures >= 0 && failures <= kMaxProveFailures);
    assert(proved_online(mission, phase));
    PhaseProof out;
    out.phase = phase;
    out.mode = mission.phases[static_cast<std::size_t>(phase)].placement;
    out.failures = failures;
    assert(max_transitions >= 0);
    Explorer(mission, model, phase, failures, max_transitions, out).run();
    return out;
}

}  // namespace keel::placement
