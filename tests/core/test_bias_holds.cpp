#include "liod/angles.hpp"
#include "liod/bias_holds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "liod/so3.hpp"

namespace liod {
namespace {

// A covariance with every state correlated with every other.
StateCovariance random_covariance(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 0.1);
  StateCovariance a;
  for (int i = 0; i < kStateDim; ++i) {
    for (int j = 0; j < kStateDim; ++j) a(i, j) = n(rng);
  }
  return a * a.transpose() + 0.01 * StateCovariance::Identity();
}

StateVector unit(int segment, const Eigen::VectorXd& direction) {
  StateVector u = StateVector::Zero();
  u.segment(segment, direction.size()) = direction.normalized();
  return u;
}

// The error state a position measurement (noise 0.1 m) moves the state by, from covariance p.
StateVector position_update(const StateCovariance& p, const Eigen::Vector3d& residual) {
  Eigen::Matrix<double, 3, kStateDim> h = Eigen::Matrix<double, 3, kStateDim>::Zero();
  h.block<3, 3>(0, 3).setIdentity();
  const Eigen::Matrix3d s = h * p * h.transpose() + 0.01 * Eigen::Matrix3d::Identity();
  return p * h.transpose() * s.ldlt().solve(residual);
}

// The forward accelerometer bias and the gravity tilt along the track (the combination that
// changes the acceleration along the body's forward axis) lose every correlation with the pose and
// velocity and keep their own variances: a position fix then teaches them nothing, while the
// lateral bias, not held, keeps its correlations.
TEST(HoldForwardAcceleration, CutsTheForwardBiasAndAlongTrackTiltFromThePoseAndVelocity) {
  NavState x;
  x.rotation = so3::exp(Eigen::Vector3d(0, 0, 30.0 * kDegToRad)) * so3::exp(Eigen::Vector3d(0, 2.0 * kDegToRad, 0));
  x.gravity = so3::exp(Eigen::Vector3d(0.01, -0.005, 0)) * Eigen::Vector3d(0, 0, -9.80665);
  const Eigen::Vector3d forward(1.0, 0.0, 0.0);
  const StateCovariance p = random_covariance(1);
  StateCovariance held = p;
  hold_forward_acceleration(held, x, forward);

  const StateVector bias = unit(12, forward);
  // The along-track tilt: each gravity dimension's effect on the acceleration along the forward
  // axis in the world, by finite differences through boxplus.
  Eigen::Vector2d along;
  for (int i = 0; i < 2; ++i) {
    const StateVector step = 1e-6 * unit(kGravityIndex, Eigen::Vector2d::Unit(i));
    along(i) = (x.rotation * forward).dot(boxplus(x, step).gravity - boxplus(x, -step).gravity) / 2e-6;
  }
  const StateVector tilt = unit(kGravityIndex, along);
  const StateVector lateral = unit(12, Eigen::Vector3d::UnitY());

  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(held.row(i).dot(bias), 0.0, 1e-12) << "pose/velocity " << i;
    EXPECT_NEAR(held.row(i).dot(tilt), 0.0, 1e-6) << "pose/velocity " << i;
    EXPECT_NEAR(held.row(i).dot(lateral), p.row(i).dot(lateral), 1e-12) << "pose/velocity " << i;
  }
  EXPECT_NEAR(bias.dot(held * bias), bias.dot(p * bias), 1e-12);
  EXPECT_NEAR(tilt.dot(held * tilt), tilt.dot(p * tilt), 1e-6);
  EXPECT_NEAR(bias.dot(held * tilt), bias.dot(p * tilt), 1e-6) << "held together: their joint covariance stays";

  const Eigen::Vector3d residual(0.5, -0.2, 0.1);
  const StateVector before = position_update(p, residual);
  const StateVector after = position_update(held, residual);
  ASSERT_GT(std::abs(before.dot(bias)), 1e-3) << "without the hold the fix moves the forward bias";
  EXPECT_NEAR(after.dot(bias), 0.0, 1e-12);
  EXPECT_NEAR(after.dot(tilt), 0.0, 1e-6);
  EXPECT_GT(std::abs(after.dot(lateral)), 1e-3);
}

// The gyro bias about the (tilted) up axis keeps its prior through a heading update; the other
// gyro-bias directions stay correlated with the heading.
TEST(HoldYawRateBias, CutsTheBiasAboutUpFromEverythingElse) {
  const Eigen::Vector3d up(0.05, 0.0, 1.0);
  const StateCovariance p = random_covariance(2);
  StateCovariance held = p;
  hold_yaw_rate_bias(held, up);
  const StateVector yaw_bias = unit(9, up);
  const StateVector across = unit(9, Eigen::Vector3d(1.0, 0.0, -0.05));
  for (int i = 0; i < kStateDim; ++i) {
    if (i >= 9 && i < 12) continue;
    EXPECT_NEAR(held.row(i).dot(yaw_bias), 0.0, 1e-12) << "state " << i;
    EXPECT_NEAR(held.row(i).dot(across), p.row(i).dot(across), 1e-12) << "state " << i;
  }
  EXPECT_NEAR(across.dot(held * yaw_bias), 0.0, 1e-12);
  EXPECT_NEAR(yaw_bias.dot(held * yaw_bias), yaw_bias.dot(p * yaw_bias), 1e-12);
}

TEST(HoldImuStates, ZeroesTheImuStatesCrossTermsAndKeepsTheBlocks) {
  const StateCovariance p = random_covariance(3);
  StateCovariance held = p;
  hold_imu_states(held);
  EXPECT_EQ((held.block<9, 8>(0, 9)).norm(), 0.0);
  EXPECT_EQ((held.block<8, 9>(9, 0)).norm(), 0.0);
  EXPECT_LT((held.block<9, 9>(0, 0) - p.block<9, 9>(0, 0)).norm(), 1e-12) << "pose and velocity keep their own";
  EXPECT_LT((held.block<8, 8>(9, 9) - p.block<8, 8>(9, 9)).norm(), 1e-12) << "biases and gravity keep theirs";
}

// An update 0.3 m along x and 0.1 m down from the prediction, and 0.02 rad about the body's y,
// with a pose covariance of 0.1 m and 0.01 rad: (3^2 + 1^2) + 2^2. The velocity and bias changes
// do not count.
TEST(PredictionNis, IsTheSquaredMahalanobisDistanceOverThePose) {
  NavState predicted;
  predicted.rotation = so3::exp(Eigen::Vector3d(0.1, -0.2, 1.0));
  predicted.position = Eigen::Vector3d(10.0, 5.0, 1.0);
  NavState updated = predicted;
  updated.position += Eigen::Vector3d(0.3, 0.0, -0.1);
  updated.rotation = predicted.rotation * so3::exp(Eigen::Vector3d(0.0, 0.02, 0.0));
  updated.velocity += Eigen::Vector3d(5.0, 0.0, 0.0);
  updated.accel_bias += Eigen::Vector3d(1.0, 1.0, 1.0);
  StateCovariance p = StateCovariance::Identity() * 1e-6;
  p.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity() * 0.01 * 0.01;
  p.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * 0.1 * 0.1;
  EXPECT_NEAR(prediction_nis(updated, predicted, p), 14.0, 1e-6);

  // Correlated: d^T P^-1 d over the 6 pose dimensions.
  StateCovariance correlated = random_covariance(4);
  Eigen::Matrix<double, 6, 1> d;
  d << 0.0, 0.02, 0.0, 0.3, 0.0, -0.1;
  const double expected = d.dot(correlated.topLeftCorner<6, 6>().inverse() * d);
  EXPECT_NEAR(prediction_nis(updated, predicted, correlated), expected, 1e-6 * expected);
}

// Over a 0.1 s scan, a turn of 1 deg is 10 deg/s: above the 5 deg/s threshold only if the IMU's
// prediction and the update both turned so; a roll does not count.
TEST(TurningFasterThan, OnlyWhenBothThePredictionAndTheUpdateTurnAboutTheVertical) {
  NavState start;
  start.rotation = so3::exp(Eigen::Vector3d(0, 0, 0.3));
  auto yawed = [&](double deg) {
    NavState s = start;
    s.rotation = start.rotation * so3::exp(Eigen::Vector3d(0, 0, deg * kDegToRad));
    return s;
  };
  EXPECT_TRUE(turning_faster_than(start, yawed(1.0), yawed(1.0), 0.1, 5.0));
  EXPECT_TRUE(turning_faster_than(start, yawed(-1.0), yawed(-0.8), 0.1, 5.0)) << "right turns too";
  EXPECT_FALSE(turning_faster_than(start, yawed(1.0), start, 0.1, 5.0)) << "the update did not turn";
  EXPECT_FALSE(turning_faster_than(start, start, yawed(1.0), 0.1, 5.0)) << "the IMU did not turn";
  EXPECT_FALSE(turning_faster_than(start, yawed(0.4), yawed(0.4), 0.1, 5.0)) << "4 deg/s";
  EXPECT_FALSE(turning_faster_than(start, yawed(1.0), yawed(1.0), 0.1, 0.0)) << "threshold 0: never";
  EXPECT_FALSE(turning_faster_than(start, yawed(1.0), yawed(1.0), 0.0, 5.0)) << "no duration";
  NavState rolled = start;
  rolled.rotation = start.rotation * so3::exp(Eigen::Vector3d(2.0 * kDegToRad, 0, 0));
  EXPECT_FALSE(turning_faster_than(start, rolled, rolled, 0.1, 5.0)) << "a roll is no turn";
}

BiasHoldConfig small_config() {
  BiasHoldConfig c;
  c.degeneracy_eigenvalue = 30.0;
  c.release_eigenvalue_factor = 2.0;
  c.consistent_scans_to_release = 5;
  c.max_prediction_nis = 200.0;
  return c;
}

TEST(BiasHolds, HoldsOnADegenerateScanAndReleasesOnlyWellAboveTheThreshold) {
  BiasHolds holds(small_config());
  EXPECT_FALSE(holds.forward_held());
  holds.decide_next(45.0, false);
  EXPECT_FALSE(holds.forward_held()) << "not degenerate";
  holds.decide_next(25.0, false);
  EXPECT_TRUE(holds.forward_held()) << "degenerate";
  holds.decide_next(45.0, false);
  EXPECT_TRUE(holds.forward_held()) << "above the threshold, below twice it";
  holds.decide_next(59.0, false);
  EXPECT_TRUE(holds.forward_held());
  holds.decide_next(60.0, false);
  EXPECT_FALSE(holds.forward_held()) << "twice the threshold releases";
  holds.decide_next(45.0, false);
  EXPECT_FALSE(holds.forward_held()) << "once released, the plain threshold decides";
}

TEST(BiasHolds, ATurnReleasesOnlyAfterEnoughScansTheImuAgreedWith) {
  BiasHolds holds(small_config());
  NavState predicted;
  const StateCovariance p = StateCovariance::Identity() * 0.01;
  NavState far = predicted;
  far.position.x() += 2.0;  // nis 400
  holds.hold_forward(true);
  for (int scan = 1; scan <= 5; ++scan) {
    EXPECT_FALSE(holds.imu_contradicts(predicted, predicted, p));
    holds.decide_next(10.0, scan < 5);  // the fifth: consistent, but no turn
    EXPECT_TRUE(holds.forward_held()) << "scan " << scan;
  }
  holds.decide_next(10.0, true);
  EXPECT_FALSE(holds.forward_held()) << "five consistent scans and a turn";

  // One contradiction starts the count again.
  holds.hold_forward(true);
  EXPECT_TRUE(holds.imu_contradicts(far, predicted, p));
  holds.decide_next(10.0, true);
  EXPECT_TRUE(holds.forward_held());
  for (int scan = 1; scan <= 4; ++scan) {
    EXPECT_FALSE(holds.imu_contradicts(predicted, predicted, p));
    holds.decide_next(10.0, true);
    EXPECT_TRUE(holds.forward_held()) << "scan " << scan << " after the contradiction";
  }
  EXPECT_FALSE(holds.imu_contradicts(predicted, predicted, p));
  holds.decide_next(10.0, true);
  EXPECT_FALSE(holds.forward_held());
}

// With a pose covariance of 0.1 m, 1 m off is a distance of 100 (within 200), 2 m 400 (beyond).
TEST(BiasHolds, ImuContradictsCountsUpdatesFarFromThePrediction) {
  BiasHolds holds(small_config());
  NavState predicted;
  const StateCovariance p = StateCovariance::Identity() * 0.01;
  NavState near = predicted;
  near.position.y() += 1.0;
  NavState far = predicted;
  far.position.y() += 2.0;
  EXPECT_FALSE(holds.imu_contradicts(near, predicted, p));
  EXPECT_EQ(holds.inconsistent_scans(), 0U);
  EXPECT_TRUE(holds.imu_contradicts(far, predicted, p));
  EXPECT_TRUE(holds.imu_contradicts(far, predicted, p));
  EXPECT_EQ(holds.inconsistent_scans(), 2U);
}

TEST(BiasHolds, ApplyHoldsTheForwardAccelerationOnlyWhileHeld) {
  BiasHolds holds(small_config());
  NavState predicted;
  const StateCovariance p = random_covariance(5);
  StateCovariance unheld = p;
  holds.apply(unheld, predicted);
  EXPECT_EQ(unheld, p);
  holds.hold_forward(true);
  StateCovariance held = p;
  holds.apply(held, predicted);
  StateCovariance expected = p;
  hold_forward_acceleration(expected, predicted, Eigen::Vector3d::UnitX());
  EXPECT_LT((held - expected).norm(), 1e-15);
}

// A held bias 0.05 m/s^2 too large along the (diagonal) forward axis: each held 0.125 s scan the
// LiDAR gives back the 0.05 * 0.125 m/s the prediction lost. After a 2 s window, with gain 1, the
// whole error comes off the bias along the forward axis; not before, and a release restarts the window.
TEST(BiasHolds, TrimTakesTheHeldBiasErrorOffAfterTheWindow) {
  BiasHoldConfig config = small_config();
  config.forward_axis = Eigen::Vector3d(2.0, 2.0, 0.0);
  config.trim_window_s = 2.0;
  config.trim_gain = 1.0;
  const Eigen::Vector3d forward = config.forward_axis.normalized();
  const Eigen::Vector3d truth(0.02, -0.01, 0.03);
  const double correction = 0.05 * 0.125;

  BiasHolds holds(config);
  NavState state;
  state.accel_bias = truth + 0.05 * forward;
  for (int scan = 0; scan < 10; ++scan) holds.trim(true, correction, 0.125, state);
  holds.trim(false, correction, 0.125, state);  // released: the window starts anew
  for (int scan = 0; scan < 15; ++scan) holds.trim(true, correction, 0.125, state);
  EXPECT_EQ(state.accel_bias, truth + 0.05 * forward) << "15 held scans since the release: 1.875 s";
  holds.trim(true, correction, 0.125, state);
  EXPECT_LT((state.accel_bias - truth).norm(), 1e-12);
}

}  // namespace
}  // namespace liod
