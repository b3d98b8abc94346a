#include "keel/eo/aocs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numeric>

#include "keel/eo/codec.hpp"

namespace keel::eo::aocs {
namespace {

double mean_over(const std::vector<double>& values, std::size_t from) {
    double sum = 0;
    for (std::size_t i = from; i < values.size(); ++i) sum += values[i];
    return sum / static_cast<double>(values.size() - from);
}

// Rewrites the checkpoint's checksum after a deliberate edit, so the semantic checks
// (not the CRC) are what must reject it.
void reseal(std::vector<std::uint8_t>& bytes) {
    const auto crc = crc32(std::span(bytes).first(bytes.size() - 4));
    for (int i = 0; i < 4; ++i)
        bytes[bytes.size() - 4 + static_cast<std::size_t>(i)] =
            static_cast<std::uint8_t>(crc >> (8 * i));
}

TEST(AocsEstimator, PropagatesAConstantRateExactly) {
    AttitudeEstimator estimator;
    const Vector3 rate(0.01, -0.02, 0.03);
    for (int i = 0; i < 1000; ++i) estimator.step(rate, 0.01);
    const Quaternion expected(Eigen::AngleAxisd(rate.norm() * 10.0, rate.normalized()));
    EXPECT_LT(angle_between_rad(estimator.attitude(), expected), 1e-9);
    EXPECT_NEAR(estimator.time_s(), 10.0, 1e-9);
    EXPECT_EQ(estimator.steps(), 1000U);
}

TEST(AocsEstimator, ConvergesOnAttitudeAndGyroBias) {
    RunConfig config;
    config.truth.seed = 3;
    config.steps = 6000;
    const RunReport report = run(config);
    // A single star-tracker reading is off by about 8e-5 rad (5e-5 per axis); the filter
    // must do better than that.
    EXPECT_LT(mean_over(report.error_rad, 2000), 6e-5);
    // The filter starts from zero bias, so its first bias error is the true bias. With this
    // gyro's angle random walk the bias settles to about 1e-5 .. 3e-5 rad/s.
    EXPECT_LT(mean_over(report.bias_error_rad_per_s, 3000), 5e-5);
    EXPECT_LT(mean_over(report.bias_error_rad_per_s, 3000), 0.5 * report.bias_error_rad_per_s[0]);
}

TEST(AocsEstimator, StarTrackerCorrectionBeatsGyroOnly) {
    RunConfig with;
    with.truth.seed = 4;
    RunConfig without = with;
    without.truth.star_tracker_every_steps = 1'000'000;  // never
    const double corrected = mean_over(run(with).error_rad, 1500);
    const double drifting = mean_over(run(without).error_rad, 1500);
    EXPECT_LT(corrected * 10, drifting);
}

TEST(AocsEstimator, GatesOutAWildStarTrackerReading) {
    AttitudeEstimator estimator;
    for (int i = 0; i < 10; ++i) estimator.step(Vector3::Zero(), 0.01, Quaternion::Identity());
    const Quaternion wild(Eigen::AngleAxisd(0.2, Vector3::UnitX()));
    EXPECT_FALSE(estimator.step(Vector3::Zero(), 0.01, wild));
    EXPECT_EQ(estimator.measurements_rejected(), 1U);
    EXPECT_LT(angle_between_rad(estimator.attitude(), Quaternion::Identity()), 1e-6);
}

TEST(AocsEstimator, RejectsStaleOrNonFiniteInputsWithoutChangingState) {
    AttitudeEstimator estimator;
    estimator.step(Vector3(0.01, 0, 0), 0.01);
    const auto before = estimator.snapshot();
    EXPECT_THROW(estimator.step(Vector3::Zero(), 0.0), std::invalid_argument);
    EXPECT_THROW(estimator.step(Vector3::Zero(), -0.01), std::invalid_argument);
    EXPECT_THROW(estimator.step(Vector3(NAN, 0, 0), 0.01), std::invalid_argument);
    EXPECT_THROW(estimator.step(Vector3::Zero(), 0.01, Quaternion(0, 0, 0, 0)),
                 std::invalid_argument);
    EXPECT_EQ(estimator.snapshot(), before);
}

TEST(AocsTruth, AdvancingReproducesTheSequentialRun) {
    TruthSimulator sequential(TruthConfig{.seed = 12});
    TruthSample expected;
    for (int i = 0; i < 251; ++i) expected = sequential.next();
    TruthSimulator skipping(TruthConfig{.seed = 12});
    skipping.advance_to(250);
    EXPECT_EQ(skipping.steps(), 250U);
    const TruthSample sample = skipping.next();
    EXPECT_EQ(sample.time_s, expected.time_s);
    EXPECT_EQ(sample.gyro_rad_per_s, expected.gyro_rad_per_s);
    EXPECT_EQ(sample.true_attitude.coeffs(), expected.true_attitude.coeffs());
    EXPECT_EQ(sample.star_tracker.has_value(), expected.star_tracker.has_value());
}

TEST(AocsEstimator, AttitudeSigmaShrinksWithStarTrackerUpdates) {
    TruthSimulator truth(TruthConfig{.seed = 13});
    AttitudeEstimator estimator({}, truth.initial_star_tracker());
    const double initial = estimator.attitude_sigma_rad();
    EXPECT_NEAR(initial, std::sqrt(3.0) * 1e-3, 1e-12);
    for (int i = 0; i < 500; ++i) {
        const auto sample = truth.next();
        estimator.step(sample.gyro_rad_per_s, 0.01, sample.star_tracker);
    }
    EXPECT_LT(estimator.attitude_sigma_rad(), 0.1 * initial);
}

TEST(AocsSnapshot, RestoredInstanceContinuesBitForBit) {
    TruthSimulator truth(TruthConfig{.seed = 9});
    AttitudeEstimator original({}, truth.initial_star_tracker());
    for (int i = 0; i < 300; ++i) {
        const auto sample = truth.next();
        original.step(sample.gyro_rad_per_s, 0.01, sample.star_tracker);
    }
    AttitudeEstimator copy = AttitudeEstimator::from_snapshot(original.snapshot());
    for (int i = 0; i < 200; ++i) {
        const auto sample = truth.next();
        original.step(sample.gyro_rad_per_s, 0.01, sample.star_tracker);
        copy.step(sample.gyro_rad_per_s, 0.01, sample.star_tracker);
    }
    EXPECT_EQ(copy.attitude().coeffs(), original.attitude().coeffs());
    EXPECT_EQ(copy.gyro_bias_rad_per_s(), original.gyro_bias_rad_per_s());
    EXPECT_EQ(copy.covariance(), original.covariance());
    EXPECT_EQ(copy.steps(), 500U);
}

TEST(AocsSnapshot, RejectsCorruptTruncatedAndMeaninglessCheckpoints) {
    AttitudeEstimator estimator;
    estimator.step(Vector3(0.01, 0, 0), 0.01, Quaternion::Identity());
    const auto good = estimator.snapshot();
    AttitudeEstimator target;
    const auto before = target.snapshot();

    auto flipped = good;
    flipped[60] ^= 0x04;
    EXPECT_THROW(target.restore(flipped), DecodeError);
    EXPECT_THROW(target.restore(std::span(good).first(good.size() - 1)), DecodeError);
    EXPECT_THROW(target.restore(std::span(good).first(3)), DecodeError);
    auto version = good;
    version[4] = 2;
    reseal(version);
    EXPECT_THROW(target.restore(version), DecodeError);
    // A well-sealed checkpoint whose quaternion is not unit length (w doubled).
    auto stretched = good;
    double w = 0;
    std::memcpy(&w, &stretched[32], sizeof w);
    w *= 2;
    std::memcpy(&stretched[32], &w, sizeof w);
    reseal(stretched);
    EXPECT_THROW(target.restore(stretched), DecodeError);
    // A negative variance on the diagonal.
    auto negative = good;
    double variance = -1e-6;
    std::memcpy(&negative[32 + 7 * 8], &variance, sizeof variance);
    reseal(negative);
    EXPECT_THROW(target.restore(negative), DecodeError);
    // Every rejection left the instance as it was.
    EXPECT_EQ(target.snapshot(), before);
    target.restore(good);
    EXPECT_EQ(target.snapshot(), good);
}

TEST(AocsSnapshot, RejectsEverySingleByteCorruption) {
    AttitudeEstimator estimator;
    estimator.step(Vector3(0.01, 0.02, 0), 0.01, Quaternion::Identity());
    const auto good = estimator.snapshot();
    for (std::size_t position = 0; position < good.size(); ++position) {
        auto bad = good;
        bad[position] ^= 0x80;
        AttitudeEstimator target;
        EXPECT_THROW(target.restore(bad), DecodeError) << "byte " << position;
    }
}

TEST(AocsMigration, CheckpointEveryStepMakesTheMigrationInvisible) {
    RunConfig reference_config;
    reference_config.truth.seed = 5;
    reference_config.steps = 1200;
    const RunReport reference = run(reference_config);
    RunConfig migrating = reference_config;
    migrating.migrate_after_step = 600;
    const RunReport migrated = run(migrating);
    EXPECT_EQ(migrated.resumed_at_step, 601);
    EXPECT_EQ(migrated.error_rad, reference.error_rad);
    EXPECT_LE(migrated.jump_rad, nominal_step_rad(reference, 300));
}

TEST(AocsMigration, ReplayingMissedSamplesResumesOnTheReferenceTrajectory) {
    // The checkpoint is 4 steps old when the node fails and the task is away for 5 more
    // steps; the restored instance replays the 9 samples it missed, then runs live.
    RunConfig reference_config;
    reference_config.truth.seed = 2;
    reference_config.steps = 1500;
    const RunReport reference = run(reference_config);
    RunConfig migrating = reference_config;
    migrating.migrate_after_step = 804;
    migrating.checkpoint_every_steps = 10;
    migrating.outage_steps = 5;
    const RunReport migrated = run(migrating);
    EXPECT_EQ(migrated.resumed_at_step, 810);
    EXPECT_EQ(migrated.replayed_samples, 9);
    for (std::size_t i = 809; i < reference.error_rad.size(); ++i) {
        ASSERT_EQ(migrated.estimate[i].coeffs(), reference.estimate[i].coeffs())
            << "step " << i + 1;
    }
    EXPECT_DOUBLE_EQ(migrated.jump_rad,
                     std::abs(reference.error_rad[809] - reference.error_rad[803]));
}

TEST(AocsMigration, WithoutHistoryTheBridgeStepCostsOnlyItsGyroNoise) {
    // Without replay, one gyro sample stands for the whole 90 ms gap, so its white noise
    // is integrated over 9 periods instead of averaging out: the jump is bounded by a
    // nominal step plus 4 sigma of that extra noise (3 axes).
    for (std::uint64_t seed : {1, 2, 3, 4}) {
        RunConfig reference_config;
        reference_config.truth.seed = seed;
        reference_config.steps = 1500;
        const RunReport reference = run(reference_config);
        RunConfig migrating = reference_config;
        migrating.migrate_after_step = 804;
        migrating.checkpoint_every_steps = 10;
        migrating.outage_steps = 5;
        migrating.replay_lost_samples = false;
        const RunReport migrated = run(migrating);
        EXPECT_EQ(migrated.replayed_samples, 0);
        const double period_s = reference_config.truth.gyro_period_s;
        const double gap_s = 10 * period_s;
        const double sample_sigma =
            reference_config.truth.gyro_angle_random_walk_rad_per_sqrt_s / std::sqrt(period_s);
        const double bound =
            nominal_step_rad(reference, 500) + 4 * std::sqrt(3.0) * sample_sigma * gap_s;
        EXPECT_LE(migrated.jump_rad, bound) << "seed " << seed;
        // The star tracker pulls it back: a second later it is as good as the reference.
        EXPECT_LT(mean_over(migrated.error_rad, 910), 2 * mean_over(reference.error_rad, 910))
            << "seed " << seed;
    }
}

}  // namespace
}  // namespace keel::eo::aocs
