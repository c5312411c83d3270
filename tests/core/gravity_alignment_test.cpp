// Start-up alignment: tilt from the accelerometer, gyro bias from the mean rate at rest.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <cmath>
#include <deque>

#include "liod/gravity_alignment.hpp"

namespace {

constexpr double kGravity = 9.80665;

// 200 Hz at rest, tilted by `pitch` about y, with a gyro bias; the body rocks in roll at 1.9 Hz
// with `rock` rad/s of rate amplitude (as someone climbing in makes it).
std::deque<liod::ImuSample> at_rest(double seconds, double pitch, const Eigen::Vector3d& bias, double rock) {
  std::deque<liod::ImuSample> out;
  const double w = 2.0 * M_PI * 1.9;
  for (int i = 0; i <= static_cast<int>(seconds * 200.0); ++i) {
    liod::ImuSample s;
    s.time = i / 200.0;
    s.gyro = bias + Eigen::Vector3d(rock * std::cos(w * s.time), 0.0, 0.0);
    s.accel = Eigen::Vector3d(-kGravity * std::sin(pitch), 0.0, kGravity * std::cos(pitch));
    out.push_back(s);
  }
  return out;
}

}  // namespace

TEST(GravityAlignment, LevelsTheTiltAndTakesTheMeanRateForTheBiasAtRest) {
  const Eigen::Vector3d bias(0.004, -0.003, 0.005);
  const auto samples = at_rest(1.0, 0.05, bias, 0.0);
  const auto a = liod::align_gravity(samples, 0.0, 1.0);
  ASSERT_TRUE(a.has_value());
  EXPECT_TRUE(a->steady);
  EXPECT_LT((a->gyro_bias - bias).norm(), 1e-12);
  // The body's up, taken into the world, is the world's up.
  const Eigen::Vector3d up_body(-std::sin(0.05), 0.0, std::cos(0.05));
  EXPECT_NEAR((a->rotation * up_body - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);
  EXPECT_FALSE(liod::align_gravity(samples, 0.0, 0.02).has_value());  // 5 samples: too few
}

TEST(GravityAlignment, ARockingBodysMeanRateIsItsBiasOnlyOverSeveralSwings) {
  const Eigen::Vector3d bias(0.004, -0.003, 0.005);
  const auto samples = at_rest(2.5, 0.0, bias, 0.02);
  // The IMU has just come up: the alignment has only the first scan's 0.1 s, a swing's peak, and
  // reads most of the swing as bias; the whole 2.5 s rest leaves a fraction of it.
  const auto peak = liod::mean_angular_rate(samples, 0.0, 0.1);
  const auto rest = liod::mean_angular_rate(samples, 0.0, 2.5);
  ASSERT_TRUE(peak && rest);
  EXPECT_GT((*peak - bias).norm(), 0.01);
  EXPECT_LT((*rest - bias).norm(), 0.002);
  EXPECT_FALSE(liod::mean_angular_rate(samples, 3.0, 4.0).has_value());
}

// The alignment's correlation, through the filter's own state perturbation (boxplus): a bias with
// the tilt the alignment would have taken for it leaves the horizontal specific force it predicts
// unchanged, so that sum's spread is the vehicle's acceleration alone.
TEST(GravityAlignment, TheBiasAndTheTiltItWouldHaveCausedCancelInThePredictedAcceleration) {
  liod::NavState aligned;
  aligned.rotation = (Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.02, Eigen::Vector3d::UnitX()))
                         .toRotationMatrix();
  aligned.gravity = Eigen::Vector3d(0.0, 0.0, -kGravity);
  const double bias_std = 0.2;
  const double accel_std = 0.15;
  liod::StateCovariance p = liod::StateCovariance::Identity() * 1e-4;
  liod::correlate_bias_and_tilt(aligned, bias_std, accel_std, p);
  // The body at rest as aligned: R f + g = 0.
  const Eigen::Vector3d f = -aligned.rotation.transpose() * aligned.gravity;
  // Horizontal acceleration the filter predicts with the state perturbed by delta.
  auto horizontal_acceleration = [&](const liod::StateVector& delta) {
    const liod::NavState x = liod::boxplus(aligned, delta);
    const Eigen::Vector3d a = x.rotation * (f - x.accel_bias) + x.gravity;
    return Eigen::Vector2d(a.x(), a.y());
  };
  // Linear map from (bias, tilt) to that acceleration, by central differences.
  Eigen::Matrix<double, 2, liod::kStateDim> jacobian = Eigen::Matrix<double, 2, liod::kStateDim>::Zero();
  for (int i = 12; i < liod::kStateDim; ++i) {
    liod::StateVector step = liod::StateVector::Zero();
    step(i) = 1e-6;
    jacobian.col(i) = (horizontal_acceleration(step) - horizontal_acceleration(-step)) / 2e-6;
  }
  const Eigen::Matrix2d spread = jacobian * p * jacobian.transpose();
  EXPECT_NEAR(spread(0, 0), accel_std * accel_std, 1e-6);
  EXPECT_NEAR(spread(1, 1), accel_std * accel_std, 1e-6);
  EXPECT_NEAR(spread(0, 1), 0.0, 1e-6);
  // Independent priors of the same sizes would have left the sum as loose as bias and tilt together.
  liod::StateCovariance independent = p;
  independent.block<3, 2>(12, liod::kGravityIndex).setZero();
  independent.block<2, 3>(liod::kGravityIndex, 12).setZero();
  EXPECT_GT((jacobian * independent * jacobian.transpose())(0, 0), 2.0 * accel_std * accel_std);
  // The bias keeps its prior, and the whole is a covariance.
  EXPECT_NEAR(p(12, 12), bias_std * bias_std, 1e-12);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<liod::StateCovariance>(p).eigenvalues().minCoeff(), 0.0);
}
