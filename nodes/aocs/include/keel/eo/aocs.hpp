// The AOCS attitude-determination task: a multiplicative extended Kalman filter (MEKF,
// Lefferts, Markley & Shuster 1982; Markley & Crassidis 2014, ch. 6) that propagates the
// attitude quaternion with gyro rates and corrects it, and the gyro bias, with
// star-tracker quaternions. It is an essential, checkpointed task: snapshot() captures
// the whole filter state, and an instance restored from it on another node continues
// the estimate where the checkpoint left it.
//
// Conventions: q is the rotation from the body frame to the inertial frame (v_I = q v_B),
// Hamilton product (Eigen's), rates in the body frame in rad/s. The filter's error state
// is [attitude error angle (body frame, rad); gyro bias error (rad/s)], defined by
// q_true = q_estimate * dq(attitude error).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace keel::eo::aocs {

using Vector3 = Eigen::Vector3d;
using Quaternion = Eigen::Quaterniond;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

struct EstimatorConfig {
    double gyro_angle_random_walk_rad_per_sqrt_s = 5e-5;   // sigma_v
    double gyro_bias_random_walk_rad_per_s_sqrt_s = 1e-6;  // sigma_u
    double star_tracker_sigma_rad = 5e-5;                  // per axis, about 10 arcsec
    double initial_attitude_sigma_rad = 1e-3;
    double initial_bias_sigma_rad_per_s = 5e-4;
    // Star-tracker residuals beyond this squared Mahalanobis distance are rejected (the
    // 99.99 % point of chi-square with 3 degrees of freedom): a glitching tracker must not
    // pull the estimate away.
    double measurement_gate = 21.1;
};

class AttitudeEstimator {
  public:
    explicit AttitudeEstimator(const EstimatorConfig& config = {},
                               const Quaternion& initial_attitude = Quaternion::Identity());

    // Advances the filter by dt_s using the gyro rates measured over that interval, then,
    // when a star-tracker attitude for the end of the interval is given, corrects with it.
    // dt_s may span several nominal periods (after a migration). Returns whether the
    // star-tracker measurement was used (false when absent or gated out). Inputs come from
    // the network, so bad ones are reported, not asserted: throws std::invalid_argument,
    // leaving the state unchanged, for dt_s <= 0 (a sample not newer than time_s(), e.g.
    // one already covered by a restored checkpoint) or non-finite rates or quaternion.
    bool step(const Vector3& gyro_rad_per_s, double dt_s,
              const std::optional<Quaternion>& star_tracker = std::nullopt);

    Quaternion attitude() const { return attitude_; }
    Vector3 gyro_bias_rad_per_s() const { return bias_; }
    const Matrix6& covariance() const { return covariance_; }
    // One-sigma attitude uncertainty (root of the attitude block's trace), rad: the health
    // value a monitor can check against the mission's bound.
    double attitude_sigma_rad() const;
    double time_s() const { return time_s_; }
    std::uint64_t steps() const { return steps_; }
    std::uint64_t measurements_rejected() const { return rejected_; }
    const EstimatorConfig& config() const { return config_; }

    // Checkpoint: the complete state (attitude, bias, covariance, time, counters and the
    // noise configuration), versioned and checksummed. Little-endian:
    //   u32 magic 'KAOC' | u16 version (1) | u16 reserved | u64 steps | u64 rejected
    //   f64 time_s | f64 q (w, x, y, z) | f64 bias (3) | f64 covariance (36, row-major)
    //   f64 config (6 fields, declaration order) | u32 CRC-32 of everything before it
    std::vector<std::uint8_t> snapshot() const;
    // Replaces this instance's state with a checkpoint's. Throws keel::eo::DecodeError for
    // a wrong magic or version, truncation, a checksum mismatch, or a state that is not
    // physically meaningful (non-unit quaternion, non-finite values, covariance that is
    // not symmetric with a positive diagonal); the instance is unchanged then.
    void restore(std::span<const std::uint8_t> bytes);
    static AttitudeEstimator from_snapshot(std::span<const std::uint8_t> bytes);

  private:
    EstimatorConfig config_;
    Quaternion attitude_;
    Vector3 bias_ = Vector3::Zero();
    Matrix6 covariance_;
    double time_s_ = 0;
    std::uint64_t steps_ = 0;
    std::uint64_t rejected_ = 0;
};

inline constexpr std::uint32_t kSnapshotMagic = 0x434F414BU;  // "KAOC"
inline constexpr std::uint16_t kSnapshotVersion = 1;

// Angle of the rotation between two attitudes, in [0, pi].
double angle_between_rad(const Quaternion& a, const Quaternion& b);

// Deterministic truth for tests and benchmarks: a spacecraft slewing smoothly on top of
// its orbital rate, a gyro with a random-walk bias and white noise, and a star tracker.
struct TruthConfig {
    std::uint64_t seed = 1;
    double gyro_period_s = 0.01;        // 100 Hz gyro
    int star_tracker_every_steps = 10;  // 10 Hz star tracker
    double gyro_angle_random_walk_rad_per_sqrt_s = 5e-5;
    double gyro_bias_random_walk_rad_per_s_sqrt_s = 1e-6;
    double gyro_initial_bias_max_rad_per_s = 2e-4;
    double star_tracker_sigma_rad = 5e-5;
    double orbit_rate_rad_per_s = 0.0011;  // low Earth orbit, nadir pointing
    double slew_rate_max_rad_per_s = 0.02;
};

struct TruthSample {
    double time_s = 0;
    Vector3 gyro_rad_per_s;                  // measured over (time_s - period, time_s]
    std::optional<Quaternion> star_tracker;  // measured at time_s
    Quaternion true_attitude;
    Vector3 true_bias_rad_per_s;
};

class TruthSimulator {
  public:
    explicit TruthSimulator(const TruthConfig& config);
    Quaternion initial_attitude() const { return initial_attitude_; }
    // A star-tracker reading of the initial attitude, to initialise a filter with.
    Quaternion initial_star_tracker();
    TruthSample next();
    // Samples produced so far; the next sample is number steps() + 1.
    std::uint64_t steps() const { return step_; }
    // Fast-forwards (computing and discarding samples) until steps() == step. The world
    // does not restart when a task migrates: a restored AOCS task that simulates its own
    // sensors builds a simulator from the seed, advances it to its checkpoint's step and
    // replays from there to now. Requires step >= steps().
    void advance_to(std::uint64_t step);

  private:
    Vector3 true_rate(double time_s) const;
    Vector3 normal3();

    TruthConfig config_;
    std::uint64_t rng_state_;
    Quaternion initial_attitude_;
    Quaternion attitude_;
    Vector3 bias_;
    Vector3 slew_amplitude_;
    Vector3 slew_frequency_hz_;
    Vector3 slew_phase_;
    std::uint64_t step_ = 0;
};

// A closed-loop run of the estimator against the truth, optionally migrating it: after
// step `migrate_after_step` the instance is destroyed, the next `outage_steps` samples
// reach no instance (the task is being re-placed), and a new instance restored from the
// latest checkpoint (taken every `checkpoint_every_steps`) takes over at the next sample.
//
// Samples the restored instance missed since its checkpoint are either replayed from a
// bounded history (`replay_lost_samples`: what a DDS reader with TRANSIENT_LOCAL
// durability and KEEP_LAST(history_depth_samples) history receives on joining), or,
// without that history, bridged by one propagation from the checkpoint's time to now
// with the newest gyro sample.
struct RunConfig {
    TruthConfig truth{};
    EstimatorConfig estimator{};
    int steps = 2000;
    std::optional<int> migrate_after_step;
    int checkpoint_every_steps = 1;
    int outage_steps = 0;
    bool replay_lost_samples = true;
    int history_depth_samples = 200;
};

struct RunReport {
    std::vector<double>
        error_rad;  // attitude error after each step (index = step - 1); NaN while no instance runs
    std::vector<double> bias_error_rad_per_s;
    std::vector<Quaternion> estimate;  // after each step (identity while no instance runs)
    std::uint64_t snapshot_bytes = 0;
    // Filled for a migrating run:
    int resumed_at_step = 0;   // first step whose sample the restored instance processes live
    int replayed_samples = 0;  // missed samples it replayed from history first
    double jump_rad = 0;       // |error(resumed_at_step) - error(migrate_after_step)|
};

RunReport run(const RunConfig& config);

// Largest step-to-step change of the attitude error of an unmigrated run over steps
// [from_step, end): what one nominal step can move the error by.
double nominal_step_rad(const RunReport& reference, int from_step);

}  // namespace keel::eo::aocs
