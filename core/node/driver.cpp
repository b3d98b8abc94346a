#include "core/node/driver.hpp"

#include <algorithm>
#include <cassert>
#include <string_view>

#include "core/fsm/overloaded.hpp"

namespace keel::node {

namespace {

// The task a Storage node's acknowledgement or restore reply speaks of.
std::optional<fsm::TaskId> checkpoint_task(const fsm::Message& message) {
    if (const auto* ack = std::get_if<fsm::CheckpointAck>(&message)) return ack->task;
    if (const auto* reply = std::get_if<fsm::CheckpointReply>(&message)) return reply->task;
    return std::nullopt;
}

bool is_send(const fsm::Action& action) { return std::holds_alternative<fsm::act::Send>(action); }

}  // namespace

NodeDriver::NodeDriver(fsm::NodeProtocol& protocol, DriverHost& host, DriverOptions options)
    : adapter_(std::in_place, protocol), protocol_(&*adapter_), host_(&host), options_(options) {}

NodeDriver::NodeDriver(ActionSource& source, DriverHost& host, DriverOptions options)
    : protocol_(&source), host_(&host), options_(options) {}

void NodeDriver::drive(fsm::TimeNs now) {
    protocol_->take_ready(actions_);
    for (const fsm::Action& action : actions_) host_->observe(action);
    if (sends_closed_) {
        const auto before = actions_.size();
        std::erase_if(actions_, is_send);
        counters_.dropped_for_disk += before - actions_.size();
    }
    // Rule 1: the state is on the disk before any message that depends on it leaves.
    bool leave_now = false;
    const bool save_first = !mutant(fsm::Mutant::save_after_send);
    if (save_first && !state_failed_ && !host_->save_state()) {
        ++counters_.state_save_errors;
        state_failed_ = leave_now = true;
        std::erase_if(actions_, is_send);
    }
    // The actions may be taken again by a leave below (a nested drive): work on a copy.
    std::vector<fsm::Action> actions;
    actions.swap(actions_);
    carry_out(actions);
    if (!save_first && !state_failed_ && !host_->save_state()) {
        ++counters_.state_save_errors;
        state_failed_ = leave_now = true;
    }
    if (leave_now) leave("its state cannot be saved", now);
}

void NodeDriver::carry_out(std::vector<fsm::Action>& actions) {
    const bool hold = !mutant(fsm::Mutant::release_held_early);
    bool heartbeat_sent = false;
    fsm::TaskId store_line = fsm::kNoTask;  // a StoreCheckpoint whose trace line follows
    std::vector<fsm::act::Send> later;  // lines_before_sends: the step's messages, in order
    const auto send_now = [&](fsm::NodeId to, fsm::Message& message) {
        if (options_.lines_before_sends) {
            later.push_back(fsm::act::Send{to, std::move(message)});
        } else {
            host_->send(to, message);
        }
    };
    for (fsm::Action& action : actions) {
        std::visit(
            fsm::Overloaded{
                [&](fsm::act::Send& send) {
                    const auto* heartbeat = std::get_if<fsm::Heartbeat>(&send.message);
                    if (options_.coalesce_heartbeats && heartbeat != nullptr && !heartbeat->reply) {
                        if (heartbeat_sent) return;
                        heartbeat_sent = true;
                        send_now(kBroadcast, send.message);
                        return;
                    }
                    const auto task = checkpoint_task(send.message);
                    if (task && storage_failed_) {  // it would stand for no durable write
                        ++counters_.dropped_for_disk;
                        return;
                    }
                    if (task && hold && held_.unwritten(*task)) {
                        held_.hold(*task, fsm::Action{std::move(send)});
                        return;
                    }
                    send_now(send.to, send.message);
                },
                [&](fsm::act::Activate& activate) { host_->activate(activate); },
                [&](fsm::act::Deactivate& deactivate) { host_->deactivate(deactivate.task); },
                [&](fsm::act::StoreCheckpoint& store) {
                    store_line = store.task;
                    if (storage_failed_) return;  // its trace line is dropped below
                    if (const auto ticket = host_->store_checkpoint(store)) {
                        held_.queued(store.task, *ticket);
                    } else {
                        store_line = fsm::kNoTask;  // no disk: its line goes as it comes
                    }
                },
                [&](fsm::act::DeclareFailed& declared) { host_->declared_failed(declared); },
                [&](fsm::act::EnterSafeMode&) { host_->entered_safe_mode(); },
                [&](fsm::act::Trace& line) {
                    if (store_line != fsm::kNoTask && std::string_view(line.action) == "StoreCheckpoint") {
                        const fsm::TaskId task = store_line;
                        store_line = fsm::kNoTask;
                        if (storage_failed_) {
                            ++counters_.dropped_for_disk;
                            return;
                        }
                        if (hold && held_.unwritten(task)) {
                            held_.hold(task, fsm::Action{std::move(line)});
                            return;
                        }
                    }
                    host_->write_trace(line);
                },
            },
            action);
    }
    send_in_order(later);
}

void NodeDriver::send_in_order(std::vector<fsm::act::Send>& sends) {
    const auto command = [](const fsm::Message& message) {
        return std::holds_alternative<fsm::Command>(message) ||
               std::holds_alternative<fsm::ActivateCommand>(message);
    };
    std::vector<fsm::NodeId> to;
    for (std::size_t at = 0; at < sends.size();) {
        fsm::act::Send& send = sends[at];
        std::size_t next = at + 1;
        if (options_.one_send_per_command && command(send.message)) {
            while (next < sends.size() && sends[next].message == send.message) ++next;
        }
        if (next - at == 1) {
            host_->send(send.to, send.message);
        } else {
            to.clear();
            for (std::size_t each = at; each < next; ++each) to.push_back(sends[each].to);
            host_->send_to_each(to, send.message);
        }
        at = next;
    }
}

bool NodeDriver::save_state(fsm::TimeNs now) {
    if (state_failed_) return false;
    if (host_->save_state()) return true;
    ++counters_.state_save_errors;
    state_failed_ = true;
    leave("its state cannot be saved", now);
    return false;
}

void NodeDriver::checkpoint_written(fsm::TaskId task, std::uint64_t ticket) {
    for (fsm::Action& action : held_.written(task, ticket)) release(action);
}

void NodeDriver::checkpoint_failed(fsm::TaskId task, std::uint64_t ticket, fsm::TimeNs now) {
    ++counters_.checkpoint_write_errors;
    if (mutant(fsm::Mutant::ignore_failed_write)) {
        // The mutant takes a failed write for a written one.
        checkpoint_written(task, ticket);
        return;
    }
    // Not on the disk: nothing that stands for it leaves, and a Storage node whose disk
    // fails is a failed Storage node (the graph's edge, or fault model 2's loss rule).
    counters_.dropped_for_disk += held_.failed(task, ticket);
    if (storage_failed_) return;
    storage_failed_ = true;
    leave("a checkpoint write failed", now);
}

void NodeDriver::release(fsm::Action& action) {
    if (auto* send = std::get_if<fsm::act::Send>(&action)) {
        if (!sends_closed_) host_->send(send->to, send->message);
    } else if (auto* line = std::get_if<fsm::act::Trace>(&action)) {
        host_->write_trace(*line);
    }
}

void NodeDriver::leave(std::string_view what, fsm::TimeNs now) {
    if (stopped_) return;
    stopped_ = true;
    // The resignation changes neither the epoch nor the view: what it sends stands for
    // nothing unsaved. Nothing after it is sent; the host stops the node.
    protocol_->resign(now);
    drive(now);
    sends_closed_ = true;
    host_->disk_failed(what);
}

}  // namespace keel::node
