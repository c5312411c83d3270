// IMU-rate poses: the last scan update propagated sample by sample equals the odometry's own
// batch propagation over the same samples (imu_intervals + one preintegration), including after
// a late anchor that must catch up on the samples buffered since its time.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>

#include "liod/daemon/imu_rate_propagator.hpp"
#include "liod/imu_trajectory.hpp"

using namespace liod;

namespace {

ImuSample sample_at(double t) {
  ImuSample s;
  s.time = t;
  s.gyro = Eigen::Vector3d(0.1 * std::sin(3 * t), 0.05, 0.3 * std::cos(2 * t));
  s.accel = Eigen::Vector3d(1.0 + 0.5 * std::sin(t), 0.2 * std::cos(5 * t), 9.81);
  return s;
}

ScanAnchor anchor_at(double t) {
  ScanAnchor a;
  a.state.time = t;
  a.state.position = Eigen::Vector3d(1, 2, 3);
  a.state.velocity = Eigen::Vector3d(10, -1, 0.2);
  a.state.rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 0.3, 1).normalized()).toRotationMatrix();
  a.state.gyro_bias = Eigen::Vector3d(0.01, -0.02, 0.005);
  a.state.accel_bias = Eigen::Vector3d(0.05, 0.0, -0.1);
  a.gravity = Eigen::Vector3d(0, 0, -9.81);
  a.flags = 4;
  return a;
}

// What the odometry computes: every interval from the anchor to `to` in one preintegration.
NavState batch(const std::deque<ImuSample>& samples, const ScanAnchor& a, double to) {
  ImuPreintegration p(a.state.gyro_bias, a.state.accel_bias, ImuNoise{});
  for (const auto& iv : imu_intervals(samples, a.state.time, to)) p.integrate(iv.gyro, iv.accel, iv.dt);
  NavState s = p.predict(a.state, a.gravity);
  s.time = to;
  return s;
}

void expect_near(const NavState& a, const NavState& b) {
  EXPECT_NEAR(a.time, b.time, 1e-12);
  EXPECT_LT((a.position - b.position).norm(), 1e-9);
  EXPECT_LT((a.velocity - b.velocity).norm(), 1e-9);
  EXPECT_LT((a.rotation - b.rotation).norm(), 1e-9);
}

}  // namespace

TEST(ImuRatePropagator, NothingBeforeTheFirstAnchor) {
  ImuRatePropagator p;
  EXPECT_FALSE(p.add(sample_at(0.0)).has_value());
  EXPECT_FALSE(p.anchor().has_value());
}

TEST(ImuRatePropagator, StepByStepEqualsTheBatchPropagation) {
  ImuRatePropagator p;
  std::deque<ImuSample> all;
  const double rate = 200.0;
  for (int k = 0; k < 20; ++k) {
    all.push_back(sample_at(k / rate));
    p.add(all.back());
  }
  // The anchor falls between two samples, like a scan's end time.
  const ScanAnchor a = anchor_at(19.3 / rate);
  p.set_anchor(a);
  for (int k = 20; k < 60; ++k) {
    all.push_back(sample_at(k / rate));
    const auto s = p.add(all.back());
    ASSERT_TRUE(s.has_value());
    expect_near(*s, batch(all, a, all.back().time));
  }
}

TEST(ImuRatePropagator, LateAnchorCatchesUpOnBufferedSamples) {
  ImuRatePropagator p;
  std::deque<ImuSample> all;
  const double rate = 200.0;
  p.set_anchor(anchor_at(0.0));
  for (int k = 0; k < 40; ++k) {
    all.push_back(sample_at(k / rate));
    p.add(all.back());
  }
  // A scan update for time 0.1 arrives when samples up to 0.195 are already in: the next
  // sample continues from the new anchor as if it had been there all along.
  const ScanAnchor late = anchor_at(0.1 + 0.3 / rate);
  p.set_anchor(late);
  all.push_back(sample_at(40 / rate));
  const auto s = p.add(all.back());
  ASSERT_TRUE(s.has_value());
  expect_near(*s, batch(all, late, all.back().time));
  EXPECT_EQ(p.anchor()->flags, 4U);
}

TEST(ImuRatePropagator, OutOfOrderSamplesAreIgnored) {
  ImuRatePropagator p;
  p.set_anchor(anchor_at(0.0));
  ASSERT_TRUE(p.add(sample_at(0.01)).has_value());
  EXPECT_FALSE(p.add(sample_at(0.01)).has_value());
  EXPECT_FALSE(p.add(sample_at(0.005)).has_value());
  EXPECT_TRUE(p.add(sample_at(0.015)).has_value());
}

TEST(AnchorExchange, HandsOverOnlyNewAnchors) {
  AnchorExchange x;
  ScanAnchor out;
  EXPECT_FALSE(x.take(out));
  x.publish(anchor_at(1.0));
  x.publish(anchor_at(2.0));
  ASSERT_TRUE(x.take(out));
  EXPECT_EQ(out.state.time, 2.0);  // the latest wins
  EXPECT_FALSE(x.take(out));
}
