#include "core/net/fault_transport.hpp"

#include <algorithm>
#include <stdexcept>

namespace keel::net {

void FaultPlan::partition(const std::set<NodeAddress>& group_a,
                          const std::set<NodeAddress>& group_b) {
    std::lock_guard lock(mutex_);
    for (NodeAddress a : group_a) {
        for (NodeAddress b : group_b) {
            blocked_.emplace(a, b);
            blocked_.emplace(b, a);
        }
    }
}

void FaultPlan::block(NodeAddress from, NodeAddress to) {
    std::lock_guard lock(mutex_);
    blocked_.emplace(from, to);
}

void FaultPlan::unblock(NodeAddress from, NodeAddress to) {
    std::lock_guard lock(mutex_);
    blocked_.erase({from, to});
}

void FaultPlan::heal() {
    std::lock_guard lock(mutex_);
    blocked_.clear();
}

bool FaultPlan::blocked(NodeAddress from, NodeAddress to) const {
    std::lock_guard lock(mutex_);
    return blocked_.contains({from, to});
}

Clock steady_clock_source() {
    return [] {
        return std::chrono::duration_cast<std::chrono::nanoseconds>(
            std::chrono::steady_clock::now().time_since_epoch());
    };
}

namespace {
void check_faults(double loss, double duplicate, std::chrono::nanoseconds delay_min,
                  std::chrono::nanoseconds delay_max) {
    if (!(loss >= 0.0 && loss <= 1.0) || !(duplicate >= 0.0 && duplicate <= 1.0)) {
        throw std::invalid_argument("fault probabilities must lie in [0, 1]");
    }
    if (delay_min.count() < 0 || delay_max < delay_min) {
        throw std::invalid_argument("fault delays need 0 <= delay_min <= delay_max");
    }
}
}  // namespace

FaultTransport::FaultTransport(std::unique_ptr<Transport> inner, FaultConfig config)
    : inner_(std::move(inner)), config_(std::move(config)), random_(config_.seed) {
    if (!inner_) throw std::invalid_argument("FaultTransport needs a transport to wrap");
    check_faults(config_.loss_probability, config_.duplicate_probability, config_.delay_min,
                 config_.delay_max);
    if (!config_.clock) config_.clock = steady_clock_source();
}

void FaultTransport::set_faults(double loss_probability, double duplicate_probability,
                                std::chrono::nanoseconds delay_min,
                                std::chrono::nanoseconds delay_max) {
    check_faults(loss_probability, duplicate_probability, delay_min, delay_max);
    config_.loss_probability = loss_probability;
    config_.duplicate_probability = duplicate_probability;
    config_.delay_min = delay_min;
    config_.delay_max = delay_max;
}

double FaultTransport::draw_unit() {
    // 53 random bits as a double in [0, 1): identical on every platform, unlike
    // std::uniform_real_distribution.
    return static_cast<double>(random_() >> 11) * 0x1.0p-53;
}

void FaultTransport::hold(Inbound&& item, std::chrono::nanoseconds release) {
    if (held_.size() >= config_.max_held) {
        ++lost_;
        return;
    }
    held_.push(Held{release, next_order_++, std::move(item)});
}

void FaultTransport::admit(Inbound&& item, std::chrono::nanoseconds now) {
    if (!item.ok) {
        hold(std::move(item), now);
        return;
    }
    const double loss_draw = draw_unit();
    const double duplicate_draw = draw_unit();
    const double delay_draw = draw_unit();
    if (config_.plan && config_.plan->blocked(item.envelope.source, local_address())) {
        ++partitioned_;
        return;
    }
    if (loss_draw < config_.loss_probability) {
        ++lost_;
        return;
    }
    const auto spread = static_cast<double>((config_.delay_max - config_.delay_min).count());
    const std::chrono::nanoseconds delay =
        config_.delay_min + std::chrono::nanoseconds(static_cast<std::int64_t>(spread * delay_draw));
    if (delay.count() > 0) ++delayed_;
    if (duplicate_draw < config_.duplicate_probability) {
        ++duplicated_;
        Inbound copy = item;
        hold(std::move(copy), now + delay);
    }
    hold(std::move(item), now + delay);
}

std::size_t FaultTransport::receive(std::vector<Inbound>& out, std::size_t max_items) {
    const std::chrono::nanoseconds now = config_.clock();
    scratch_.clear();
    inner_->receive(scratch_, max_items);
    for (Inbound& item : scratch_) admit(std::move(item), now);
    scratch_.clear();
    std::size_t released = 0;
    while (released < max_items && !held_.empty() && held_.top().release <= now) {
        // priority_queue::top() is const; the element is popped right after being moved from.
        out.push_back(std::move(const_cast<Held&>(held_.top()).item));
        held_.pop();
        ++released;
    }
    return released;
}

bool FaultTransport::wait(std::chrono::nanoseconds timeout) {
    if (!held_.empty()) {
        const std::chrono::nanoseconds until_release = held_.top().release - config_.clock();
        if (until_release.count() <= 0) return true;
        timeout = std::min(timeout, until_release);
        inner_->wait(timeout);
        return true;
    }
    return inner_->wait(timeout);
}

TransportCounters FaultTransport::counters() const {
    TransportCounters counters = inner_->counters();
    counters.fault_lost += lost_.load();
    counters.fault_partitioned += partitioned_.load();
    counters.fault_duplicated += duplicated_.load();
    counters.fault_delayed += delayed_.load();
    return counters;
}

}  // namespace keel::net
