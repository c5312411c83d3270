#include <gtest/gtest.h>

#include <deque>

#include "liod/imu_preintegration.hpp"
#include "liod/imu_trajectory.hpp"
#include "liod/so3.hpp"
#include "analytic_motion.hpp"

namespace {

const Eigen::Vector3d& kGravity = liod::test::kAnalyticGravity;

std::deque<liod::ImuSample> simulate(double duration, double rate, const Eigen::Vector3d& bg, const Eigen::Vector3d& ba) {
  return liod::test::analytic_imu(duration, rate, bg, ba);
}

liod::NavState truth(double t) { return liod::test::analytic_state(t); }

TEST(ImuPreintegration, PredictsAnAnalyticTrajectory) {
  const auto samples = simulate(2.0, 200.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  liod::ImuPreintegration pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), liod::ImuNoise{});
  for (const auto& iv : liod::imu_intervals(samples, 0.0, 1.0)) pre.integrate(iv.gyro, iv.accel, iv.dt);
  EXPECT_NEAR(pre.duration(), 1.0, 1e-12);
  const liod::NavState predicted = pre.predict(truth(0.0), kGravity);
  const liod::NavState expected = truth(1.0);
  EXPECT_LT((predicted.position - expected.position).norm(), 5e-3);
  EXPECT_LT((predicted.velocity - expected.velocity).norm(), 5e-3);
  EXPECT_LT(liod::so3::log(predicted.rotation.transpose() * expected.rotation).norm(), 1e-6);
}

TEST(ImuPreintegration, PoseTableAgreesWithPrediction) {
  const auto samples = simulate(1.0, 200.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  const auto intervals = liod::imu_intervals(samples, 0.0123, 0.5077);  // ends between samples
  liod::ImuPreintegration pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), liod::ImuNoise{});
  for (const auto& iv : intervals) pre.integrate(iv.gyro, iv.accel, iv.dt);
  const liod::NavState start = truth(0.0123);
  const auto predicted = pre.predict(start, kGravity);
  const auto table = liod::integrate_imu_poses(start, intervals, kGravity);
  const liod::Pose end = table.at(0.5077);
  EXPECT_LT((end.translation - predicted.position).norm(), 1e-9);
  EXPECT_LT((end.translation - truth(0.5077).position).norm(), 3e-3);
  // Half way, the table interpolates the true motion.
  EXPECT_LT((table.at(0.25).translation - truth(0.25).position).norm(), 3e-3);
}

TEST(ImuPreintegration, BiasCorrectionMatchesRepropagationToFirstOrder) {
  const Eigen::Vector3d bg(0.01, -0.02, 0.015);
  const Eigen::Vector3d ba(0.1, 0.05, -0.08);
  const auto samples = simulate(1.0, 200.0, bg, ba);
  liod::ImuPreintegration pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), liod::ImuNoise{});
  for (const auto& iv : liod::imu_intervals(samples, 0.0, 1.0)) pre.integrate(iv.gyro, iv.accel, iv.dt);
  // First-order correction to the true bias, Forster eq. (44)...
  const Eigen::Matrix3d dr = pre.delta_rotation(bg);
  const Eigen::Vector3d dv = pre.delta_velocity(bg, ba);
  const Eigen::Vector3d dp = pre.delta_position(bg, ba);
  const Eigen::Vector3d uncorrected_dp = pre.delta_position(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  // ...against re-integration with that bias.
  pre.repropagate(bg, ba);
  EXPECT_LT(liod::so3::log(dr.transpose() * pre.delta_rotation(bg)).norm(), 1e-4);
  EXPECT_LT((dv - pre.delta_velocity(bg, ba)).norm(), 2e-3);
  EXPECT_LT((dp - pre.delta_position(bg, ba)).norm(), 1e-3);
  // The correction itself is much larger than its error: the Jacobians carry real information.
  EXPECT_GT((uncorrected_dp - pre.delta_position(bg, ba)).norm(), 0.04);
}

TEST(ImuPreintegration, CovarianceGrowsWithTimeAndIsSymmetric) {
  const auto samples = simulate(2.0, 200.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  liod::ImuPreintegration pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), liod::ImuNoise{});
  double last_trace = 0.0;
  for (const auto& iv : liod::imu_intervals(samples, 0.0, 2.0)) {
    pre.integrate(iv.gyro, iv.accel, iv.dt);
    EXPECT_GT(pre.covariance().trace(), last_trace);
    last_trace = pre.covariance().trace();
  }
  EXPECT_LT((pre.covariance() - pre.covariance().transpose()).norm(), 1e-12);
  // Random-walk growth of the attitude: sigma^2 * T.
  const double expected_attitude_var = 2.0e-3 * 2.0e-3 * 2.0;
  EXPECT_NEAR(pre.covariance()(0, 0), expected_attitude_var, 0.05 * expected_attitude_var);
}

}  // namespace
