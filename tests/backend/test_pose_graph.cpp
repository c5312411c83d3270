// Pose graph: a square driven twice with a drifting odometry; loops back to the first lap must
// remove the drift, and the robust kernel must keep one wrong loop from bending the graph.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "liod/angles.hpp"
#include "liod/backend/pose_graph.hpp"

namespace {

using liod::PoseGraph;
using liod::kDegToRad;
using liod::PoseGraphFactor;

constexpr int kPerSide = 20;      // 2 m steps on a 40 m square
constexpr int kLap = 4 * kPerSide;

Eigen::Isometry3d square_pose(int i) {
  const int side = (i / kPerSide) % 4;
  const double s = 2.0 * (i % kPerSide);
  const double corners[4][2] = {{0, 0}, {40, 0}, {40, 40}, {0, 40}};
  const double yaw = side * 90.0 * kDegToRad;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(corners[side][0], corners[side][1], 0.0) + s * t.linear().col(0);
  return t;
}

struct Drive {
  std::vector<Eigen::Isometry3d> truth;
  std::vector<Eigen::Isometry3d> odometry;
};

// Two laps; the odometry's yaw drifts 0.05 deg per step (a gyro bias), with noise.
Drive drive() {
  Drive d;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::normal_distribution<double> yaw_noise(0.0, 0.05 * kDegToRad);
  for (int i = 0; i < 2 * kLap; ++i) d.truth.push_back(square_pose(i));
  d.odometry.push_back(d.truth[0]);
  for (int i = 1; i < 2 * kLap; ++i) {
    Eigen::Isometry3d step = d.truth[i - 1].inverse() * d.truth[i];
    step.linear() = Eigen::AngleAxisd(0.05 * kDegToRad + yaw_noise(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix() * step.linear();
    step.translation() += Eigen::Vector3d(noise(rng), noise(rng), 0.2 * noise(rng));
    d.odometry.push_back(d.odometry.back() * step);
  }
  return d;
}

PoseGraph chain(const Drive& d) {
  PoseGraph g;
  for (std::size_t i = 0; i < d.odometry.size(); ++i) {
    g.add_node(d.odometry[i]);
    g.set_tilt(i, d.truth[i].linear().transpose() * Eigen::Vector3d::UnitZ(), 0.5 * kDegToRad);
    if (i == 0) continue;
    PoseGraphFactor f;
    f.from = i - 1;
    f.to = i;
    f.measured = d.odometry[i - 1].inverse() * d.odometry[i];
    f.information = liod::relative_pose_information(0.05, 0.1 * kDegToRad);
    g.add_factor(f);
  }
  return g;
}

PoseGraphFactor loop(const Drive& d, std::size_t a, std::size_t b) {
  PoseGraphFactor f;
  f.from = a;
  f.to = b;
  f.measured = d.truth[a].inverse() * d.truth[b];
  f.information = liod::relative_pose_information(0.1, 0.5 * kDegToRad);
  f.loop = true;
  return f;
}

double rms_error(const PoseGraph& g, const Drive& d) {
  double sum = 0.0;
  for (std::size_t i = 0; i < d.truth.size(); ++i) sum += (g.pose(i).translation() - d.truth[i].translation()).squaredNorm();
  return std::sqrt(sum / static_cast<double>(d.truth.size()));
}

TEST(PoseGraph, LoopsOnASquareRemoveTheDrift) {
  const Drive d = drive();
  PoseGraph g = chain(d);
  const double before = rms_error(g, d);
  for (int i = kLap; i < 2 * kLap; i += 10) g.add_factor(loop(d, static_cast<std::size_t>(i - kLap), static_cast<std::size_t>(i)));
  const auto report = g.optimize(liod::RobustLoss::kCauchy, 3.0, 100);
  const double after = rms_error(g, d);
  EXPECT_GT(before, 1.5);  // 8 deg of heading drift over two laps
  EXPECT_LT(after, 0.3) << "before " << before;
  EXPECT_LT(after, before / 5.0);
  EXPECT_GT(report.iterations, 0);
  EXPECT_EQ(report.nodes, d.truth.size() - 1);  // all but the prior
  // The first pose is the fixed prior.
  EXPECT_TRUE(g.pose(0).isApprox(d.truth[0], 1e-12));
}

// A windowed solve (the backend's bound on a long drive): the first half of the second lap is
// solved with its loops, then the second half's loops arrive and only a window from the middle
// of the lap is freed. The nodes before it stay bit for bit; the window alone satisfies the new
// loops (the held nodes were already consistent with the first lap).
TEST(PoseGraph, WindowedSolveMovesOnlyTheWindow) {
  const Drive d = drive();
  PoseGraph g = chain(d);
  for (int i = kLap; i < kLap + kLap / 2; i += 10) {
    g.add_factor(loop(d, static_cast<std::size_t>(i - kLap), static_cast<std::size_t>(i)));
  }
  g.optimize(liod::RobustLoss::kCauchy, 3.0, 100);
  std::size_t new_loops = 0;
  for (int i = kLap + kLap / 2; i < 2 * kLap; i += 10, ++new_loops) {
    g.add_factor(loop(d, static_cast<std::size_t>(i - kLap), static_cast<std::size_t>(i)));
  }
  auto worst_loop = [&] {
    double worst = 0.0;
    for (const auto& f : g.factors()) worst = f.loop ? std::max(worst, g.whitened_error(f)) : worst;
    return worst;
  };
  const std::vector<Eigen::Isometry3d> before = g.poses();
  const double worst_before = worst_loop();
  const std::size_t first_free = kLap + kLap / 2 - 5;
  const auto report = g.optimize(liod::RobustLoss::kCauchy, 3.0, 100, first_free);
  EXPECT_EQ(report.nodes, 2 * kLap - first_free);
  // The odometry factors into and within the window, and the loops that reach it.
  EXPECT_EQ(report.factors, 2 * kLap - first_free + new_loops);
  for (std::size_t i = 0; i < first_free; ++i) {
    EXPECT_EQ(g.pose(i).matrix(), before[i].matrix()) << i;
  }
  EXPECT_GT((g.pose(2 * kLap - 1).translation() - before[2 * kLap - 1].translation()).norm(), 0.5);
  EXPECT_GT(worst_before, 10.0);
  EXPECT_LT(worst_loop(), 3.0) << "before " << worst_before;
}

TEST(PoseGraph, RobustLossDownweightsOneWrongLoop) {
  const Drive d = drive();
  std::vector<PoseGraphFactor> loops;
  for (int i = kLap; i < 2 * kLap; i += 20) loops.push_back(loop(d, static_cast<std::size_t>(i - kLap), static_cast<std::size_t>(i)));
  PoseGraph clean = chain(d);
  for (const auto& f : loops) clean.add_factor(f);
  clean.optimize(liod::RobustLoss::kNone, 0.0, 100);
  // A wrong loop: a look-alike place that registration matched 8 m off.
  PoseGraphFactor wrong = loop(d, 45, kLap + 25);
  wrong.measured.translation() += Eigen::Vector3d(8.0, 0.0, 0.0);
  loops.push_back(wrong);

  PoseGraph plain = chain(d);
  PoseGraph robust = chain(d);
  for (const auto& f : loops) {
    plain.add_factor(f);
    robust.add_factor(f);
  }
  plain.optimize(liod::RobustLoss::kNone, 0.0, 100);
  robust.optimize(liod::RobustLoss::kCauchy, 3.0, 100);
  const double clean_error = rms_error(clean, d);
  const double plain_error = rms_error(plain, d);
  const double robust_error = rms_error(robust, d);
  // Least squares bends the graph towards the wrong loop; Cauchy ends where the true loops alone lead.
  EXPECT_GT(plain_error, clean_error + 0.5);
  EXPECT_LT(robust_error, clean_error + 0.05) << "least squares: " << plain_error << ", true loops only: " << clean_error;
  // The wrong loop is left far outside the kernel; the true ones are satisfied.
  EXPECT_GT(robust.whitened_error(robust.factors().back()), 10.0);
  for (const auto& f : robust.factors()) {
    if (f.loop && &f != &robust.factors().back()) {
      EXPECT_LT(robust.whitened_error(f), 3.0);
    }
  }
}

TEST(PoseGraph, TiltFactorKeepsRollAndPitch) {
  const Drive d = drive();
  PoseGraph g = chain(d);
  for (int i = kLap; i < 2 * kLap; i += 10) g.add_factor(loop(d, static_cast<std::size_t>(i - kLap), static_cast<std::size_t>(i)));
  g.optimize(liod::RobustLoss::kCauchy, 3.0, 100);
  for (std::size_t i = 0; i < d.truth.size(); ++i) {
    const Eigen::Vector3d up = g.pose(i).linear().transpose() * Eigen::Vector3d::UnitZ();
    EXPECT_GT(up.z(), std::cos(0.5 * kDegToRad)) << i;
  }
}

}  // namespace
