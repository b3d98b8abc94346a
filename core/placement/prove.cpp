#include "core/placement/prove.hpp"

#include <algorithm>
#include <cassert>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <unordered_map>

#include "core/placement/check.hpp"
#include "core/placement/place.hpp"

namespace keel::placement {

namespace {

// A graph edge's target: a configuration's index in the phase, or one of these.
constexpr int kEdgeMissing = -1;
constexpr int kEdgeSafe = -2;

std::size_t index(int id) { return static_cast<std::size_t>(id); }

// A state's key, kept as a 128-bit fingerprint of its bytes (two 64-bit hashes, seeded
// apart): a 64-node mission at K = 3 has millions of states of 256 tasks each, and the
// bytes themselves took gigabytes. As TLC's fingerprints, two states could share one; the
// chance among n states is about n^2 / 2^129 (10^-25 for ten million).
struct Fingerprint {
    std::uint64_t a = 0;
    std::uint64_t b = 0;
    friend bool operator==(const Fingerprint&, const Fingerprint&) = default;
};

// A set of fingerprints: open addressing, linear probing, 16 bytes a slot (a node-based
// set took a heap node per state, and as much time in malloc as in its lookups).
class FingerprintSet {
  public:
    // Whether `f` was not in the set (it is now).
    bool insert(Fingerprint f) {
        if (f == Fingerprint{}) f.b = 1;  // the empty slot's value stands for no state
        if (2 * (size_ + 1) > slots_.size()) grow();
        if (!place(slots_, f)) return false;
        ++size_;
        return true;
    }

  private:
    static bool place(std::vector<Fingerprint>& slots, const Fingerprint& f) {
        const std::size_t mask = slots.size() - 1;
        for (std::size_t i = static_cast<std::size_t>(f.a) & mask;; i = (i + 1) & mask) {
            if (slots[i] == f) return false;
            if (slots[i] == Fingerprint{}) {
                slots[i] = f;
                return true;
            }
        }
    }

    void grow() {
        std::vector<Fingerprint> bigger(slots_.empty() ? 1024 : 2 * slots_.size());
        for (const Fingerprint& f : slots_) {
            if (!(f == Fingerprint{})) place(bigger, f);
        }
        slots_ = std::move(bigger);
    }

    std::vector<Fingerprint> slots_;  // a power of two, at most half full
    std::size_t size_ = 0;
};

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

Fingerprint fingerprint(const std::string& bytes) {
    Fingerprint f{0x9e3779b97f4a7c15ULL, 0xc2b2ae3d27d4eb4fULL};
    std::uint64_t word = 0;
    const auto feed = [&](std::uint64_t w) {
        f.a = mix(f.a ^ w) * 0xff51afd7ed558ccdULL;
        f.b = mix(f.b + w * 0x9e3779b97f4a7c15ULL) ^ (f.b >> 29);
    };
    std::size_t at = 0;
    for (; at + 8 <= bytes.size(); at += 8) {
        std::memcpy(&word, bytes.data() + at, 8);
        feed(word);
    }
    word = 0;
    for (; at < bytes.size(); ++at) {
        word = (word << 8) | static_cast<unsigned char>(bytes[at]);
    }
    feed(word ^ (static_cast<std::uint64_t>(bytes.size()) << 56));
    return {mix(f.a), mix(f.b)};
}

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

// A move of a path: the failure of `node`, or a phase change into `phase`.
struct Event {
    int node = kNone;
    int phase = kNone;
};

// What one thread found and counted, per proof; merged into the proofs at the end. A
// finding is listed by its place in the exploration's order (`order`, then `sub` within a
// state's readmissions), so that the first kMaxListedViolations are the same whichever
// thread checked them.
struct Listed {
    std::int64_t order = 0;
    int sub = 0;
    ProveViolation violation;
};

struct Tally {
    explicit Tally(std::size_t proofs)
        : placements(proofs, 0), readmissions(proofs, 0), violation_count(proofs, 0), listed(proofs) {}
    std::vector<std::int64_t> placements;
    std::vector<std::int64_t> readmissions;
    std::vector<std::int64_t> violation_count;
    std::vector<std::vector<Listed>> listed;
    FreshPasses fresh;  // the placer's, on this tally's thread

    void add(std::size_t proof, Listed found) {
        ++violation_count[proof];
        auto& list = listed[proof];
        list.push_back(std::move(found));
        // Keep this thread's first kMaxListedViolations: one with as many before it here is
        // not among the first of all.
        if (list.size() >= 2 * static_cast<std::size_t>(kMaxListedViolations)) keep_first(list);
    }

    static void keep_first(std::vector<Listed>& list) {
        std::sort(list.begin(), list.end(), [](const Listed& a, const Listed& b) {
            return a.order != b.order ? a.order < b.order : a.sub < b.sub;
        });
        if (list.size() > static_cast<std::size_t>(kMaxListedViolations)) {
            list.resize(static_cast<std::size_t>(kMaxListedViolations));
        }
    }
};

// A state's readmissions, to be checked: they lead to no state the exploration expands,
// only to findings, so they are checked apart from it (on every thread).
struct Readmissions {
    std::int64_t order = 0;
    int phase = kNone;
    bool graph = false;
    int graph_index = kNone;
    Configuration config;
    FailedSet failed;
    std::vector<int> sequence;
    std::vector<Event> path;
    int start = kNone;
};

// The readmissions' work, shared by the exploring thread and the helpers: batches queued
// by the explorer; a helper takes the oldest; the explorer checks one itself when the
// queue is long (so that neither waits while the other has work), and all that is left at
// the end. A batch checked goes back to the explorer to be filled again: its jobs' vectors
// keep their room (a job holds a configuration of every task: allocated once, not per job).
class Helpers {
  public:
    struct Batch {
        std::vector<Readmissions> jobs;
        std::size_t size = 0;  // jobs[0, size) to check
    };
    using Work = std::function<void(const Readmissions&, Tally&)>;
    static constexpr std::size_t kBatch = 64;      // readmission jobs per batch
    static constexpr std::size_t kQueued = 8;      // batches queued before the explorer helps

    Helpers(int threads, std::size_t proofs, Work work) : work_(std::move(work)), mine_(proofs) {
        for (int i = 1; i < threads; ++i) tallies_.emplace_back(proofs);
        for (std::size_t i = 0; i < tallies_.size(); ++i) {
            threads_.emplace_back([this, i] { serve(tallies_[i]); });
        }
    }
    Helpers(const Helpers&) = delete;
    Helpers& operator=(const Helpers&) = delete;
    ~Helpers() { stop(); }

    // The next job's slot, to fill (then submit()).
    Readmissions& next() {
        if (batch_.jobs.size() <= batch_.size) batch_.jobs.emplace_back();
        return batch_.jobs[batch_.size++];
    }

    void submit() {
        if (batch_.size < kBatch) return;
        if (threads_.empty()) {
            check(batch_, mine_);
            return;
        }
        Batch help;
        {
            std::lock_guard lock(mutex_);
            queue_.push_back(std::move(batch_));
            if (queue_.size() > kQueued) {
                help = std::move(queue_.front());
                queue_.pop_front();
            }
            batch_ = Batch{};
            if (!spare_.empty()) {
                batch_ = std::move(spare_.back());
                spare_.pop_back();
            }
        }
        ready_.notify_one();
        if (help.size != 0) {
            check(help, mine_);
            std::lock_guard lock(mutex_);
            spare_.push_back(std::move(help));
        }
    }

    // Every job checked; the explorer's tally and the helpers', in order.
    std::vector<Tally*> finish() {
        check(batch_, mine_);
        for (;;) {
            Batch help;
            {
                std::lock_guard lock(mutex_);
                if (queue_.empty()) break;
                help = std::move(queue_.front());
                queue_.pop_front();
            }
            check(help, mine_);
        }
        stop();
        std::vector<Tally*> out{&mine_};
        for (Tally& t : tallies_) out.push_back(&t);
        return out;
    }

  private:
    void check(Batch& batch, Tally& tally) {
        for (std::size_t i = 0; i < batch.size; ++i) work_(batch.jobs[i], tally);
        batch.size = 0;
    }

    void serve(Tally& tally) {
        for (;;) {
            Batch batch;
            {
                std::unique_lock lock(mutex_);
                ready_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
                if (queue_.empty()) return;  // stopping, and nothing left
                batch = std::move(queue_.front());
                queue_.pop_front();
            }
            check(batch, tally);
            std::lock_guard lock(mutex_);
            if (spare_.size() < kQueued) spare_.push_back(std::move(batch));
        }
    }

    void stop() {
        {
            std::lock_guard lock(mutex_);
            stopping_ = true;
        }
        ready_.notify_all();
        for (std::thread& t : threads_) t.join();
        threads_.clear();
    }

    Work work_;
    Tally mine_;
    std::deque<Tally> tallies_;  // one per helper (a deque: no move while they run)
    std::vector<std::thread> threads_;
    std::mutex mutex_;
    std::condition_variable ready_;
    std::deque<Batch> queue_;
    std::vector<Batch> spare_;  // checked, to fill again
    Batch batch_;               // the explorer's, filling
    bool stopping_ = false;
};

// What the explorer knows of one phase: its graph, by index.
struct PhaseGraph {
    mission::PlacementMode mode = mission::PlacementMode::graph;
    std::vector<Configuration> configs;    // the graph's, by index
    std::vector<std::vector<int>> edges;   // [configuration][node]: on_failure target
    std::vector<std::vector<int>> on_phase;  // [target phase][configuration]: index there, or kNone
    std::vector<bool> declared;            // per target phase: an on_phase entry names it
    int proof = kNone;                     // its index in the proofs (a phase not placed by graph)
};

class Explorer {
  public:
    Explorer(const mission::Mission& mission, const Model& model, int failures, std::int64_t max_transitions,
             int threads, std::vector<PhaseProof>& proofs)
        : mission_(mission), model_(model), failures_(failures), max_transitions_(max_transitions),
          threads_(threads), proofs_(proofs) {
        const auto nodes = static_cast<std::size_t>(model.node_count());
        const auto phases = static_cast<std::size_t>(model.phase_count());
        phases_.resize(phases);
        within_sets_.resize(phases);
        beyond_sets_.resize(phases);
        for (int p = 0; p < model.phase_count(); ++p) {
            PhaseGraph& graph = phases_[index(p)];
            const mission::Phase& source = mission.phases[index(p)];
            graph.mode = source.placement;
            for (const std::string& name : model.phase(p).configurations) {
                graph.configs.push_back(*model.configuration(mission, name));
            }
            graph.edges.assign(graph.configs.size(), std::vector<int>(nodes, kEdgeMissing));
            for (const mission::FailureEdge& edge : source.on_failure) {
                const int from = index_of(p, edge.config);
                const int node = model.node_id(edge.node);
                if (from == kNone || node == kNone) continue;  // the loader checked every name
                graph.edges[index(from)][index(node)] = edge.next == mission::kSafe ? kEdgeSafe : index_of(p, edge.next);
            }
            graph.on_phase.assign(phases, std::vector<int>(graph.configs.size(), kNone));
            graph.declared.assign(phases, false);
            for (const mission::PhaseEdge& edge : source.on_phase) {
                const int target = model.phase_id(edge.phase);
                const int from = index_of(p, edge.from);
                if (target == kNone || from == kNone) continue;
                graph.declared[index(target)] = true;
                graph.on_phase[index(target)][index(from)] = index_of(target, edge.to);
            }
            if (source.placement != mission::PlacementMode::graph) {
                graph.proof = static_cast<int>(proofs_.size());
                PhaseProof proof;
                proof.phase = p;
                proof.mode = source.placement;
                proof.failures = failures;
                proofs_.push_back(std::move(proof));
            }
        }
        tolerated_.assign(nodes, mission.tolerance.nodes.empty());
        for (const std::string& name : mission.tolerance.nodes) {
            const int node = model.node_id(name);
            if (node != kNone) tolerated_[index(node)] = true;
        }
    }

    // From every phase's initial configuration with no node failed (a phase placed by its
    // graph too: its failures and phase changes lead into the phases proved here).
    void run() {
        Tally explored(proofs_.size());
        tally_ = &explored;
        Helpers helpers(threads_, proofs_.size(),
                        [this](const Readmissions& job, Tally& tally) { readmissions(job, tally); });
        helpers_ = &helpers;
        for (int p = 0; p < model_.phase_count(); ++p) {
            FailedSet failed = model_.no_failures();
            std::vector<int> sequence;
            const int initial = model_.phase(p).initial;
            assert(initial != kNone);
            start_ = p;
            path_.clear();
            visit(p, true, initial, graph_of(p).configs[index(initial)], failed, sequence);
        }
        std::vector<Tally*> tallies = helpers.finish();
        tallies.push_back(&explored);
        for (std::size_t i = 0; i < proofs_.size(); ++i) {
            PhaseProof& proof = proofs_[i];
            std::vector<Listed> listed;
            for (Tally* t : tallies) {
                proof.placements += t->placements[i];
                proof.readmissions += t->readmissions[i];
                proof.violation_count += t->violation_count[i];
                for (Listed& l : t->listed[i]) listed.push_back(std::move(l));
            }
            Tally::keep_first(listed);
            for (Listed& l : listed) proof.violations.push_back(std::move(l.violation));
        }
        helpers_ = nullptr;
        tally_ = nullptr;
        for (PhaseProof& proof : proofs_) {
            tally(within_sets_[index(proof.phase)], proof.within);
            tally(beyond_sets_[index(proof.phase)], proof.beyond);
            proof.complete = complete_;
        }
    }

  private:
    const PhaseGraph& graph_of(int phase) const { return phases_[index(phase)]; }
    // The proof a phase's findings count in: its own, or (a phase placed by its graph, whose
    // graph the verifier's Z3 proof covers) the other end's of the phase change.
    PhaseProof* proof_of(int phase) {
        const int at = graph_of(phase).proof;
        return at == kNone ? nullptr : &proofs_[index(at)];
    }

    int index_of(int phase, const std::string& name) const {
        const auto& names = model_.phase(phase).configurations;
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

    // The state's key: the phase, the failed set, whether the configuration is the graph's,
    // and it.
    static std::string state_key(int phase, const std::vector<int>& sequence, bool graph,
                                 const Configuration& config) {
        std::string key = failed_key(sequence);
        key.reserve(key.size() + 7 + 2 * (config.observers.size() + config.host.size()));
        key.push_back(graph ? 'g' : 'o');
        append(key, phase);
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
    int walk_from_initial(int phase, const FailedSet& failed) const {
        const PhaseGraph& graph = graph_of(phase);
        int at = model_.phase(phase).initial;
        std::vector<int> pending;
        for (int n = 0; n < model_.node_count(); ++n) {
            if (failed[index(n)]) pending.push_back(n);
        }
        for (std::size_t guard = 0; guard <= pending.size(); ++guard) {
            const Configuration& config = graph.configs[index(at)];
            const auto it = std::find_if(pending.begin(), pending.end(), [&](int n) {
                return matters(config, n) || graph.edges[index(at)][index(n)] != kEdgeMissing;
            });
            if (it == pending.end()) break;
            const int edge = graph.edges[index(at)][index(*it)];
            pending.erase(it);
            if (edge < 0) return kEdgeSafe;
            at = edge;
        }
        return hosts_failed(graph.configs[index(at)], failed) ? kEdgeSafe : at;
    }

    // A readmission of `node` in the state (failed, config) (spec/Rejoin.tla, as
    // core/fsm/online.hpp's recovery_target answers it): in a graph+online phase the
    // graph's configuration of the smaller failed set where it is not SAFE and its master
    // is the current one or the node that comes back (a state the failure exploration
    // proves, or the mission's on_recovery edge the verifier proves); the placer otherwise,
    // from the current configuration, its master staying. Within the tolerance of the
    // smaller set, safe mode, another master or a checker finding is a violation. Run on
    // any thread: it reads the explorer's mission and graphs only.
    void readmissions(const Readmissions& job, Tally& tally) const {
        const PhaseGraph& graphs = graph_of(job.phase);
        const auto proof = static_cast<std::size_t>(graphs.proof);
        FailedSet failed = job.failed;
        int sub = 0;
        for (const int node : job.sequence) {
            failed[index(node)] = false;
            std::vector<int> rest;
            for (const int n : job.sequence) {
                if (n != node) rest.push_back(n);
            }
            bool by_graph = false;
            if (graphs.mode == mission::PlacementMode::graph_online) {
                const int edge = job.graph ? recovery_edge(job.phase, job.graph_index, node) : kNone;
                const int target = edge != kNone ? edge : walk_from_initial(job.phase, failed);
                by_graph = target >= 0 && (graphs.configs[index(target)].master == job.config.master ||
                                           graphs.configs[index(target)].master == node);
            }
            if (!by_graph) {
                ++tally.readmissions[proof];
                const Step step = placed(job.phase, job.config, failed, job.config.master, tally);
                if (step.kind != Step::Kind::online && within_tolerance(rest)) {
                    tally.add(proof, Listed{job.order, sub++,
                                            describe(job.phase, step_kind(step), job.sequence,
                                                     "readmitting " + model_.node(node).name + ": " +
                                                         why_not(step, "the current one"),
                                                     job.path, job.start)});
                }
            }
            failed[index(node)] = true;
        }
    }

    // The mission's on_recovery edge of `node` from the graph's configuration, or kNone.
    int recovery_edge(int phase, int graph_index, int node) const {
        const mission::Phase& source = mission_.phases[index(phase)];
        const std::string& config = model_.phase(phase).configurations[index(graph_index)];
        const std::string& name = model_.node(node).name;
        for (const mission::FailureEdge& e : source.on_recovery) {
            if (e.config == config && e.node == name) return index_of(phase, e.next);
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

    Step placed(int phase, const Configuration& current, const FailedSet& failed, int master, Tally& tally) const {
        const int proof = graph_of(phase).proof;
        if (proof != kNone) ++tally.placements[index(proof)];
        Placement answer = place(model_, phase, failed, current, &tally.fresh);
        Step step;
        if (answer.safe) return step;
        if (answer.config.master != master) {
            step.kind = Step::Kind::mismatch;
            step.elected = master;
            step.config = std::move(answer.config);
            return step;
        }
        step.findings = check(model_, phase, failed, answer.config, Shedding::allowed);
        step.kind = step.findings.empty() ? Step::Kind::online : Step::Kind::invalid;
        step.config = std::move(answer.config);
        return step;
    }

    static const char* step_kind(const Step& step) {
        return step.kind == Step::Kind::safe       ? "safe-mode-within-tolerance"
               : step.kind == Step::Kind::mismatch ? "master-mismatch"
                                                   : step.findings.front().kind.c_str();
    }

    std::string why_not(const Step& step, const std::string& master) const {
        if (step.kind == Step::Kind::safe) return "the placer finds no placement of the essential tasks";
        if (step.kind == Step::Kind::mismatch) {
            return "the placer names " + model_.node(step.config.master).name + " Master, not " + master;
        }
        std::string text;
        for (const Finding& f : step.findings) text += (text.empty() ? "" : "; ") + f.message;
        return "the placer's configuration fails the checker: " + text;
    }

    // The failure of `node` in the state (phase, configuration), the failed set `failed`
    // (node included): the graph's edge where the phase's mode and Topology::walk take it,
    // the placer where an online phase or a graph+online one answers, SAFE otherwise.
    Step next(int phase, bool graph, int graph_index, const Configuration& current, int node,
              const FailedSet& failed) {
        const PhaseGraph& graphs = graph_of(phase);
        const int master = elected(current, failed);
        if (graph && graphs.mode != mission::PlacementMode::online) {
            const int edge = graphs.edges[index(graph_index)][index(node)];
            if (edge == kEdgeMissing && !matters(current, node)) {
                return Step{Step::Kind::graph, graph_index, current, {}, kNone};
            }
            if (edge >= 0) {
                const Configuration& target = graphs.configs[static_cast<std::size_t>(edge)];
                // As the runtime's walk (Topology::walk): a target whose master or a task's
                // host has failed (beyond the verifier's proof of the graph) is not taken,
                // nor one of another master.
                if (target.master == master && !hosts_failed(target, failed)) {
                    return Step{Step::Kind::graph, edge, target, {}, kNone};
                }
            }
            if (graphs.mode == mission::PlacementMode::graph) return Step{};  // SAFE
        }
        return placed(phase, current, failed, master, *tally_);
    }

    // A phase change into `target` from the state (phase, configuration) (core/fsm/online.hpp,
    // phase_target, the Master staying): from a configuration of the graph its on_phase
    // entry, from an online one the target's graph configuration of the failed set (unless
    // the target is placed online), where its master is this one, no failed node is its
    // master or a task's host and, into a phase not placed by its graph alone, the checker
    // finds it valid; else, into a phase not placed by its graph, the placer.
    // Nothing (the change is refused) otherwise.
    Step phase_change(int phase, bool graph, int graph_index, const Configuration& current, int target,
                      const FailedSet& failed) {
        const PhaseGraph& into = graph_of(target);
        const auto usable = [&](int id) {
            if (id < 0 || into.configs[index(id)].master != current.master) return false;
            if (hosts_failed(into.configs[index(id)], failed)) return false;
            return into.mode == mission::PlacementMode::graph || valid(model_, target, failed, into.configs[index(id)]);
        };
        int entry = kNone;
        if (graph) {
            entry = graph_of(phase).on_phase[index(target)][index(graph_index)];
        } else if (into.mode != mission::PlacementMode::online) {
            entry = walk_from_initial(target, failed);
        }
        if (usable(entry)) return Step{Step::Kind::graph, entry, into.configs[index(entry)], {}, kNone};
        if (into.mode == mission::PlacementMode::graph) return Step{};  // refused
        return placed(target, current, failed, current.master, *tally_);
    }

    std::string path_text(const std::vector<Event>& path, int start) const {
        std::string text = "from " + model_.phase(start).name + "'s initial configuration";
        for (const Event& e : path) {
            text += e.node != kNone ? ", " + model_.node(e.node).name + " fails"
                                    : ", the phase changes to " + model_.phase(e.phase).name;
        }
        return text;
    }

    // A violation in `phase` reached by `path` from `start`'s initial configuration.
    ProveViolation describe(int phase, const char* kind, const std::vector<int>& sequence, std::string message,
                            const std::vector<Event>& path, int start) const {
        std::string text = "phase " + model_.phase(phase).name + ", ";
        const bool changed = std::any_of(path.begin(), path.end(), [](const Event& e) { return e.node == kNone; });
        if (changed || start != phase) {
            text += path_text(path, start) + ": ";
        } else {
            std::string names;
            for (const int n : sequence) names += (names.empty() ? "" : ", ") + model_.node(n).name;
            text += names + " failed in this order: ";
        }
        ProveViolation v{kind, sequence, text + std::move(message), {}, start};
        for (const Event& e : path) v.path.push_back(ProveEvent{e.node, e.phase});
        return v;
    }

    // A violation on the exploration's path.
    void violation(int phase, const char* kind, const std::vector<int>& sequence, std::string message) {
        const std::size_t proof = index(graph_of(phase).proof);
        if (tally_->violation_count[proof] >= kMaxListedViolations) {
            ++tally_->violation_count[proof];  // counted, not listed (and not described)
            return;
        }
        tally_->add(proof, Listed{order_++, 0, describe(phase, kind, sequence, std::move(message), path_, start_)});
    }

    void record(int phase, const std::vector<int>& sequence, Outcome outcome, const Configuration* config) {
        if (graph_of(phase).proof == kNone || sequence.empty()) return;
        auto& sets = within_tolerance(sequence) ? within_sets_ : beyond_sets_;
        FailedSetOutcome& set = sets[index(phase)][failed_key(sequence)];
        if (set.shed.empty()) set.shed.assign(static_cast<std::size_t>(model_.task_count()), false);
        if (config != nullptr) {
            for (const int t : model_.phase(phase).tasks) {
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

    // Whether a phase change's finding is new: one configuration reached from several states,
    // or one state's refusal, is one violation.
    bool once(const std::string& key) { return reported_.insert(fingerprint(key)); }

    bool budget_spent() {
        if (transitions_ < max_transitions_) return false;
        complete_ = false;
        return true;
    }

    // Expands the state (phase, failed, config) once: the readmission of each failed node
    // (a phase not placed by its graph), every phase change, and every failure of an alive
    // node.
    void visit(int phase, bool graph, int graph_index, const Configuration& config, FailedSet& failed,
               std::vector<int>& sequence) {
        const std::string key = state_key(phase, sequence, graph, config);
        if (!expanded_.insert(fingerprint(key))) return;
        PhaseProof* proof = proof_of(phase);
        if (proof != nullptr && !sequence.empty()) {
            Readmissions& job = helpers_->next();  // copied into the slot's room
            job.order = order_++;
            job.phase = phase;
            job.graph = graph;
            job.graph_index = graph_index;
            job.config = config;
            job.failed = failed;
            job.sequence = sequence;
            job.path = path_;
            job.start = start_;
            helpers_->submit();
        }
        // The failures first: a state is reached first by the fewest phase changes.
        if (static_cast<int>(sequence.size()) < failures_) {
            if (proof != nullptr) ++proof->states;
            for (int node = 0; node < model_.node_count(); ++node) {
                if (failed[index(node)]) continue;
                if (budget_spent()) return;
                failed[index(node)] = true;
                sequence.push_back(node);
                path_.push_back(Event{node, kNone});
                ++transitions_;
                if (proof != nullptr) ++proof->transitions;
                apply(phase, next(phase, graph, graph_index, config, node, failed), failed, sequence);
                path_.pop_back();
                sequence.pop_back();
                failed[index(node)] = false;
            }
        }
        for (int target = 0; target < model_.phase_count(); ++target) {
            if (target == phase || budget_spent()) continue;
            // A change between two phases placed by their graphs is the verifier's Z3 proof's.
            if (graph && proof == nullptr && graph_of(target).proof == kNone) continue;
            ++transitions_;
            path_.push_back(Event{kNone, target});
            change(phase, graph, graph_index, config, key, target, failed, sequence);
            path_.pop_back();
        }
    }

    // A phase change into `target`: its configuration checked, then explored. Within the
    // tolerance, a change the mission names (an on_phase entry into `target`) that the
    // runtime refuses, or a configuration of the graph that is not valid under the failed
    // set, is a violation; a placer's answer the checker refuses is one anywhere.
    void change(int phase, bool graph, int graph_index, const Configuration& config, const std::string& from,
                int target, FailedSet& failed, std::vector<int>& sequence) {
        const Step step = phase_change(phase, graph, graph_index, config, target, failed);
        const int owner = graph_of(target).proof != kNone ? target : phase;
        if (PhaseProof* proof = proof_of(owner)) ++proof->phase_changes;
        const bool within = within_tolerance(sequence);
        const bool declared = graph_of(phase).declared[index(target)];
        const std::string into = "the change to phase " + model_.phase(target).name;
        switch (step.kind) {
            case Step::Kind::safe:
            case Step::Kind::mismatch:
                if (within && declared && proof_of(owner) != nullptr && once(from + char(target))) {
                    violation(owner, "phase-transition-invalid", sequence,
                              into + " is refused: " +
                                  (graph_of(target).mode == mission::PlacementMode::graph
                                       ? std::string("no configuration of the graph this Master drives without a failed node")
                                       : why_not(step, "this Master " + model_.node(config.master).name)));
                }
                return;
            case Step::Kind::invalid:
                if (once(state_key(target, sequence, false, step.config))) {
                    violation(owner, step.findings.front().kind.c_str(), sequence, into + ": " + why_not(step, ""));
                }
                return;
            case Step::Kind::graph: {
                const auto findings = check(model_, target, failed, step.config, Shedding::forbidden);
                if (!findings.empty() && within && proof_of(owner) != nullptr && !sequence.empty() &&
                    once(state_key(target, sequence, true, step.config))) {
                    violation(owner, "phase-transition-invalid", sequence,
                              into + " takes " + model_.phase(target).configurations[index(step.graph)] +
                                  ", which is not valid under the failed set: " + findings.front().message);
                }
                break;
            }
            case Step::Kind::online:
                break;
        }
        visit(target, step.kind == Step::Kind::graph, step.graph, step.config, failed, sequence);
    }

    void apply(int phase, const Step& step, FailedSet& failed, std::vector<int>& sequence) {
        const bool within = within_tolerance(sequence);
        const bool proved = proof_of(phase) != nullptr;
        switch (step.kind) {
            case Step::Kind::safe:
                record(phase, sequence, Outcome::safe, nullptr);
                if (within && proved) {
                    violation(phase, "safe-mode-within-tolerance", sequence,
                              "the placer finds no placement of the essential tasks: safe mode");
                }
                return;
            case Step::Kind::mismatch: {
                record(phase, sequence, Outcome::safe, nullptr);  // the nodes go to SAFE
                const std::string who = step.elected == kNone ? "no node (no observer is alive)"
                                                              : model_.node(step.elected).name;
                if (within) violation(phase, "master-mismatch", sequence,
                                      "the placer names " + model_.node(step.config.master).name +
                                          " Master, the election makes " + who);
                return;
            }
            case Step::Kind::invalid:
                record(phase, sequence, Outcome::safe, nullptr);  // every node refuses it
                violation(phase, step.findings.front().kind.c_str(), sequence, why_not(step, ""));
                return;
            case Step::Kind::graph:
            case Step::Kind::online:
                record(phase, sequence, Outcome::running, &step.config);
                visit(phase, step.kind == Step::Kind::graph, step.graph, step.config, failed, sequence);
                return;
        }
    }

    const mission::Mission& mission_;
    const Model& model_;
    const int failures_;
    const std::int64_t max_transitions_;
    const int threads_;  // the helpers' and the explorer's
    std::vector<PhaseProof>& proofs_;
    std::vector<PhaseGraph> phases_;
    std::vector<bool> tolerated_;              // per node: in tolerance.nodes
    FingerprintSet expanded_;  // states' keys
    FingerprintSet reported_;  // phase changes' findings
    std::vector<std::unordered_map<std::string, FailedSetOutcome>> within_sets_;  // per phase
    std::vector<std::unordered_map<std::string, FailedSetOutcome>> beyond_sets_;
    std::int64_t transitions_ = 0;  // failures and phase changes applied, every phase
    bool complete_ = true;
    Tally* tally_ = nullptr;      // the exploration's findings and placements (run())
    Helpers* helpers_ = nullptr;  // who checks the readmissions (run())
    std::int64_t order_ = 0;      // findings and readmissions numbered in the exploration's order
    int start_ = kNone;         // the phase whose initial configuration the path starts from
    std::vector<Event> path_;   // the moves from there to the state visited
};

}  // namespace

bool proved_online(const mission::Mission& mission, int phase) {
    return mission.phases[index(phase)].placement != mission::PlacementMode::graph;
}

std::vector<PhaseProof> prove(const mission::Mission& mission, const Model& model, int failures,
                              std::int64_t max_transitions, int threads) {
    assert(failures >= 0 && failures <= kMaxProveFailures);
    assert(max_transitions >= 0);
    if (threads <= 0) threads = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
    std::vector<PhaseProof> proofs;
    Explorer(mission, model, failures, max_transitions, std::min(threads, kMaxProveThreads), proofs).run();
    return proofs;
}

PhaseProof prove_phase(const mission::Mission& mission, const Model& model, int phase, int failures,
                       std::int64_t max_transitions) {
    assert(phase >= 0 && phase < model.phase_count());
    assert(proved_online(mission, phase));
    for (PhaseProof& proof : prove(mission, model, failures, max_transitions)) {
        if (proof.phase == phase) return std::move(proof);
    }
    return PhaseProof{};  // unreachable: every phase proved_online has its proof
}

}  // namespace keel::placement
