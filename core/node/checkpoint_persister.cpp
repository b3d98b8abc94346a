#include "core/node/checkpoint_persister.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <memory>

#include "core/node/state_db.hpp"

namespace keel::node {

namespace {

// The writer yields the CPU to the node's loop (and its DDS threads): heartbeats first.
constexpr int kWriterNice = 10;

}  // namespace

CheckpointPersister::CheckpointPersister(const std::string& path, std::function<void()> written)
    : on_written_(std::move(written)) {
    // Opened here, so a database that cannot be opened stops the node's boot.
    auto db = std::make_unique<StateDb>(path);
    writer_ = std::thread([this, owned = db.release()] {
        const std::unique_ptr<StateDb> connection(owned);
        run(connection.get());
    });
}

CheckpointPersister::~CheckpointPersister() { stop(); }

void CheckpointPersister::stop() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_one();
    if (writer_.joinable()) writer_.join();
}

std::uint64_t CheckpointPersister::store(fsm::TaskId task, std::string task_name, fsm::Version version,
                                         std::vector<std::uint8_t> state, bool replaces) {
    std::uint64_t ticket = 0;
    {
        std::lock_guard lock(mutex_);
        ticket = ++tickets_;
        auto [entry, inserted] = waiting_.try_emplace(task);
        if (!inserted) ++coalesced_;  // the waiting older checkpoint is never written
        replaces = replaces || (!inserted && entry->second.replaces);
        entry->second = Waiting{std::move(task_name), version, std::move(state), replaces, ticket};
    }
    wake_.notify_one();
    return ticket;
}

std::vector<CheckpointPersister::Written> CheckpointPersister::take_written() {
    std::lock_guard lock(mutex_);
    std::vector<Written> done;
    done.swap(written_);
    return done;
}

std::uint64_t CheckpointPersister::coalesced() const {
    std::lock_guard lock(mutex_);
    return coalesced_;
}

std::uint64_t CheckpointPersister::writes() const {
    std::lock_guard lock(mutex_);
    return writes_;
}

std::size_t CheckpointPersister::waiting() const {
    std::lock_guard lock(mutex_);
    return waiting_.size();
}

void CheckpointPersister::run(StateDb* db) {
    // Linux schedules threads on their own: this lowers the writer alone.
    setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kWriterNice);
    std::unique_lock lock(mutex_);
    fsm::TaskId last_task = 0;
    for (;;) {
        wake_.wait(lock, [this] { return stopping_ || !waiting_.empty(); });
        if (waiting_.empty()) return;  // stopping, and everything is written
        // Round robin over the tasks: one task's stream of checkpoints (a flood) never keeps
        // another's waiting.
        auto next = waiting_.upper_bound(last_task);
        if (next == waiting_.end()) next = waiting_.begin();
        const fsm::TaskId task = next->first;
        last_task = task;
        Waiting item = std::move(next->second);
        waiting_.erase(next);
        lock.unlock();
        Written done{task, item.version, item.ticket, {}};
        try {
            db->store_checkpoint(item.task_name, item.version, item.state, item.replaces);
        } catch (const StateDbError& error) {
            done.error = error.what();
        }
        item = Waiting{};  // the state's memory goes before the next one is taken
        lock.lock();
        written_.push_back(std::move(done));
        ++writes_;
        if (on_written_) on_written_();
    }
}

}  // namespace keel::node
