#include "nodes/sim/src/liar.hpp"

#include <algorithm>
#include <memory>

#include "core/fsm/admission.hpp"
#include "core/fsm/codec.hpp"
#include "core/fsm/online.hpp"
#include "core/fsm/overloaded.hpp"

namespace keel::sim {

namespace {

// How often the liar's honest messages are changed on the way out, and lost.
constexpr double kChanged = 0.25;
constexpr double kNotSent = 0.05;
// How often it forges a message of its own at a period boundary.
constexpr double kForged = 0.6;
// Of those, how many are a coherent switch (plausible_switch).
constexpr double kCoherent = 0.3;
constexpr std::size_t kMaxStateBytes = 16;

}  // namespace

Liar::Liar(const fsm::Topology& topology, fsm::NodeId node, std::uint64_t seed)
    : topology_(&topology), node_(node), rng_(seed ^ 0x11A2'0000'F00D'0003ull) {}

std::optional<fsm::Message> Liar::outgoing(const fsm::Message& honest, const fsm::NodeProtocol& at,
                                           fsm::TimeNs now) {
    last_[honest.index()] = honest;
    if (rng_.chance(kNotSent)) return std::nullopt;
    if (!rng_.chance(kChanged)) return honest;
    return through_the_codec(lie_about(honest, at, now));
}

std::vector<Liar::Forged> Liar::forge(const fsm::NodeProtocol& at, fsm::TimeNs now) {
    if (!rng_.chance(kForged)) return {};
    if (rng_.chance(kCoherent)) return plausible_switch(at);
    const std::size_t kind = rng_.below(std::variant_size_v<fsm::Message>);
    fsm::Message message = last_[kind] ? *last_[kind] : template_of(kind, at, now);
    message = lie_about(std::move(message), at, now);
    auto delivered = through_the_codec(message);
    if (!delivered) return {};
    Forged forged{std::move(*delivered), rng_.chance(0.5) || topology_->node_count() < 2, fsm::kNoNode};
    if (!forged.to_all) {
        do {
            forged.to = static_cast<fsm::NodeId>(rng_.below(static_cast<std::uint64_t>(topology_->node_count())));
        } while (forged.to == node_);
    }
    return {std::move(forged)};
}

std::vector<Liar::Forged> Liar::plausible_switch(const fsm::NodeProtocol& at) {
    const fsm::View& own = at.view();
    if (own.epoch == 0 || own.config == fsm::kNoConfig || own.is_safe()) return {};
    // A live node to exclude, on the liar's word alone.
    fsm::NodeSet candidates = topology_->all_nodes().minus(own.failed);
    candidates.erase(node_);
    if (candidates.empty()) return {};
    std::vector<fsm::NodeId> ids;
    candidates.for_each([&](fsm::NodeId n) { ids.push_back(n); });
    const fsm::NodeId victim = ids[rng_.below(ids.size())];
    fsm::NodeSet failed = own.failed;
    failed.insert(victim);
    // The configuration an honest Master would switch to (the graph's, or the placer's
    // where the phase places online), were the victim failed.
    const fsm::Target target = fsm::failure_target(*topology_, own, {victim}, failed, node_);
    if (target.is_safe()) return {};
    fsm::View view;
    view.config = view.base = target.config;
    view.online = target.online;
    view.failed = failed;
    view.master = node_;
    if (own.master == node_) {
        view.epoch = own.epoch;
        view.seq = std::min(fsm::kMaxSeq, own.seq + 1);
    } else {
        // A take-over under its own name: the next epoch it owns (a node outside the
        // succession owns none).
        const auto& priority = topology_->priority();
        if (std::find(priority.begin(), priority.end(), node_) == priority.end()) return {};
        view.epoch = topology_->next_epoch(node_, own.epoch);
        view.seq = 1;
    }
    if (fsm::master_of(*topology_, target) != node_) return {};  // not a view it may command
    // To every node, or to some only (the others may get another view under the same id
    // from the next lie), and the Activate at once, before anyone could have prepared.
    const auto command = through_the_codec(fsm::Command(node_, view));
    const auto activate = through_the_codec(fsm::ActivateCommand{node_, view.epoch, view.seq});
    if (!command || !activate) return {};
    std::vector<Forged> forged;
    const bool to_all = rng_.chance(0.5);
    for (fsm::NodeId to = 0; to < topology_->node_count(); ++to) {
        if (to == node_ || (!to_all && rng_.chance(0.5))) continue;
        forged.push_back({*command, false, to});
        if (rng_.chance(0.5)) forged.push_back({*activate, false, to});
    }
    return forged;
}

std::optional<fsm::Message> Liar::through_the_codec(const fsm::Message& message) {
    // The receiver's codec refuses what the wire cannot carry; the rest is delivered.
    auto decoded = fsm::decode(fsm::encode(message));
    if (!decoded.ok()) return std::nullopt;
    return std::move(*decoded.message);
}

fsm::Message Liar::template_of(std::size_t kind, const fsm::NodeProtocol& at, fsm::TimeNs now) const {
    const fsm::View& view = at.view();
    const fsm::Epoch epoch = at.epoch();
    const auto seq = static_cast<std::uint32_t>(now / topology_->heartbeat_period_ns());
    switch (kind) {
        case 0: return fsm::Heartbeat{node_, epoch, 1, false, seq, {}, false, 0, false, 0, 0};
        case 1: {
            fsm::View next = view;
            next.seq = std::min(fsm::kMaxSeq, next.seq + 1);
            return fsm::Command(node_, next);
        }
        case 2: return fsm::ActivateCommand{node_, view.epoch, view.seq};
        case 3: return fsm::Ack{node_, view.epoch, view.seq, fsm::AckKind::Prepared, fsm::view_digest(view), false};
        case 4: return fsm::ErrorNotification{node_, epoch, node_};
        case 5: return fsm::CheckpointWrite{node_, epoch, 0, at.config_switch().version(0), false, {}};
        case 6: return fsm::CheckpointAck{node_, epoch, 0, at.config_switch().version(0)};
        case 7: return fsm::CheckpointRequest{node_, view.epoch, view.seq, 0};
        case 8: return fsm::CheckpointReply{node_, view.epoch, view.seq, 0, true, at.config_switch().version(0), {}};
        default: return fsm::PhaseRequest{node_, 0};
    }
}

fsm::Message Liar::lie_about(fsm::Message message, const fsm::NodeProtocol& at, fsm::TimeNs now) {
    const fsm::Epoch epoch = at.epoch();
    const int wrong = 1 + static_cast<int>(rng_.below(3));
    for (int k = 0; k < wrong; ++k) {
        const auto field = rng_.below(8);
        std::visit(
            fsm::Overloaded{
                [&](fsm::Heartbeat& m) {
                    switch (field) {
                        case 0: m.epoch = near(m.epoch, fsm::kMaxEpoch); break;
                        case 1: m.incarnation = near(m.incarnation, fsm::kMaxIncarnation); break;
                        case 2: m.excluded = !m.excluded; break;
                        case 3:
                            m.seq = near(m.seq, 0xFFFF'FFFFu);
                            break;
                        case 4:
                            if (!m.acks.empty() && rng_.chance(0.5)) {
                                auto& ack = m.acks[rng_.below(m.acks.size())];
                                ack.node = any_node();
                                ack.incarnation = near(ack.incarnation, fsm::kMaxIncarnation);
                                ack.seq = near(ack.seq, 0xFFFF'FFFFu);
                            } else if (m.acks.size() < static_cast<std::size_t>(topology_->node_count())) {
                                m.acks.push_back({any_node(), near(1, fsm::kMaxIncarnation),
                                                  near(now / topology_->heartbeat_period_ns(), 0xFFFF'FFFFu)});
                            }
                            break;
                        case 5: m.waiting = !m.waiting; break;
                        case 6: m.boot = rng_.chance(0.5) ? m.previous_boot : static_cast<std::uint32_t>(rng_.next()); break;
                        default: m.reply = !m.reply; break;
                    }
                },
                [&](fsm::Command& m) {
                    if (field == 7 && m.joint.size() < 2) {
                        m.joint.push_back(any_view(m.view));
                    } else if (field == 6 && !m.joint.empty()) {
                        m.joint[rng_.below(m.joint.size())] = any_view(m.view);
                    } else {
                        fsm::View& v = m.view;
                        switch (field % 6) {
                            case 0: v.epoch = near(v.epoch, fsm::kMaxEpoch); break;
                            case 1: v.seq = near(v.seq, fsm::kMaxSeq); break;
                            case 2:
                                if (topology_->has_online() && rng_.chance(0.5)) {
                                    v.online = any_online(v);
                                    v.config = v.base = fsm::kOnlineConfig;
                                } else {
                                    v.config = any_config();
                                }
                                break;
                            case 3: v.base = rng_.chance(0.5) ? v.config : any_config(); break;
                            case 4: v.master = rng_.chance(0.5) ? node_ : any_node(); break;
                            default: v.failed = any_nodes(v.failed); break;
                        }
                    }
                    // A hand-over it made names the boot of its receiver it heard, as an
                    // honest one does: the receiver's check of the boot stops no lie.
                    if (m.view.master != m.from && m.view.master < topology_->node_count()) {
                        m.boot = at.monitor().boot_of(m.view.master);
                    }
                },
                [&](fsm::ActivateCommand& m) {
                    if (field % 2 == 0) m.epoch = near(m.epoch, fsm::kMaxEpoch);
                    else m.seq = near(m.seq, fsm::kMaxSeq);
                },
                [&](fsm::Ack& m) {
                    switch (field % 5) {
                        case 0: m.epoch = near(m.epoch, fsm::kMaxEpoch); break;
                        case 1: m.seq = near(m.seq, fsm::kMaxSeq); break;
                        case 2:
                            m.kind = m.kind == fsm::AckKind::Prepared ? fsm::AckKind::Activated : fsm::AckKind::Prepared;
                            break;
                        case 3: m.view = rng_.chance(0.5) ? fsm::view_digest(any_view(at.view())) : rng_.next(); break;
                        default: m.reply = !m.reply; break;
                    }
                },
                [&](fsm::ErrorNotification& m) {
                    if (field % 2 == 0) m.failed_node = any_node();
                    else m.epoch = near(m.epoch, fsm::kMaxEpoch);
                },
                [&](fsm::CheckpointWrite& m) {
                    switch (field % 5) {
                        case 0: m.task = any_task(); break;
                        case 1: m.epoch = near(m.epoch, fsm::kMaxEpoch); break;
                        case 2: m.version = any_version(m.version, epoch); break;
                        case 3: m.final = !m.final; break;
                        default: m.state = any_state(); break;
                    }
                },
                [&](fsm::CheckpointAck& m) {
                    switch (field % 3) {
                        case 0: m.task = any_task(); break;
                        case 1: m.epoch = near(m.epoch, fsm::kMaxEpoch); break;
                        default: m.version = any_version(m.version, epoch); break;
                    }
                },
                [&](fsm::CheckpointRequest& m) {
                    switch (field % 3) {
                        case 0: m.task = any_task(); break;
                        case 1: m.epoch = near(m.epoch, fsm::kMaxEpoch); break;
                        default: m.seq = near(m.seq, fsm::kMaxSeq); break;
                    }
                },
                [&](fsm::CheckpointReply& m) {
                    switch (field % 6) {
                        case 0: m.task = any_task(); break;
                        case 1: m.epoch = near(m.epoch, fsm::kMaxEpoch); break;
                        case 2: m.seq = near(m.seq, fsm::kMaxSeq); break;
                        case 3: m.found = !m.found; break;
                        case 4: m.version = any_version(m.version, epoch); break;
                        default: m.state = any_state(); break;
                    }
                },
                [&](fsm::PhaseRequest& m) {
                    m.phase = static_cast<fsm::PhaseId>(rng_.below(static_cast<std::uint64_t>(topology_->phase_count()) + 1));
                },
            },
            message);
    }
    // DDS Security binds every message to its writer: the liar speaks only as itself.
    std::visit([&](auto& m) { m.from = node_; }, message);
    return message;
}

// Mostly a few steps from `base`, sometimes anywhere within the field's width.
std::uint32_t Liar::near(std::uint64_t base, std::uint64_t width_max) {
    return static_cast<std::uint32_t>(near64(base, width_max));
}

std::uint64_t Liar::near64(std::uint64_t base, std::uint64_t width_max) {
    if (rng_.chance(0.15)) return rng_.below(width_max) + (rng_.chance(0.5) ? 1 : 0);
    const auto step = static_cast<std::int64_t>(rng_.below(12)) - 3;
    const auto value = static_cast<std::int64_t>(std::min(base, width_max)) + step;
    return static_cast<std::uint64_t>(std::clamp<std::int64_t>(value, 0, static_cast<std::int64_t>(width_max)));
}

fsm::NodeId Liar::any_node() {
    // One beyond the mission's ids, within a NodeSet's capacity.
    const auto count = std::min<std::uint64_t>(static_cast<std::uint64_t>(topology_->node_count()) + 1,
                                               fsm::kMaxNodes);
    return static_cast<fsm::NodeId>(rng_.below(count));
}

fsm::TaskId Liar::any_task() {
    return static_cast<fsm::TaskId>(rng_.below(static_cast<std::uint64_t>(topology_->task_count()) + 1));
}

fsm::ConfigId Liar::any_config() {
    const auto count = static_cast<std::uint64_t>(topology_->config_count());
    const auto id = rng_.below(count + 2);
    return id == count + 1 ? fsm::kSafeConfig : static_cast<fsm::ConfigId>(id);
}

fsm::NodeSet Liar::any_nodes(fsm::NodeSet around) {
    fsm::NodeSet set = rng_.chance(0.5) ? around : fsm::NodeSet{};
    const fsm::NodeId flipped = any_node();
    if (set.contains(flipped)) set.erase(flipped);
    else set.insert(flipped);
    return set;
}

fsm::View Liar::any_view(const fsm::View& around) {
    fsm::View view = around;
    view.epoch = near(around.epoch, fsm::kMaxEpoch);
    view.seq = near(around.seq, fsm::kMaxSeq);
    if (rng_.chance(0.5)) view.config = any_config();
    view.base = rng_.chance(0.7) ? view.config : any_config();
    view.master = rng_.chance(0.5) ? topology_->owner(view.epoch == 0 ? 1 : view.epoch) : any_node();
    if (rng_.chance(0.5)) view.failed = any_nodes(around.failed);
    // Where the mission places online, an online configuration as often as not: a wrong
    // one, for the receivers' checker (core/fsm/online.hpp) to refuse.
    if (topology_->has_online() && rng_.chance(0.5)) {
        if (rng_.chance(0.8)) view.config = fsm::kOnlineConfig;
        view.base = fsm::kOnlineConfig;
        view.online = any_online(around);
    }
    return view;
}

fsm::OnlinePtr Liar::any_online(const fsm::View& around) {
    auto online = std::make_shared<fsm::OnlineConfig>();
    if (around.online) {
        *online = *around.online;
    } else {
        // A view of the graph (a lie may have left `around` naming none: the initial one).
        const bool graph = !around.is_online() && static_cast<int>(around.base) < topology_->config_count() &&
                           (around.is_safe() || around.config == around.base);
        const fsm::View from = graph ? around : topology_->initial_view();
        online->phase = topology_->phase_of(from);
        online->master = from.master;
        online->observers = topology_->observers(from);
        for (fsm::TaskId task = 0; task < topology_->task_count(); ++task) {
            online->host.push_back(topology_->host(from, task));
        }
    }
    // One value changed, or a few: a task moved (to any node, or unplaced), the master or
    // an observer replaced, the phase, the number of hosts.
    const int changes = 1 + static_cast<int>(rng_.below(3));
    for (int i = 0; i < changes; ++i) {
        switch (rng_.below(6)) {
            case 0:
            case 1:
                if (!online->host.empty()) {
                    const auto task = rng_.below(online->host.size());
                    online->host[task] = rng_.chance(0.3) ? fsm::kNoNode : any_node();
                }
                break;
            case 2: online->master = rng_.chance(0.5) ? node_ : any_node(); break;
            case 3:
                if (!online->observers.empty() && rng_.chance(0.5)) {
                    online->observers[rng_.below(online->observers.size())] = any_node();
                } else {
                    online->observers.push_back(any_node());
                }
                break;
            case 4:
                online->phase = static_cast<fsm::PhaseId>(rng_.below(static_cast<std::uint64_t>(topology_->phase_count()) + 1));
                break;
            default:
                if (rng_.chance(0.5) && !online->host.empty()) online->host.pop_back();
                else online->host.push_back(any_node());
                break;
        }
    }
    return fsm::OnlinePtr(std::move(online));
}

std::vector<std::uint8_t> Liar::any_state() {
    std::vector<std::uint8_t> state(rng_.below(kMaxStateBytes + 1));
    for (auto& byte : state) byte = static_cast<std::uint8_t>(rng_.next());
    return state;
}

fsm::Version Liar::any_version(fsm::Version around, fsm::Epoch epoch) {
    fsm::Version version = around;
    if (rng_.chance(0.3)) {
        version.lineage = fsm::lineage_of(near(epoch, fsm::kMaxEpoch), near(0, fsm::kMaxSeq));
    }
    version.count = rng_.chance(0.7) ? around.count + rng_.below(4) : near64(around.count, fsm::kMaxVersionCount);
    return version;
}

}  // namespace keel::sim
