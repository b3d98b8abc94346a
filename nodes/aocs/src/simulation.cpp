#include <algorithm>
#include <cassert>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <numbers>

#include "keel/eo/aocs.hpp"

namespace keel::eo::aocs {
namespace {

// SplitMix64: tiny, fast and identical on every platform, so a seed reproduces a run.
std::uint64_t next_bits(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

double uniform(std::uint64_t& state) {
    return static_cast<double>(next_bits(state) >> 11) * 0x1.0p-53;
}

double uniform(std::uint64_t& state, double low, double high) {
    return low + (high - low) * uniform(state);
}

Quaternion rotation(const Vector3& theta) {
    const double angle = theta.norm();
    if (angle < 1e-12)
        return Quaternion(1.0, 0.5 * theta.x(), 0.5 * theta.y(), 0.5 * theta.z()).normalized();
    return Quaternion(Eigen::AngleAxisd(angle, theta / angle));
}

// The truth is integrated in finer steps than the gyro samples it, so the filter's own
// one-step integration error is part of what the test measures.
constexpr int kTruthSubsteps = 10;

}  // namespace

TruthSimulator::TruthSimulator(const TruthConfig& config)
    : config_(config), rng_state_(config.seed) {
    assert(config.gyro_period_s > 0 && config.star_tracker_every_steps > 0);
    const Vector3 axis =
        Vector3(uniform(rng_state_, -1, 1), uniform(rng_state_, -1, 1), uniform(rng_state_, -1, 1));
    initial_attitude_ =
        Quaternion(Eigen::AngleAxisd(uniform(rng_state_, 0, std::numbers::pi), axis.normalized()));
    attitude_ = initial_attitude_;
    for (int i = 0; i < 3; ++i) {
        bias_[i] = uniform(rng_state_, -config.gyro_initial_bias_max_rad_per_s,
                           config.gyro_initial_bias_max_rad_per_s);
        slew_amplitude_[i] = uniform(rng_state_, 0.25, 1.0) * config.slew_rate_max_rad_per_s;
        slew_frequency_hz_[i] = uniform(rng_state_, 0.002, 0.02);
        slew_phase_[i] = uniform(rng_state_, 0, 2 * std::numbers::pi);
    }
}

Vector3 TruthSimulator::true_rate(double time_s) const {
    Vector3 rate(0.0, -config_.orbit_rate_rad_per_s, 0.0);
    for (int i = 0; i < 3; ++i) {
        rate[i] += slew_amplitude_[i] *
                   std::sin(2 * std::numbers::pi * slew_frequency_hz_[i] * time_s + slew_phase_[i]);
    }
    return rate;
}

Vector3 TruthSimulator::normal3() {
    // Box-Muller, written out so the sequence does not depend on the standard library.
    Vector3 out;
    for (int i = 0; i < 3; ++i) {
        const double u1 = std::max(uniform(rng_state_), 1e-300);
        const double u2 = uniform(rng_state_);
        out[i] = std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
    }
    return out;
}

Quaternion TruthSimulator::initial_star_tracker() {
    return (initial_attitude_ * rotation(config_.star_tracker_sigma_rad * normal3())).normalized();
}

TruthSample TruthSimulator::next() {
    const double period = config_.gyro_period_s;
    const double start_s = static_cast<double>(step_) * period;
    ++step_;
    // Truth: integrate the rate at sub-step midpoints; the gyro reports the mean rate.
    Vector3 rate_sum = Vector3::Zero();
    const double substep = period / kTruthSubsteps;
    for (int i = 0; i < kTruthSubsteps; ++i) {
        const Vector3 rate = true_rate(start_s + (i + 0.5) * substep);
        attitude_ = (attitude_ * rotation(rate * substep)).normalized();
        rate_sum += rate;
    }
    // Bias random walk, then white rate noise whose integral over the period has the
    // angle-random-walk variance sigma_v^2 * period.
    bias_ += config_.gyro_bias_random_walk_rad_per_s_sqrt_s * std::sqrt(period) * normal3();
    TruthSample sample;
    sample.time_s = static_cast<double>(step_) * period;
    sample.gyro_rad_per_s =
        rate_sum / kTruthSubsteps + bias_ +
        config_.gyro_angle_random_walk_rad_per_sqrt_s / std::sqrt(period) * normal3();
    sample.true_attitude = attitude_;
    sample.true_bias_rad_per_s = bias_;
    if (step_ % static_cast<std::uint64_t>(config_.star_tracker_every_steps) == 0) {
        sample.star_tracker =
            (attitude_ * rotation(config_.star_tracker_sigma_rad * normal3())).normalized();
    }
    return sample;
}

void TruthSimulator::advance_to(std::uint64_t step) {
    assert(step >= step_ && "the simulator cannot go back in time");
    while (step_ < step) (void)next();
}

RunReport run(const RunConfig& config) {
    assert(config.steps > 0 && config.checkpoint_every_steps > 0 && config.outage_steps >= 0);
    assert(config.history_depth_samples > 0);
    assert(!config.migrate_after_step ||
           (*config.migrate_after_step > 0 &&
            *config.migrate_after_step + config.outage_steps < config.steps));
    TruthSimulator truth(config.truth);
    auto estimator =
        std::make_unique<AttitudeEstimator>(config.estimator, truth.initial_star_tracker());
    std::vector<std::uint8_t> checkpoint = estimator->snapshot();
    RunReport report;
    report.snapshot_bytes = checkpoint.size();
    report.error_rad.reserve(static_cast<std::size_t>(config.steps));
    const int failed_after = config.migrate_after_step.value_or(-1);
    const int resume_at = failed_after + config.outage_steps + 1;
    // The sensor's recent samples, as a bounded history would keep them.
    std::deque<TruthSample> history;
    for (int step = 1; step <= config.steps; ++step) {
        const TruthSample sample = truth.next();
        if (config.migrate_after_step && step > failed_after && step < resume_at) {
            // Nobody runs the task while it is being re-placed.
            report.error_rad.push_back(std::numeric_limits<double>::quiet_NaN());
            report.bias_error_rad_per_s.push_back(std::numeric_limits<double>::quiet_NaN());
            report.estimate.push_back(Quaternion::Identity());
        } else {
            if (config.migrate_after_step && step == resume_at) {
                estimator = std::make_unique<AttitudeEstimator>(
                    AttitudeEstimator::from_snapshot(checkpoint));
                report.resumed_at_step = step;
                if (config.replay_lost_samples) {
                    for (const TruthSample& old : history) {
                        // Half a period of slack: times are sums of periods and may differ in the
                        // last bit.
                        if (old.time_s <= estimator->time_s() + 0.5 * config.truth.gyro_period_s)
                            continue;
                        estimator->step(old.gyro_rad_per_s, old.time_s - estimator->time_s(),
                                        old.star_tracker);
                        ++report.replayed_samples;
                    }
                }
            }
            // Normally one period; after a restore without (enough) history, the whole gap.
            const double dt_s = sample.time_s - estimator->time_s();
            estimator->step(sample.gyro_rad_per_s, dt_s, sample.star_tracker);
            report.error_rad.push_back(
                angle_between_rad(estimator->attitude(), sample.true_attitude));
            report.bias_error_rad_per_s.push_back(
                (estimator->gyro_bias_rad_per_s() - sample.true_bias_rad_per_s).norm());
            report.estimate.push_back(estimator->attitude());
            if (step % config.checkpoint_every_steps == 0) checkpoint = estimator->snapshot();
            if (step == failed_after) estimator.reset();  // the node hosting the task fails
        }
        history.push_back(sample);
        if (history.size() > static_cast<std::size_t>(config.history_depth_samples))
            history.pop_front();
    }
    if (config.migrate_after_step) {
        report.jump_rad = std::abs(report.error_rad[static_cast<std::size_t>(resume_at - 1)] -
                                   report.error_rad[static_cast<std::size_t>(failed_after - 1)]);
    }
    return report;
}

double nominal_step_rad(const RunReport& reference, int from_step) {
    assert(from_step >= 2 && from_step <= static_cast<int>(reference.error_rad.size()));
    double largest = 0;
    for (std::size_t i = static_cast<std::size_t>(from_step - 1); i < reference.error_rad.size();
         ++i) {
        const double change = std::abs(reference.error_rad[i] - reference.error_rad[i - 1]);
        assert(std::isfinite(change) && "the reference run must not migrate");
        largest = std::max(largest, change);
    }
    return largest;
}

}  // namespace keel::eo::aocs
