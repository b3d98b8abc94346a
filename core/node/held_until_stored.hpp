// HeldUntilStored: what the Storage node says about a task waits until the checkpoint it
// stands for is durable (NodeDriver, driver.hpp; CheckpointPersister writes the checkpoints).
#pragma once

#include <algorithm>
#include <cstdint>
#include <deque>
#include <map>
#include <utility>
#include <vector>

#include "core/fsm/types.hpp"

namespace keel::node {

// What waits for a task's checkpoint to be on disk: items (messages, trace lines) each
// standing for a version of a task, released in the order they were held once that version
// (or a newer one) is written. A task with nothing unwritten holds nothing.
template <typename Item>
class HeldUntilStored {
public:
    // A checkpoint of `task` was queued for writing as `ticket` (CheckpointPersister::store).
    void queued(fsm::TaskId task, std::uint64_t ticket) {
        Task& entry = tasks_[task];
        entry.newest_queued = std::max(entry.newest_queued, ticket);
    }
    // True when `task` has a queued checkpoint not yet written: what is said about the
    // task now stands for that checkpoint and must wait (hold()).
    bool unwritten(fsm::TaskId task) const {
        const auto found = tasks_.find(task);
        return found != tasks_.end() && found->second.written < found->second.newest_queued;
    }
    // Holds `item` until the task's newest queued checkpoint is written.
    void hold(fsm::TaskId task, Item item) {
        Task& entry = tasks_[task];
        entry.held.emplace_back(entry.newest_queued, std::move(item));
    }
    // `ticket` of `task` is written: returns what may go now, in the order it was held.
    // The persister writes a task's checkpoints in the order they were queued, a waiting
    // one replaced by a newer one (which then stands for both), so a ticket written means
    // every earlier one of its task is written or replaced. Tickets, not versions: a write
    // that replaces a newer version (act::StoreCheckpoint::replaces) is not covered by that
    // newer version's write.
    std::vector<Item> written(fsm::TaskId task, std::uint64_t ticket) {
        std::vector<Item> ready;
        Task& entry = tasks_[task];
        entry.written = std::max(entry.written, ticket);
        while (!entry.held.empty() && entry.held.front().first <= entry.written) {
            ready.push_back(std::move(entry.held.front().second));
            entry.held.pop_front();
        }
        return ready;
    }
    // `ticket` of `task` failed to be written: what waits for it (or an earlier one) is
    // dropped, never released; returns how many.
    std::size_t failed(fsm::TaskId task, std::uint64_t ticket) {
        Task& entry = tasks_[task];
        std::size_t dropped = 0;
        while (!entry.held.empty() && entry.held.front().first <= ticket) {
            entry.held.pop_front();
            ++dropped;
        }
        return dropped;
    }
    std::size_t held() const {
        std::size_t count = 0;
        for (const auto& [task, entry] : tasks_) count += entry.held.size();
        return count;
    }

private:
    struct Task {
        std::uint64_t newest_queued = 0;  // tickets start at 1
        std::uint64_t written = 0;
        std::deque<std::pair<std::uint64_t, Item>> held;
    };
    std::map<fsm::TaskId, Task> tasks_;
};

}  // namespace keel::node
