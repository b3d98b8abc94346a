#include "core/placement/model.hpp"

#include <algorithm>
#include <map>

namespace keel::placement {

void Capabilities::add(int capability) {
    const auto word = static_cast<std::size_t>(capability / 64);
    if (words_.size() <= word) words_.resize(word + 1, 0);
    words_[word] |= std::uint64_t{1} << (capability % 64);
}

bool Capabilities::empty() const {
    return std::all_of(words_.begin(), words_.end(), [](std::uint64_t w) { return w == 0; });
}

std::optional<Model> Model::build(const mission::Mission& mission, std::string* error) {
    auto fail = [&](const std::string& why) -> std::optional<Model> {
        if (error != nullptr) *error = why;
        return std::nullopt;
    };
    if (mission.nodes.size() > static_cast<std::size_t>(kMaxNodes)) {
        return fail("mission has " + std::to_string(mission.nodes.size()) + " nodes, beyond " +
                    std::to_string(kMaxNodes));
    }
    if (mission.tasks.size() > static_cast<std::size_t>(kMaxTasks)) {
        return fail("mission has " + std::to_string(mission.tasks.size()) + " tasks, beyond " +
                    std::to_string(kMaxTasks));
    }
    Model model;
    std::map<std::string, int> capability_ids;
    auto capability = [&](const std::string& name) {
        const auto [it, added] =
            capability_ids.emplace(name, static_cast<int>(capability_ids.size()));
        (void)added;
        return it->second;
    };
    for (const mission::Node& n : mission.nodes) {
        NodeInfo node;
        node.name = n.name;
        node.processing = n.is_processing();
        node.storage = n.is_storage();
        for (const std::string& c : n.capabilities) node.capabilities.add(capability(c));
        node.cpu = n.capacity.cpu.value_or(kUnbounded);
        node.mem_mb = n.capacity.mem_mb.value_or(kUnbounded);
        model.capacity_.push_back(Room{node.cpu, node.mem_mb});
        model.nodes_.push_back(std::move(node));
    }
    model.node_count_ = static_cast<int>(model.nodes_.size());
    std::map<std::string, int> group_ids;
    for (const mission::Task& t : mission.tasks) {
        TaskInfo task;
        task.name = t.name;
        for (const std::string& c : t.requires_capabilities) {
            task.requires_capabilities.add(capability(c));
        }
        task.cpu = t.load.cpu.value_or(0);
        task.mem_mb = t.load.mem_mb.value_or(0);
        task.essential = t.essential;
        task.checkpoint = t.checkpoint;
        task.priority = t.priority.value_or(0);
        if (t.group) {
            task.group = group_ids.emplace(*t.group, static_cast<int>(group_ids.size())).first->second;
        }
        for (int n = 0; n < model.node_count(); ++n) {
            const bool able = model.node(n).capabilities.contains_all(task.requires_capabilities);
            if (able) task.capable.push_back(n);
            model.capable_.push_back(able ? 1 : 0);
        }
        model.tasks_.push_back(std::move(task));
    }
    model.task_count_ = static_cast<int>(model.tasks_.size());
    model.groups_ = static_cast<int>(group_ids.size());
    for (const mission::Phase& p : mission.phases) {
        PhaseInfo phase;
        phase.name = p.name;
        phase.in_phase.assign(mission.tasks.size(), 0);
        for (const std::string& t : p.tasks) {
            const int id = model.task_id(t);
            if (id == kNone) return fail("phase " + p.name + " names unknown task " + t);
            phase.in_phase[static_cast<std::size_t>(id)] = 1;
        }
        for (int t = 0; t < model.task_count(); ++t) {
            if (phase.in_phase[static_cast<std::size_t>(t)]) phase.tasks.push_back(t);
        }
        // The placer's order of need: essential first, then priority, then the larger
        // load; ties in id order (computed once: the placer runs per failure).
        phase.by_need = phase.tasks;
        std::sort(phase.by_need.begin(), phase.by_need.end(), [&](int a, int b) {
            const TaskInfo& x = model.task(a);
            const TaskInfo& y = model.task(b);
            if (x.essential != y.essential) return x.essential;
            if (x.priority != y.priority) return x.priority > y.priority;
            if (x.cpu != y.cpu) return x.cpu > y.cpu;
            if (x.mem_mb != y.mem_mb) return x.mem_mb > y.mem_mb;
            return a < b;
        });
        for (const mission::Configuration& c : p.configurations) {
            if (c.name == p.initial) phase.initial = static_cast<int>(phase.configurations.size());
            phase.configurations.push_back(c.name);
        }
        model.phases_.push_back(std::move(phase));
    }
    return model;
}

namespace {
template <typename Items>
int find_name(const Items& items, const std::string& name) {
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (items[i].name == name) return static_cast<int>(i);
    }
    return kNone;
}
}  // namespace

int Model::node_id(const std::string& name) const { return find_name(nodes_, name); }
int Model::task_id(const std::string& name) const { return find_name(tasks_, name); }
int Model::phase_id(const std::string& name) const { return find_name(phases_, name); }

std::optional<Configuration> Model::configuration(const mission::Mission& mission,
                                                  const std::string& name) const {
    const mission::Configuration* c = mission.configuration(name);
    if (c == nullptr) return std::nullopt;
    Configuration out;
    out.master = node_id(c->master);
    for (const std::string& o : c->observers) out.observers.push_back(node_id(o));
    out.host.assign(tasks_.size(), kNone);
    for (const auto& [task, node] : c->placement) {
        const int t = task_id(task);
        if (t != kNone) out.host[static_cast<std::size_t>(t)] = node_id(node);
    }
    return out;
}

}  // namespace keel::placement
