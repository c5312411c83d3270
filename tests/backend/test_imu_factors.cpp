// The graph's IMU preintegration factors (LIO-SAM's graph; imu_factor.hpp): on an analytic
// motion measured by a biased IMU, the factors must recover the biases and velocities that the
// poses alone leave free, and the backend must join exactly the keyframes whose IMU stretch is
// whole.

#include <gtest/gtest.h>

#include <memory>

#include "analytic_motion.hpp"
#include "liod/angles.hpp"
#include "liod/backend/backend.hpp"
#include "liod/backend/pose_graph.hpp"
#include "liod/imu_trajectory.hpp"

namespace {

using liod::test::analytic_state;

const Eigen::Vector3d kGyroBias(0.002, -0.003, 0.01);
const Eigen::Vector3d kAccelBias(0.05, -0.03, 0.08);
constexpr double kKeyframeStep_s = 0.5;
constexpr int kNodes = 21;

Eigen::Isometry3d pose_of(const liod::NavState& s) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = s.rotation;
  t.translation() = s.position;
  return t;
}

liod::ImuGraphFactor imu_factor(const std::deque<liod::ImuSample>& samples, std::size_t from, const liod::ImuNoise& noise) {
  auto pre = std::make_shared<liod::ImuPreintegration>(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), noise);
  for (const auto& iv : liod::imu_intervals(samples, from * kKeyframeStep_s, (from + 1) * kKeyframeStep_s)) {
    pre->integrate(iv.gyro, iv.accel, iv.dt);
  }
  liod::ImuGraphFactor f;
  f.from = from;
  f.to = from + 1;
  f.gravity = liod::test::kAnalyticGravity;
  f.gyro_bias_walk_sigma = noise.gyro_bias_random_walk * std::sqrt(kKeyframeStep_s);
  f.accel_bias_walk_sigma = noise.accel_bias_random_walk * std::sqrt(kKeyframeStep_s);
  f.preintegration = std::move(pre);
  return f;
}

// The IMU at 1 kHz: the preintegration integrates each interval at its start's rotation, which at
// this motion's roll and pitch rates turns gravity's share of the specific force by a few mm/s^2
// at 200 Hz, and this test checks the factor's algebra, not the discretisation.
TEST(ImuFactors, RecoverBiasesAndVelocitiesAlongAnExactPoseChain) {
  const auto samples = liod::test::analytic_imu(kNodes * kKeyframeStep_s, 1000.0, kGyroBias, kAccelBias);
  liod::ImuNoise noise;
  noise.gyro_noise_density = 5e-4;
  noise.accel_noise_density = 5e-3;
  liod::PoseGraph graph;
  for (int i = 0; i < kNodes; ++i) {
    const liod::NavState truth = analytic_state(i * kKeyframeStep_s);
    graph.add_node(pose_of(truth));
    // What the graph starts from: velocities 0.3 m/s off, biases unknown (zero).
    graph.set_motion(i, {truth.velocity + Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
    if (i == 0) continue;
    liod::PoseGraphFactor odometry;
    odometry.from = i - 1;
    odometry.to = i;
    odometry.measured = pose_of(analytic_state((i - 1) * kKeyframeStep_s)).inverse() * pose_of(truth);
    odometry.information = liod::relative_pose_information(0.002, 0.02 * liod::kDegToRad);
    graph.add_factor(odometry);
    graph.add_imu_factor(imu_factor(samples, i - 1, noise));
  }
  const liod::SolveReport report = graph.optimize(liod::RobustLoss::kNone, 0.0, 50);
  EXPECT_EQ(report.imu_factors, static_cast<std::size_t>(kNodes - 1));
  for (int i : {0, kNodes / 2, kNodes - 1}) {
    const liod::NodeMotion& m = graph.motion(i);
    SCOPED_TRACE("node " + std::to_string(i));
    EXPECT_LT((m.gyro_bias - kGyroBias).norm(), 5e-4);
    EXPECT_LT((m.accel_bias - kAccelBias).norm(), 0.02);
    EXPECT_LT((m.velocity - analytic_state(i * kKeyframeStep_s).velocity).norm(), 0.02);
    EXPECT_LT((graph.pose(i).translation() - analytic_state(i * kKeyframeStep_s).position).norm(), 0.01);
  }
}

TEST(ImuFactors, TransformTurnsVelocitiesAndGravityWithThePoses) {
  const auto samples = liod::test::analytic_imu(2.0, 200.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  liod::PoseGraph graph;
  for (int i = 0; i < 2; ++i) {
    graph.add_node(pose_of(analytic_state(i * kKeyframeStep_s)));
    graph.set_motion(i, {analytic_state(i * kKeyframeStep_s).velocity, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  }
  graph.add_imu_factor(imu_factor(samples, 0, liod::ImuNoise{}));
  const Eigen::Matrix<double, 9, 1> before_move = graph.whitened_error(graph.imu_factors()[0]);
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()).toRotationMatrix();
  delta.translation() = Eigen::Vector3d(3.0, -2.0, 0.5);
  graph.transform(delta);
  EXPECT_LT((graph.motion(1).velocity - delta.linear() * analytic_state(kKeyframeStep_s).velocity).norm(), 1e-12);
  EXPECT_LT((graph.imu_factors()[0].gravity - delta.linear() * liod::test::kAnalyticGravity).norm(), 1e-12);
  // The factor's residuals are those of the states before the move.
  EXPECT_LT((graph.whitened_error(graph.imu_factors()[0]) - before_move).norm(), 1e-6 * (1.0 + before_move.norm()));
  // The moved states still satisfy the factor: a solve from them changes nothing.
  graph.add_node(graph.pose(1));  // a third node so that node 1 is free
  const Eigen::Isometry3d before = graph.pose(1);
  graph.optimize(liod::RobustLoss::kNone, 0.0, 20);
  EXPECT_LT((graph.pose(1).translation() - before.translation()).norm(), 1e-3);
}

liod::Keyframe keyframe(std::uint64_t id, const std::deque<liod::ImuSample>& samples, double imu_from) {
  liod::Keyframe k;
  k.id = id;
  k.state = analytic_state(id * kKeyframeStep_s);
  if (id > 0) k.imu_since_previous = liod::imu_intervals(samples, imu_from, k.state.time);
  return k;
}

TEST(ImuFactors, TheBackendJoinsKeyframesWhoseImuStretchIsWhole) {
  const auto samples = liod::test::analytic_imu(4.0, 200.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  for (const bool enabled : {true, false}) {
    liod::AlgorithmConfig config;
    config.backend.imu_factors = enabled;
    liod::Backend backend(config);
    backend.add_keyframe(keyframe(0, samples, 0.0));
    backend.add_keyframe(keyframe(1, samples, 0.0));
    backend.add_keyframe(keyframe(2, samples, 0.7));  // begins after keyframe 1 (a stretch the front end lost)
    backend.add_keyframe(keyframe(3, samples, 1.0));
    liod::Keyframe without = keyframe(4, samples, 1.5);
    without.imu_since_previous.clear();               // bridged: the front end sends none
    backend.add_keyframe(without);
    const auto& factors = backend.graph().imu_factors();
    if (!enabled) {
      EXPECT_TRUE(factors.empty());
      continue;
    }
    ASSERT_EQ(factors.size(), 2U);
    EXPECT_EQ(factors[0].from, 0U);
    EXPECT_EQ(factors[1].from, 2U);
    EXPECT_NEAR(factors[1].preintegration->duration(), kKeyframeStep_s, 1e-9);
    EXPECT_LT((backend.graph().motion(3).velocity - analytic_state(1.5).velocity).norm(), 1e-12);
  }
}

}  // namespace
