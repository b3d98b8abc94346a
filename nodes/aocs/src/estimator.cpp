#include <cassert>
#include <cmath>
#include <stdexcept>
#include <string>

#include "keel/eo/aocs.hpp"
#include "keel/eo/codec.hpp"

namespace keel::eo::aocs {
namespace {

using Matrix3 = Eigen::Matrix3d;

Matrix3 cross_matrix(const Vector3& v) {
    Matrix3 m;
    m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
    return m;
}

// Rotation by the rotation vector theta (rad), as a unit quaternion.
Quaternion rotation(const Vector3& theta) {
    const double angle = theta.norm();
    if (angle < 1e-12)
        return Quaternion(1.0, 0.5 * theta.x(), 0.5 * theta.y(), 0.5 * theta.z()).normalized();
    return Quaternion(Eigen::AngleAxisd(angle, theta / angle));
}

constexpr int kConfigFields = 6;
constexpr std::size_t kSnapshotBytes =
    4 + 2 + 2 + 8 + 8 + 8 + 4 * 8 + 3 * 8 + 36 * 8 + kConfigFields * 8 + 4;

}  // namespace

double angle_between_rad(const Quaternion& a, const Quaternion& b) {
    const double w = std::abs((a.conjugate() * b).normalized().w());
    return 2.0 * std::acos(std::min(1.0, w));
}

AttitudeEstimator::AttitudeEstimator(const EstimatorConfig& config,
                                     const Quaternion& initial_attitude)
    : config_(config), attitude_(initial_attitude.normalized()) {
    assert(config.gyro_angle_random_walk_rad_per_sqrt_s > 0 && config.star_tracker_sigma_rad > 0);
    assert(config.initial_attitude_sigma_rad > 0 && config.initial_bias_sigma_rad_per_s > 0);
    covariance_.setZero();
    covariance_.topLeftCorner<3, 3>() =
        Matrix3::Identity() * std::pow(config.initial_attitude_sigma_rad, 2);
    covariance_.bottomRightCorner<3, 3>() =
        Matrix3::Identity() * std::pow(config.initial_bias_sigma_rad_per_s, 2);
}

double AttitudeEstimator::attitude_sigma_rad() const {
    return std::sqrt(covariance_.topLeftCorner<3, 3>().trace());
}

bool AttitudeEstimator::step(const Vector3& gyro_rad_per_s, double dt_s,
                             const std::optional<Quaternion>& star_tracker) {
    if (!(dt_s > 0) || !std::isfinite(dt_s)) {
        throw std::invalid_argument("AOCS step: time must advance (dt_s = " + std::to_string(dt_s) +
                                    ")");
    }
    if (!gyro_rad_per_s.allFinite())
        throw std::invalid_argument("AOCS step: non-finite gyro rates");
    if (star_tracker && (!star_tracker->coeffs().allFinite() || star_tracker->norm() < 0.5)) {
        throw std::invalid_argument(
            "AOCS step: star-tracker quaternion is not finite and near unit length");
    }
    // Propagation: integrate the bias-corrected rate, and the error covariance with the
    // discrete transition matrix for a constant rate over the interval.
    const Vector3 rate = gyro_rad_per_s - bias_;
    attitude_ = (attitude_ * rotation(rate * dt_s)).normalized();
    Matrix6 transition = Matrix6::Identity();
    transition.topLeftCorner<3, 3>() = rotation(rate * dt_s).toRotationMatrix().transpose();
    transition.topRightCorner<3, 3>() =
        -Matrix3::Identity() * dt_s + 0.5 * cross_matrix(rate) * dt_s * dt_s;
    // Discrete process noise of a rate-integrating gyro (Farrenkopf's model).
    const double sv2 = std::pow(config_.gyro_angle_random_walk_rad_per_sqrt_s, 2);
    const double su2 = std::pow(config_.gyro_bias_random_walk_rad_per_s_sqrt_s, 2);
    Matrix6 noise = Matrix6::Zero();
    noise.topLeftCorner<3, 3>() =
        Matrix3::Identity() * (sv2 * dt_s + su2 * dt_s * dt_s * dt_s / 3.0);
    noise.topRightCorner<3, 3>() = -Matrix3::Identity() * (su2 * dt_s * dt_s / 2.0);
    noise.bottomLeftCorner<3, 3>() = noise.topRightCorner<3, 3>();
    noise.bottomRightCorner<3, 3>() = Matrix3::Identity() * (su2 * dt_s);
    covariance_ = transition * covariance_ * transition.transpose() + noise;
    covariance_ = 0.5 * (covariance_ + covariance_.transpose()).eval();
    time_s_ += dt_s;
    ++steps_;
    if (!star_tracker) return false;

    // Update: the residual is the small rotation from the estimate to the measurement.
    Quaternion residual = attitude_.conjugate() * star_tracker->normalized();
    if (residual.w() < 0) residual.coeffs() *= -1.0;  // the shorter way round
    const Vector3 innovation = 2.0 * residual.vec();
    const Matrix3 innovation_covariance =
        covariance_.topLeftCorner<3, 3>() +
        Matrix3::Identity() * std::pow(config_.star_tracker_sigma_rad, 2);
    const Matrix3 inverse = innovation_covariance.inverse();
    if (innovation.dot(inverse * innovation) > config_.measurement_gate) {
        ++rejected_;
        return false;
    }
    const Eigen::Matrix<double, 6, 3> gain = covariance_.leftCols<3>() * inverse;
    const Eigen::Matrix<double, 6, 1> correction = gain * innovation;
    attitude_ = (attitude_ * rotation(correction.head<3>())).normalized();
    bias_ += correction.tail<3>();
    // Joseph form: stays symmetric positive definite under rounding.
    Matrix6 keep = Matrix6::Identity();
    keep.leftCols<3>() -= gain;
    covariance_ = keep * covariance_ * keep.transpose() +
                  gain * gain.transpose() * std::pow(config_.star_tracker_sigma_rad, 2);
    covariance_ = 0.5 * (covariance_ + covariance_.transpose()).eval();
    return true;
}

std::vector<std::uint8_t> AttitudeEstimator::snapshot() const {
    std::vector<std::uint8_t> out;
    out.reserve(kSnapshotBytes);
    ByteWriter writer(out);
    writer.u32(kSnapshotMagic);
    writer.u16(kSnapshotVersion);
    writer.u16(0);
    writer.u64(steps_);
    writer.u64(rejected_);
    writer.f64(time_s_);
    for (double value : {attitude_.w(), attitude_.x(), attitude_.y(), attitude_.z()})
        writer.f64(value);
    for (int i = 0; i < 3; ++i) writer.f64(bias_[i]);
    for (int row = 0; row < 6; ++row) {
        for (int column = 0; column < 6; ++column) writer.f64(covariance_(row, column));
    }
    for (double value : {config_.gyro_angle_random_walk_rad_per_sqrt_s,
                         config_.gyro_bias_random_walk_rad_per_s_sqrt_s,
                         config_.star_tracker_sigma_rad, config_.initial_attitude_sigma_rad,
                         config_.initial_bias_sigma_rad_per_s, config_.measurement_gate}) {
        writer.f64(value);
    }
    writer.u32(crc32(out));
    assert(out.size() == kSnapshotBytes);
    return out;
}

void AttitudeEstimator::restore(std::span<const std::uint8_t> bytes) {
    ByteReader reader(bytes);
    if (reader.u32("magic") != kSnapshotMagic)
        throw DecodeError("not an AOCS checkpoint: bad magic");
    const auto version = reader.u16("version");
    if (version != kSnapshotVersion)
        throw DecodeError("unsupported AOCS checkpoint version " + std::to_string(version));
    (void)reader.u16("reserved");
    if (bytes.size() != kSnapshotBytes) {
        throw DecodeError("AOCS checkpoint is " + std::to_string(bytes.size()) +
                          " bytes, expected " + std::to_string(kSnapshotBytes));
    }
    const auto stored_crc = static_cast<std::uint32_t>(bytes[kSnapshotBytes - 4]) |
                            (static_cast<std::uint32_t>(bytes[kSnapshotBytes - 3]) << 8) |
                            (static_cast<std::uint32_t>(bytes[kSnapshotBytes - 2]) << 16) |
                            (static_cast<std::uint32_t>(bytes[kSnapshotBytes - 1]) << 24);
    if (crc32(bytes.first(kSnapshotBytes - 4)) != stored_crc)
        throw DecodeError("AOCS checkpoint checksum mismatch");

    // Decode into locals first so a rejected checkpoint leaves this instance untouched.
    const auto steps = reader.u64("steps");
    const auto rejected = reader.u64("rejected");
    const double time_s = reader.f64("time_s");
    const double w = reader.f64("q.w");
    const double x = reader.f64("q.x");
    const double y = reader.f64("q.y");
    const double z = reader.f64("q.z");
    const Quaternion attitude(w, x, y, z);
    Vector3 bias;
    for (int i = 0; i < 3; ++i) bias[i] = reader.f64("bias");
    Matrix6 covariance;
    for (int row = 0; row < 6; ++row) {
        for (int column = 0; column < 6; ++column)
            covariance(row, column) = reader.f64("covariance");
    }
    EstimatorConfig config;
    config.gyro_angle_random_walk_rad_per_sqrt_s = reader.f64("config");
    config.gyro_bias_random_walk_rad_per_s_sqrt_s = reader.f64("config");
    config.star_tracker_sigma_rad = reader.f64("config");
    config.initial_attitude_sigma_rad = reader.f64("config");
    config.initial_bias_sigma_rad_per_s = reader.f64("config");
    config.measurement_gate = reader.f64("config");

    if (!std::isfinite(time_s) || time_s < 0) throw DecodeError("AOCS checkpoint: bad time");
    if (!attitude.coeffs().allFinite() || std::abs(attitude.norm() - 1.0) > 1e-9) {
        throw DecodeError("AOCS checkpoint: attitude is not a unit quaternion");
    }
    if (!bias.allFinite() || !covariance.allFinite())
        throw DecodeError("AOCS checkpoint: non-finite state");
    if ((covariance - covariance.transpose()).cwiseAbs().maxCoeff() >
            1e-12 * (1.0 + covariance.cwiseAbs().maxCoeff()) ||
        (covariance.diagonal().array() <= 0).any()) {
        throw DecodeError("AOCS checkpoint: covariance is not symmetric with a positive diagonal");
    }
    if (!(config.gyro_angle_random_walk_rad_per_sqrt_s > 0 &&
          config.gyro_bias_random_walk_rad_per_s_sqrt_s >= 0 && config.star_tracker_sigma_rad > 0 &&
          config.initial_attitude_sigma_rad > 0 && config.initial_bias_sigma_rad_per_s > 0 &&
          config.measurement_gate > 0)) {
        throw DecodeError("AOCS checkpoint: bad noise configuration");
    }
    config_ = config;
    attitude_ = attitude;
    bias_ = bias;
    covariance_ = covariance;
    time_s_ = time_s;
    steps_ = steps;
    rejected_ = rejected;
}

AttitudeEstimator AttitudeEstimator::from_snapshot(std::span<const std::uint8_t> bytes) {
    AttitudeEstimator estimator;
    estimator.restore(bytes);
    return estimator;
}

}  // namespace keel::eo::aocs
