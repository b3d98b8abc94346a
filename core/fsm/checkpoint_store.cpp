#include "core/fsm/checkpoint_store.hpp"

#include <cassert>

#include "core/fsm/json.hpp"

namespace keel::fsm {

CheckpointStore::CheckpointStore(const Topology& topology, NodeId self)
    : topology_(&topology),
      self_(self),
      present_(static_cast<std::size_t>(topology.task_count())),
      version_(static_cast<std::size_t>(topology.task_count())),
      state_(static_cast<std::size_t>(topology.task_count())),
      writer_(static_cast<std::size_t>(topology.task_count()), kNoNode),
      budget_(topology) {
    assert(self < topology.node_count());
}

void CheckpointStore::set_view(const View& view) {
    excluded_ = view.failed;
    if (view_ && view_->epoch == view.epoch && view_->seq == view.seq) {
        view_ = view;
        return;
    }
    previous_view_ = view_;
    view_ = view;
}

void CheckpointStore::restore(const std::vector<StoredCheckpoint>& records) {
    for (const auto& record : records) {
        if (record.task >= topology_->task_count()) continue;
        // Kept under an earlier mission: a task no longer checkpointed, or a state above the
        // bound this mission states, is served to no one (a node would refuse to flush it
        // back, and the protocol's domain may not carry it).
        const TopologyTask& task = topology_->task(record.task);
        if (!task.checkpoint || (task.max_state_bytes && record.state.size() > *task.max_state_bytes)) {
            continue;
        }
        if (present_[record.task] && record.version <= version_[record.task]) continue;
        present_[record.task] = true;
        version_[record.task] = record.version;
        state_[record.task] = record.state;
        writer_[record.task] = kNoNode;
    }
}

// The Storage node's variables after a store: "stored" (the task's count) and, for a
// lineage other than the initial one, "storedLineage".
std::string CheckpointStore::stored_json(TaskId task) const {
    std::string name;
    append_json_string(name, topology_->task(task).name);
    JsonObject vars;
    vars.raw("stored", "{" + name + ":" + std::to_string(version_[task].count) + "}");
    if (version_[task].lineage != 0) {
        vars.raw("storedLineage", "{" + name + ":" + json_lineage(version_[task].lineage) + "}");
    }
    return vars.str();
}

void CheckpointStore::trace_recovered(Outbox& out) const {
    if (!out.tracing()) return;
    for (TaskId task = 0; task < topology_->task_count(); ++task) {
        if (!topology_->task(task).checkpoint) continue;
        out.trace("switch", "Recovered",
                  JsonObject()
                      .field("n", topology_->node_name(self_))
                      .field("t", topology_->task(task).name)
                      .version(version_[task])
                      .str(),
                  stored_json(task));
    }
}

bool CheckpointStore::receive_write(const CheckpointWrite& write, Outbox& out) {
    if (write.task >= topology_->task_count()) return false;
    if (excluded_.contains(write.from)) return false;
    const TaskId task = write.task;
    const auto& bound = topology_->task(task).max_state_bytes;
    if (!topology_->task(task).checkpoint || !topology_->may_host(task).contains(write.from) ||
        (bound && write.state.size() > *bound)) {
        ++refused_writes_;  // no honest node writes it: nothing stored, nothing acknowledged
        return false;
    }
    bool newer = !present_[task] || write.version > version_[task];
    bool replaces = false;
    if (!newer && write.version != version_[task] && host_wins(write)) {
        ++overridden_;
        newer = replaces = true;
    }
    if (newer) {
        present_[task] = true;
        version_[task] = write.version;
        state_[task] = write.state;
        writer_[task] = write.from;
        out.push(act::StoreCheckpoint{task, write.version, write.state, replaces});
        if (out.tracing()) {
            out.trace("switch", "StoreCheckpoint",
                      JsonObject()
                          .field("from", topology_->node_name(write.from))
                          .field("t", topology_->task(task).name)
                          .version(write.version)
                          .str(),
                      stored_json(task));
        }
    }
    if (write.final) {
        out.send(write.from, CheckpointAck{self_, write.epoch, task, version_[task]});
    }
    return newer;
}

bool CheckpointStore::host_wins(const CheckpointWrite& write) const {
    // Only a running host's periodic write: a final write flushes a hand-off, which may be
    // older than what another node handed off since (a hand-off flushed after the Storage
    // node's readmission).
    if (write.final || !view_ || write.epoch != view_->epoch) return false;
    const NodeId host = topology_->host(*view_, write.task);
    if (write.from != host) return false;
    const NodeId writer = writer_[write.task];
    if (writer == host) return false;
    return !(previous_view_ && topology_->host(*previous_view_, write.task) == writer);
}

void CheckpointStore::receive_request(const CheckpointRequest& request, const View& view,
                                      TimeNs now, Outbox& out) {
    if (request.task >= topology_->task_count() || request.from >= topology_->node_count() ||
        excluded_.contains(request.from)) {
        return;
    }
    if (!budget_.admit(request, view, now)) return;
    CheckpointReply reply;
    reply.from = self_;
    reply.epoch = request.epoch;
    reply.seq = request.seq;
    reply.task = request.task;
    reply.found = present_[request.task];
    reply.version = version_[request.task];
    reply.state = state_[request.task];
    out.send(request.from, std::move(reply));
}

std::optional<Version> CheckpointStore::latest_version(TaskId task) const {
    if (task >= topology_->task_count() || !present_[task]) return std::nullopt;
    return version_[task];
}

std::vector<StoredCheckpoint> CheckpointStore::records() const {
    std::vector<StoredCheckpoint> result;
    for (int task = 0; task < topology_->task_count(); ++task) {
        if (present_[task]) {
            result.push_back({static_cast<TaskId>(task), version_[task], state_[task]});
        }
    }
    return result;
}

}  // namespace keel::fsm
