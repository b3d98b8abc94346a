#include "core/placement/place.hpp"

#include <algorithm>
#include <cstdint>

namespace keel::placement {

namespace {

bool is_failed(const FailedSet& failed, int node) {
    return static_cast<std::size_t>(node) < failed.size() && failed[static_cast<std::size_t>(node)];
}

bool alive_processing(const Model& model, const FailedSet& failed, int node) {
    return node >= 0 && node < model.node_count() && model.node(node).processing &&
           !is_failed(failed, node);
}

// The room left on every node, and which groups each node hosts.
class Bins {
  public:
    explicit Bins(const Model& model)
        : model_(&model), room_(model.capacity()),
          groups_(static_cast<std::size_t>(model.node_count()) * static_cast<std::size_t>(model.group_count()), false) {}

    bool fits(int node, const TaskInfo& task) const {
        const auto n = static_cast<std::size_t>(node);
        return task.cpu <= room_[n].cpu && task.mem_mb <= room_[n].mem_mb;
    }
    bool hosts_group(int node, int group) const {
        return group != kNone && groups_[index(node, group)];
    }
    void take(int node, const TaskInfo& task) {
        const auto n = static_cast<std::size_t>(node);
        if (room_[n].cpu != kUnbounded) room_[n].cpu -= task.cpu;
        if (room_[n].mem_mb != kUnbounded) room_[n].mem_mb -= task.mem_mb;
        if (task.group != kNone) groups_[index(node, task.group)] = true;
    }
    // take(node, task) undone, `hosted` what hosts_group(node, task.group) was before it.
    void give_back(int node, const TaskInfo& task, bool hosted) {
        const auto n = static_cast<std::size_t>(node);
        if (room_[n].cpu != kUnbounded) room_[n].cpu += task.cpu;
        if (room_[n].mem_mb != kUnbounded) room_[n].mem_mb += task.mem_mb;
        if (task.group != kNone) groups_[index(node, task.group)] = hosted;
    }
    // Tighter is better: the cpu, then the memory, left after taking `task`.
    std::pair<std::int64_t, std::int64_t> left_after(int node, const TaskInfo& task) const {
        const auto n = static_cast<std::size_t>(node);
        return {room_[n].cpu == kUnbounded ? kUnbounded : room_[n].cpu - task.cpu,
                room_[n].mem_mb == kUnbounded ? kUnbounded : room_[n].mem_mb - task.mem_mb};
    }

  private:
    std::size_t index(int node, int group) const {
        return static_cast<std::size_t>(node) * static_cast<std::size_t>(model_->group_count()) +
               static_cast<std::size_t>(group);
    }
    const Model* model_;
    std::vector<Model::Room> room_;     // per node: the capacity left
    std::vector<bool> groups_;  // [node][group]: hosts a task of it (bits: the search copies none)
};

class Placer {
  public:
    Placer(const Model& model, int phase, const FailedSet& failed, const Configuration& current,
           FreshPasses* memo)
        : model_(model), phase_id_(phase), phase_(model.phase(phase)), failed_(failed), current_(current),
          was_(&current.host), memo_(memo) {
        if (current.host.size() != static_cast<std::size_t>(model.task_count())) {
            unplaced_.assign(static_cast<std::size_t>(model.task_count()), kNone);
            was_ = &unplaced_;
        }
        for (int n = 0; n < model.node_count(); ++n) {
            if (is_failed(failed, n)) continue;
            if (model.node(n).storage) storage_alive_ = true;
        }
    }

    Placement run() {
        Placement out;
        const int master = choose_master();
        if (master == kNone) {
            out.safe = true;
            return out;
        }
        out.config.master = master;
        out.config.observers = choose_observers(master);
        // Every task kept where it runs and the others placed: the fewest moves.
        Pass kept = keep_then_place();
        if (kept.shed.empty()) {
            out.config.host = std::move(kept.host);
            return finish(std::move(out));
        }
        if (unbeaten(kept)) {  // what the passes below would answer, without them
            out.config.host = std::move(kept.host);
            out.shed = std::move(kept.shed);
            return finish(std::move(out));
        }
        // Otherwise in order of need, each task on its host if it still fits there, or
        // placed afresh; a task that fits nowhere is shed (an essential one: safe mode).
        Pass staying = by_need(true);
        Pass fresh = afresh();
        const Pass* best = &kept;
        for (const Pass* other : {&staying, &fresh}) {
            if (!better(*best, *other)) best = other;
        }
        Pass exact;
        if (!best->essential_placed) {
            // The greedy passes packed the essential tasks badly: search for their
            // placement (bounded), then the others in order of need around them.
            exact = essentials_first();
            best = &exact;
        }
        if (!best->essential_placed) {
            out.safe = true;
            out.config = Configuration{};
            return out;
        }
        out.config.host = best->host;
        out.shed = best->shed;
        return finish(std::move(out));
    }

  private:
    int choose_master() const {
        if (alive_processing(model_, failed_, current_.master)) return current_.master;
        for (const int o : current_.observers) {
            if (alive_processing(model_, failed_, o)) return o;
        }
        for (int n = 0; n < model_.node_count(); ++n) {
            if (alive_processing(model_, failed_, n)) return n;
        }
        return kNone;
    }

    std::vector<int> choose_observers(int master) const {
        std::vector<int> observers;
        // Taken: the master or an observer already (a few nodes: a scan, no table).
        const auto taken = [&](int n) {
            return n == master || std::find(observers.begin(), observers.end(), n) != observers.end();
        };
        for (const int o : current_.observers) {
            if (!alive_processing(model_, failed_, o) || taken(o)) continue;
            observers.push_back(o);
        }
        const std::size_t wanted = std::max<std::size_t>(current_.observers.size(), 1);
        for (int n = 0; n < model_.node_count() && observers.size() < wanted; ++n) {
            if (!alive_processing(model_, failed_, n) || taken(n)) continue;
            observers.push_back(n);
        }
        return observers;
    }

    bool able(int node, int t) const {
        if (is_failed(failed_, node)) return false;
        if (model_.task(t).checkpoint && !storage_alive_) return false;
        return model_.capable(t, node);
    }

    struct Pass {
        std::vector<int> host;
        std::vector<int> shed;  // in the order they were found not to fit
        bool essential_placed = true;
        int moved = 0;
    };

    // The best node for `task` with the room left, or kNone: able, with room, hosting no
    // task of its group if there is one, the tightest fit first, the lowest id first.
    int best_node(const Bins& bins, const TaskInfo& task) const {
        int best = kNone;
        bool best_spread = false;
        std::pair<std::int64_t, std::int64_t> best_left{};
        if (task.checkpoint && !storage_alive_) return kNone;
        for (const int n : task.capable) {  // able(n, task), as the nodes' capabilities go
            if (is_failed(failed_, n) || !bins.fits(n, task)) continue;
            const bool spread = !bins.hosts_group(n, task.group);
            const auto left = bins.left_after(n, task);
            if (best == kNone || (spread && !best_spread) ||
                (spread == best_spread && left < best_left)) {
                best = n;
                best_spread = spread;
                best_left = left;
            }
        }
        return best;
    }

    int current_host(int t) const {
        const int was = (*was_)[static_cast<std::size_t>(t)];
        return was >= 0 && was < model_.node_count() ? was : kNone;
    }

    void place_or_shed(Pass& pass, Bins& bins, int t, int node) const {
        const TaskInfo& task = model_.task(t);
        if (node == kNone) {
            pass.shed.push_back(t);
            if (task.essential) pass.essential_placed = false;
            return;
        }
        bins.take(node, task);
        pass.host[static_cast<std::size_t>(t)] = node;
        const int was = current_host(t);
        if (was != kNone && was != node) ++pass.moved;
    }

    // Every task kept on its host where it is able and fits (in id order), then the others
    // in order of need.
    Pass keep_then_place() const {
        Pass pass;
        pass.host.assign(static_cast<std::size_t>(model_.task_count()), kNone);
        Bins bins(model_);
        std::size_t kept = 0;
        for (const int t : phase_.tasks) {
            const int was = current_host(t);
            const TaskInfo& task = model_.task(t);
            if (was == kNone || !able(was, t) || !bins.fits(was, task)) continue;
            bins.take(was, task);
            pass.host[static_cast<std::size_t>(t)] = was;
            ++kept;
        }
        if (kept == phase_.tasks.size()) return pass;  // none to place
        for (const int t : order_) {
            if (pass.host[static_cast<std::size_t>(t)] != kNone) continue;
            place_or_shed(pass, bins, t, best_node(bins, model_.task(t)));
        }
        return pass;
    }

    // Every task in order of need: on its host if `stay` and it is able and fits there,
    // else on the best node, else shed.
    Pass by_need(bool stay) const {
        Pass pass;
        pass.host.assign(static_cast<std::size_t>(model_.task_count()), kNone);
        Bins bins(model_);
        for (const int t : order_) {
            const TaskInfo& task = model_.task(t);
            const int was = current_host(t);
            const int node = stay && was != kNone && able(was, t) && bins.fits(was, task)
                                 ? was
                                 : best_node(bins, task);
            place_or_shed(pass, bins, t, node);
        }
        return pass;
    }

    // by_need(false), kept across calls in memo_ where there is one: it does not depend on
    // current_ but for the moves it counts.
    Pass afresh() const {
        if (memo_ == nullptr) return by_need(false);
        std::string key(failed_.begin(), failed_.end());
        key.push_back('/');
        key += std::to_string(phase_id_);
        if (const FreshPasses::Pass* kept = memo_->find(key)) {
            Pass pass{kept->host, kept->shed, kept->essential_placed, 0};
            for (const int t : phase_.tasks) {
                const int was = current_host(t);
                const int now = pass.host[static_cast<std::size_t>(t)];
                if (now != kNone && was != kNone && was != now) ++pass.moved;
            }
            return pass;
        }
        Pass pass = by_need(false);
        memo_->keep(std::move(key), FreshPasses::Pass{pass.host, pass.shed, pass.essential_placed});
        return pass;
    }

    // A search for a placement of the essential tasks (depth first, in order of need, at
    // most kSearchBudget nodes visited), then the other tasks as by_need(false) does.
    static constexpr int kSearchBudget = 4096;

    bool search(std::size_t i, const std::vector<int>& tasks, Bins& bins, std::vector<int>& host,
                int& budget) const {
        if (i == tasks.size()) return true;
        const TaskInfo& task = model_.task(tasks[i]);
        for (int n = 0; n < model_.node_count(); ++n) {
            if (!able(n, tasks[i]) || !bins.fits(n, task)) continue;
            if (--budget < 0) return false;  // a step is a node tried that can take the task
            const bool hosted = bins.hosts_group(n, task.group);
            bins.take(n, task);
            host[static_cast<std::size_t>(tasks[i])] = n;
            if (search(i + 1, tasks, bins, host, budget)) return true;
            bins.give_back(n, task, hosted);
            host[static_cast<std::size_t>(tasks[i])] = kNone;
        }
        return false;
    }

    Pass essentials_first() const {
        Pass pass;
        pass.host.assign(static_cast<std::size_t>(model_.task_count()), kNone);
        std::vector<int> essential;
        for (const int t : order_) {
            if (model_.task(t).essential) essential.push_back(t);
        }
        Bins bins(model_);
        int budget = kSearchBudget;
        if (!search(0, essential, bins, pass.host, budget)) {
            pass.essential_placed = false;
            return pass;
        }
        for (const int t : order_) {
            if (model_.task(t).essential) continue;
            place_or_shed(pass, bins, t, best_node(bins, model_.task(t)));
        }
        for (const int t : essential) {
            const int was = current_host(t);
            if (was != kNone && was != pass.host[static_cast<std::size_t>(t)]) ++pass.moved;
        }
        return pass;
    }

    // Whether no pass can be better() than `kept`: its essential tasks are placed, every task
    // it sheds fits on no alive node even alone (every pass sheds it too, so another pass
    // sheds the same set or a larger one, of priorities no lower), and it moves only the
    // tasks it places whose host cannot keep them (a pass that sheds the same set moves
    // those too). The usual case beyond the tolerance, where a failed
    // interface node's task can run nowhere: the other passes place every task afresh.
    bool unbeaten(const Pass& kept) const {
        if (!kept.essential_placed) return false;
        for (const int t : kept.shed) {
            if (fits_alone(model_.task(t))) return false;
        }
        int forced = 0;
        for (const int t : phase_.tasks) {
            const int was = current_host(t);
            const bool placed = kept.host[static_cast<std::size_t>(t)] != kNone;
            if (placed && was != kNone && (!able(was, t) || !alone_fits(was, model_.task(t)))) ++forced;
        }
        return kept.moved == forced;
    }

    bool alone_fits(int node, const TaskInfo& task) const {
        return task.cpu <= model_.node(node).cpu && task.mem_mb <= model_.node(node).mem_mb;
    }

    bool fits_alone(const TaskInfo& task) const {
        if (task.checkpoint && !storage_alive_) return false;
        return std::any_of(task.capable.begin(), task.capable.end(),
                           [&](int n) { return !is_failed(failed_, n) && alone_fits(n, task); });
    }

    // The essential tasks placed; then the shed tasks' priorities, highest first, the
    // lower (then the fewer) the better; then the fewer moves.
    bool better(const Pass& a, const Pass& b) const {
        if (a.essential_placed != b.essential_placed) return a.essential_placed;
        auto priorities = [&](const Pass& pass) {
            std::vector<std::int64_t> out;
            for (const int t : pass.shed) out.push_back(model_.task(t).priority);
            std::sort(out.rbegin(), out.rend());
            return out;
        };
        const auto pa = priorities(a);
        const auto pb = priorities(b);
        if (pa != pb) {
            return std::lexicographical_compare(pa.begin(), pa.end(), pb.begin(), pb.end());
        }
        return a.moved <= b.moved;
    }

    Placement finish(Placement out) const {
        for (const int t : phase_.tasks) {
            const int now = out.config.host[static_cast<std::size_t>(t)];
            const int was = (*was_)[static_cast<std::size_t>(t)];
            if (now == kNone) continue;
            if (was == kNone) {
                ++out.started;
            } else if (was != now) {
                ++out.moved;
            }
        }
        return out;
    }

    const Model& model_;
    const int phase_id_;
    const PhaseInfo& phase_;
    const FailedSet& failed_;
    const Configuration& current_;
    const std::vector<int>* was_;   // each task's host in current_ (unplaced_ if it names none)
    std::vector<int> unplaced_;
    FreshPasses* memo_;
    bool storage_alive_ = false;
    // The order of need (PhaseInfo::by_need): essential first, then priority, then the
    // larger load.
    const std::vector<int>& order_ = phase_.by_need;
};

}  // namespace

Placement place(const Model& model, int phase, const FailedSet& failed,
                const Configuration& current, FreshPasses* fresh) {
    if (phase < 0 || phase >= model.phase_count()) return Placement{true, {}, {}, 0, 0};
    return Placer(model, phase, failed, current, fresh).run();
}

}  // namespace keel::placement
