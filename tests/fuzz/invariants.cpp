#include "tests/fuzz/invariants.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "core/fsm/admission.hpp"
#include "core/fsm/codec.hpp"
#include "core/fsm/json.hpp"
#include "core/fsm/overloaded.hpp"

namespace keel::fuzz {

using fsm::NodeId;
using fsm::TaskId;

void broken(const char* invariant, const std::string& what) {
    std::fprintf(stderr, "keel-protocol-fuzz: %s broken: %s\n", invariant, what.c_str());
    std::fflush(stderr);
    std::abort();
}

namespace {

std::string hex(std::span<const std::uint8_t> bytes) {
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string text;
    for (const std::uint8_t byte : bytes) {
        text += kDigits[byte >> 4];
        text += kDigits[byte & 0xF];
    }
    return text;
}

}  // namespace

void Invariants::check_decoded(std::span<const std::uint8_t> bytes,
                               const fsm::DecodedMessage& decoded) {
    if (!decoded.ok()) return;
    const std::vector<std::uint8_t> again = fsm::encode(*decoded.message);
    if (!std::equal(again.begin(), again.end(), bytes.begin(), bytes.end())) {
        broken("CodecRoundTripInv", std::string(fsm::kind_name(*decoded.message)) +
                                        " decoded from " + hex(bytes) + " encodes as " +
                                        hex(again));
    }
}

void Invariants::set_call(const char* call, fsm::TimeNs now) {
    call_ = call;
    now_ = now;
}

std::string Invariants::where(const fsm::NodeProtocol& node) const {
    const fsm::View& view = node.view();
    return topology_->node_name(node.self()) + " (" + fsm::to_string(node.role()) + ", epoch " +
           std::to_string(node.epoch()) + ", view " + topology_->config_name(view.config) + " " +
           std::to_string(view.epoch) + "." + std::to_string(view.seq) + ") after " + call_ +
           " at " + std::to_string(now_) + " ns of " + std::string(topology_->mission_name());
}

void Invariants::check_actions(const fsm::NodeProtocol& node,
                               const std::vector<fsm::Action>& actions,
                               fsm::TaskSet running) const {
    const NodeId self = node.self();
    const auto node_ok = [&](NodeId id) { return static_cast<int>(id) < topology_->node_count(); };
    const auto task_ok = [&](TaskId id) { return static_cast<int>(id) < topology_->task_count(); };
    for (const fsm::Action& action : actions) {
        std::visit(
            fsm::Overloaded{
                [&](const fsm::act::Send& send) {
                    if (!node_ok(send.to) || send.to == self) {
                        broken("ActionsInv", where(node) + ": a " +
                                                 std::string(fsm::kind_name(send.message)) +
                                                 " to node " + std::to_string(send.to));
                    }
                    if (fsm::sender_of(send.message) != self) {
                        broken("ActionsInv", where(node) + ": a " +
                                                 std::string(fsm::kind_name(send.message)) +
                                                 " in the name of node " +
                                                 std::to_string(fsm::sender_of(send.message)));
                    }
                },
                [&](const fsm::act::Activate& activate) {
                    if (!task_ok(activate.task) || running.contains(activate.task)) {
                        broken("ActionsInv", where(node) + ": Activate of task " +
                                                 std::to_string(activate.task) + ", running " +
                                                 fsm::json_tasks(*topology_, running));
                    }
                    running.insert(activate.task);
                },
                [&](const fsm::act::Deactivate& deactivate) {
                    if (!task_ok(deactivate.task) || !running.contains(deactivate.task)) {
                        broken("ActionsInv", where(node) + ": Deactivate of task " +
                                                 std::to_string(deactivate.task) + ", running " +
                                                 fsm::json_tasks(*topology_, running));
                    }
                    running.erase(deactivate.task);
                },
                [&](const fsm::act::StoreCheckpoint& store) {
                    if (self != topology_->storage_node() || !task_ok(store.task) ||
                        !topology_->task(store.task).checkpoint) {
                        broken("ActionsInv", where(node) + ": StoreCheckpoint of task " +
                                                 std::to_string(store.task));
                    }
                },
                [&](const fsm::act::DeclareFailed& declared) {
                    if (!node_ok(declared.node) || declared.node == self) {
                        broken("ActionsInv", where(node) + ": DeclareFailed of node " +
                                                 std::to_string(declared.node));
                    }
                },
                [&](const fsm::act::EnterSafeMode&) {},
                [&](const fsm::act::Trace&) {},
            },
            action);
    }
}

void Invariants::check_view(const fsm::NodeProtocol& node, const fsm::View& view,
                            const char* verb) const {
    if (view.epoch > fsm::kMaxEpoch) {
        broken("EpochWidthInv",
               where(node) + ": " + verb + " a view of epoch " + std::to_string(view.epoch));
    }
    if (view == topology_->initial_view()) return;
    if (auto problem = fsm::view_problem(view, *topology_)) {
        broken("ViewValidInv",
               where(node) + ": " + verb + " view " + topology_->config_name(view.config) +
                   " (epoch " + std::to_string(view.epoch) + " seq " + std::to_string(view.seq) +
                   ", failed " + fsm::json_nodes(*topology_, view.failed) + "): " + *problem);
    }
}

void Invariants::check_node(const fsm::NodeProtocol& node, const fsm::TaskSet& running) {
    const NodeId self = node.self();
    check_view(node, node.view(), "holds");
    if (node.epoch() > fsm::kMaxEpoch) {
        broken("EpochWidthInv", where(node) + ": epoch " + std::to_string(node.epoch()));
    }
    Last& last = last_[self];
    const fsm::View& view = node.view();
    if (node.epoch() < last.epoch ||
        fsm::newer_than(last.view_epoch, last.view_seq, view.epoch, view.seq)) {
        broken("MonotoneInv", where(node) + ": was at epoch " + std::to_string(last.epoch) +
                                  ", view " + std::to_string(last.view_epoch) + "." +
                                  std::to_string(last.view_seq));
    }
    last = Last{node.epoch(), view.epoch, view.seq};
    if (node.is_master()) {
        check_view(node, node.manager().driving(), "drives");
        const fsm::Epoch epoch = node.epoch();
        if (topology_->owner(epoch) != self) {
            broken("OneMasterPerEpochInv",
                   where(node) + ": Master of epoch " + std::to_string(epoch) + ", which is " +
                       topology_->node_name(topology_->owner(epoch)) + "'s");
        }
        const auto seen = std::find_if(masters_.begin(), masters_.end(),
                                       [&](const auto& entry) { return entry.first == epoch; });
        if (seen == masters_.end()) {
            masters_.emplace_back(epoch, self);
        } else if (seen->second != self) {
            broken("OneMasterPerEpochInv",
                   where(node) + ": Master of epoch " + std::to_string(epoch) + ", which " +
                       topology_->node_name(seen->second) + " was Master of");
        }
    }
    const fsm::TaskSet& active = node.config_switch().active();
    const fsm::TaskSet placed = topology_->tasks_on(node.view(), self);
    if (!placed.includes(active)) {
        broken("TasksPlacedInv", where(node) + ": active " + fsm::json_tasks(*topology_, active) +
                                     ", its view places " + fsm::json_tasks(*topology_, placed));
    }
    if (!active.includes(running)) {
        broken("TasksPlacedInv", where(node) + ": runs " + fsm::json_tasks(*topology_, running) +
                                     ", active " + fsm::json_tasks(*topology_, active));
    }
    if ((node.holding() || node.view().failed.contains(self)) && !running.empty()) {
        broken("TasksPlacedInv", where(node) + ": runs " + fsm::json_tasks(*topology_, running) +
                                     " while " +
                                     (node.holding() ? "holding" : "excluded by its own view"));
    }
}

void Invariants::check_tick(const fsm::NodeProtocol& node, fsm::TimeNs next_tick_ns,
                            fsm::TimeNs now) const {
    if (next_tick_ns <= now) {
        broken("TickProgressInv", where(node) + ": next_tick_ns() " + std::to_string(next_tick_ns) +
                                      " is not after the tick");
    }
}

}  // namespace keel::fuzz
