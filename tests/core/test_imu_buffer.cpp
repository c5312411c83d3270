#include "liod/imu_buffer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "liod/imu_preintegration.hpp"
#include "liod/so3.hpp"

namespace liod {
namespace {

// Times on a binary grid (multiples of 1/128 s), so that comparisons with them are exact.
constexpr double kStep = 1.0 / 128.0;

// An automotive MEMS unit's measurement ranges: 2000 deg/s, 16 g.
constexpr double kGyroRange = 34.9;
constexpr double kAccelRange = 157.0;

ImuSample sample_at(double time) {
  ImuSample s;
  s.time = time;
  s.accel = Eigen::Vector3d(0.0, 0.0, 9.80665);
  return s;
}

TEST(ImuBuffer, DropsAndCountsNonFiniteAndOutOfOrderSamples) {
  ImuBuffer buffer(10.0, kGyroRange, kAccelRange);
  EXPECT_TRUE(buffer.empty());
  EXPECT_EQ(buffer.latest_time(), -std::numeric_limits<double>::infinity());

  buffer.add(sample_at(1.0));
  ImuSample nan_time = sample_at(std::nan(""));
  ImuSample nan_gyro = sample_at(2.0);
  nan_gyro.gyro.y() = std::nan("");
  ImuSample inf_accel = sample_at(2.0);
  inf_accel.accel.z() = std::numeric_limits<double>::infinity();
  buffer.add(nan_time);
  buffer.add(nan_gyro);
  buffer.add(inf_accel);
  buffer.add(sample_at(1.0));  // same time as the newest: not after it
  buffer.add(sample_at(0.5));  // before it
  buffer.add(sample_at(1.5));

  EXPECT_EQ(buffer.dropped(), 5U);
  ASSERT_EQ(buffer.size(), 2U);
  EXPECT_EQ(buffer.samples()[0].time, 1.0);
  EXPECT_EQ(buffer.samples()[1].time, 1.5);
  EXPECT_EQ(buffer.latest_time(), 1.5);
}

// A value beyond the measurement range on any axis is no measurement (a corrupted but finite
// float passes an 8-bit checksum); one at the range is a clipped measurement and is kept.
TEST(ImuBuffer, DropsSamplesBeyondTheMeasurementRange) {
  ImuBuffer buffer(10.0, kGyroRange, kAccelRange);
  ImuSample fast_turn = sample_at(1.0);
  fast_turn.gyro.x() = -1.01 * kGyroRange;
  ImuSample hard_knock = sample_at(1.1);
  hard_knock.accel.y() = 1.0e6;
  ImuSample clipped = sample_at(1.2);
  clipped.gyro.z() = kGyroRange;
  clipped.accel.x() = -kAccelRange;
  buffer.add(fast_turn);
  buffer.add(hard_knock);
  buffer.add(clipped);
  EXPECT_EQ(buffer.dropped(), 2U);
  ASSERT_EQ(buffer.size(), 1U);
  EXPECT_EQ(buffer.samples()[0].time, 1.2);
}

TEST(ImuBuffer, WithoutSamplesTheWholeSpanIsAGap) {
  const ImuBuffer buffer(10.0, kGyroRange, kAccelRange);
  const auto gaps = buffer.gaps(1.0, 1.5, 0.05);
  ASSERT_EQ(gaps.size(), 1U);
  EXPECT_EQ(gaps[0].from, 1.0);
  EXPECT_EQ(gaps[0].to, 1.5);
  EXPECT_TRUE(buffer.gaps(1.5, 1.5, 0.05).empty());
}

// With no scan to trim it, the buffer keeps history_s back from the newest sample and no more.
TEST(ImuBuffer, KeepsHistorySecondsBackFromTheNewestSample) {
  ImuBuffer buffer(1.0, kGyroRange, kAccelRange);
  for (int k = 0; k <= 5 * 128; ++k) buffer.add(sample_at(k * kStep));
  EXPECT_EQ(buffer.latest_time(), 5.0);
  EXPECT_EQ(buffer.samples().front().time, 4.0);  // the oldest within 1 s of 5.0
  EXPECT_EQ(buffer.size(), 129U);
  EXPECT_EQ(buffer.dropped(), 0U);

  // However short the history, two samples stay to interpolate between.
  ImuBuffer short_buffer(0.0, kGyroRange, kAccelRange);
  for (int k = 0; k < 10; ++k) short_buffer.add(sample_at(k * kStep));
  EXPECT_EQ(short_buffer.size(), 2U);
  EXPECT_EQ(short_buffer.samples().back().time, 9 * kStep);
}

TEST(ImuBuffer, ForgetBeforeKeepsOneSampleBeforeTheTime) {
  ImuBuffer buffer(100.0, kGyroRange, kAccelRange);
  for (int k = 0; k < 64; ++k) buffer.add(sample_at(k * kStep));
  buffer.forget_before(10.5 * kStep);
  EXPECT_EQ(buffer.samples().front().time, 10 * kStep);  // the last one before: interpolation needs it
  EXPECT_EQ(buffer.samples()[1].time, 11 * kStep);
  EXPECT_EQ(buffer.size(), 54U);
  // A time past every sample leaves the last two.
  buffer.forget_before(1000.0);
  ASSERT_EQ(buffer.size(), 2U);
  EXPECT_EQ(buffer.samples().back().time, 63 * kStep);
}

// Samples every 1/128 s over [1, 2] s with none in (1.25, 1.5).
ImuBuffer buffer_with_hole() {
  ImuBuffer buffer(100.0, kGyroRange, kAccelRange);
  for (int k = 128; k <= 256; ++k) {
    const double t = k * kStep;
    if (t > 1.25 && t < 1.5) continue;
    buffer.add(sample_at(t));
  }
  return buffer;
}

TEST(ImuBuffer, GapsFindsLeadingInnerAndTrailingSilences) {
  const ImuBuffer buffer = buffer_with_hole();
  const auto gaps = buffer.gaps(0.75, 2.25, 0.05);
  ASSERT_EQ(gaps.size(), 3U);
  EXPECT_EQ(gaps[0].from, 0.75);  // before the first sample
  EXPECT_EQ(gaps[0].to, 1.0);
  EXPECT_EQ(gaps[1].from, 1.25);  // between the samples around the hole
  EXPECT_EQ(gaps[1].to, 1.5);
  EXPECT_EQ(gaps[2].from, 2.0);  // after the last sample
  EXPECT_EQ(gaps[2].to, 2.25);

  // Silences no longer than max_gap are no gaps: the samples' own spacing, and 0.25 s with max_gap 0.3.
  EXPECT_TRUE(buffer.gaps(1.0, 1.25, 0.05).empty());
  EXPECT_TRUE(buffer.gaps(0.8, 2.2, 0.3).empty());
}

TEST(ImuBuffer, GapsAreClippedToTheAskedSpan) {
  const ImuBuffer buffer = buffer_with_hole();
  const auto inside = buffer.gaps(1.3, 1.4, 0.05);
  ASSERT_EQ(inside.size(), 1U);
  EXPECT_EQ(inside[0].from, 1.3);
  EXPECT_EQ(inside[0].to, 1.4);

  const auto overlapping = buffer.gaps(1.125, 1.375, 0.05);
  ASSERT_EQ(overlapping.size(), 1U);
  EXPECT_EQ(overlapping[0].from, 1.25);
  EXPECT_EQ(overlapping[0].to, 1.375);

  // A hole entirely outside the span is not reported.
  EXPECT_TRUE(buffer.gaps(1.625, 1.875, 0.05).empty());
}

// A body on a constant twist: a steady turn about the world's vertical at yaw_rate, its velocity
// constant in the body frame, the body tilted (a road's crossfall). In a bridged gap the intervals
// carry what its IMU (with the start's biases) measures, so integrating them ends where the
// kinematics of that circular motion says, whatever the intervals held before.
TEST(BridgeImuGaps, IntervalsInAGapCarryTheTwistsMeasurements) {
  const Eigen::Vector3d gravity(0.0, 0.0, -9.80665);
  const double yaw_rate = 0.4;  // rad/s: a sharp turn, 0.6 m off a straight line after 0.5 s
  const Eigen::Vector3d v_body(12.0, 0.3, -0.1);
  NavState start;
  start.rotation = so3::exp(Eigen::Vector3d(0, 0, 0.35)) * so3::exp(Eigen::Vector3d(0.07, -0.03, 0));
  start.position = Eigen::Vector3d(5.0, -2.0, 1.0);
  start.velocity = start.rotation * v_body;
  start.gyro_bias = Eigen::Vector3d(0.01, -0.02, 0.005);
  start.accel_bias = Eigen::Vector3d(0.05, -0.03, 0.1);
  start.gravity = gravity;
  const Eigen::Vector3d rate_body = start.rotation.transpose() * Eigen::Vector3d(0, 0, yaw_rate);

  // Intervals of 1 ms over [0, 0.5] s holding nonsense (a dead sensor's zeros).
  const double duration = 0.5;
  const double dt = 0.001;
  std::vector<ImuInterval> intervals;
  for (int k = 0; k < 500; ++k) intervals.push_back({k * dt, dt, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  bridge_imu_gaps(intervals, {{0.0, duration}}, start, rate_body, gravity);

  ImuPreintegration preintegration(start.gyro_bias, start.accel_bias, ImuNoise{});
  for (const auto& iv : intervals) preintegration.integrate(iv.gyro, iv.accel, iv.dt);
  const NavState end = preintegration.predict(start, gravity);

  // Closed form: R(t) = Rz(w t) R0, v(t) = Rz(w t) v0, p(T) = p0 + int_0^T Rz(w s) ds v0.
  const double a = yaw_rate * duration;
  const Eigen::Matrix3d turn = so3::exp(Eigen::Vector3d(0, 0, a));
  const Eigen::Vector3d v0 = start.velocity;
  const Eigen::Vector3d travelled((std::sin(a) * v0.x() + (std::cos(a) - 1.0) * v0.y()) / yaw_rate,
                                  ((1.0 - std::cos(a)) * v0.x() + std::sin(a) * v0.y()) / yaw_rate,
                                  v0.z() * duration);
  EXPECT_LT(so3::log(end.rotation.transpose() * turn * start.rotation).norm(), 1e-6);
  EXPECT_LT((end.velocity - turn * v0).norm(), 0.005) << end.velocity.transpose() << " vs " << (turn * v0).transpose();
  EXPECT_LT((end.position - (start.position + travelled)).norm(), 0.005)
      << end.position.transpose() << " vs " << (start.position + travelled).transpose();
}

TEST(BridgeImuGaps, OnlyIntervalsWhoseMiddleLiesInAGapChange) {
  NavState start;
  start.velocity = Eigen::Vector3d(10.0, 0.0, 0.0);
  const Eigen::Vector3d rate(0.0, 0.0, 0.2);
  const Eigen::Vector3d marker(7.0, 7.0, 7.0);
  std::vector<ImuInterval> intervals;
  for (int k = 0; k < 8; ++k) intervals.push_back({k * 0.125, 0.125, marker, marker});
  // Gaps [0.3, 0.55] and [0.8, 0.95]: middles 0.3125, 0.4375 and 0.8125, 0.9375 fall in them.
  bridge_imu_gaps(intervals, {{0.3, 0.55}, {0.8, 0.95}}, start, rate, start.gravity);
  // At 10 m/s turning at 0.2 rad/s, level: 2 m/s^2 to the left, 9.80665 up.
  const Eigen::Vector3d bridged_accel(0.0, 2.0, 9.80665);
  for (int k = 0; k < 8; ++k) {
    const bool in_gap = k == 2 || k == 3 || k == 6 || k == 7;
    const auto& iv = intervals[static_cast<std::size_t>(k)];
    EXPECT_EQ(iv.gyro, in_gap ? rate : marker) << "interval " << k;
    EXPECT_LT((iv.accel - (in_gap ? bridged_accel : marker)).norm(), 1e-12) << "interval " << k;
  }
}

// An unknown acceleration a (per axis) held over a gap of T moves the position by a T^2 / 2 and
// the velocity by a T: the widening adds a rank-one position/velocity block per axis in those
// proportions, and a rotation variance growing with T^2; nothing else.
TEST(WidenForImuGaps, GrowsThePoseAndVelocityBlocksOnly) {
  StateCovariance p = StateCovariance::Identity() * 0.01;
  p(3, 12) = p(12, 3) = 0.001;
  p(0, 15) = p(15, 0) = 0.002;
  const StateCovariance before = p;
  const double gap = 0.3;
  widen_for_imu_gaps(p, {{1.0, 1.1}, {2.0, 2.2}});  // 0.3 s in all
  const StateCovariance added = p - before;

  StateCovariance outside = added;
  outside.block<3, 3>(0, 0).setZero();
  outside.block<6, 6>(3, 3).setZero();
  EXPECT_EQ(outside.norm(), 0.0) << "only the rotation, position and velocity blocks grow";

  const double vv = added(6, 6);
  ASSERT_GT(vv, 0.0);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(added(6 + axis, 6 + axis), vv, 1e-15);
    EXPECT_NEAR(added(3 + axis, 6 + axis), vv * gap / 2.0, 1e-12) << "cov(a T^2/2, a T) = var(a) T^3 / 2";
    EXPECT_NEAR(added(6 + axis, 3 + axis), vv * gap / 2.0, 1e-12);
    EXPECT_NEAR(added(3 + axis, 3 + axis), vv * gap * gap / 4.0, 1e-12) << "var(a T^2/2) = var(a) T^4 / 4";
    EXPECT_GT(added(axis, axis), 0.0);
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      EXPECT_EQ(added(3 + i, 3 + j), 0.0) << "no coupling across axes";
      EXPECT_EQ(added(3 + i, 6 + j), 0.0) << "no coupling across axes";
      EXPECT_EQ(added(6 + i, 6 + j), 0.0) << "no coupling across axes";
      EXPECT_EQ(added(i, j), 0.0) << "no coupling across axes";
    }
    for (int j = 3; j < 9; ++j) EXPECT_EQ(added(i, j), 0.0) << "rotation uncorrelated with translation";
  }

  // Twice the gap: four times the rotation variance (a rate error times T), four times the velocity's.
  StateCovariance twice = before;
  widen_for_imu_gaps(twice, {{0.0, 2.0 * gap}});
  EXPECT_NEAR((twice - before)(0, 0), 4.0 * added(0, 0), 1e-12);
  EXPECT_NEAR((twice - before)(6, 6), 4.0 * vv, 1e-12);
  EXPECT_NEAR((twice - before)(3, 3), 16.0 * added(3, 3), 1e-12);

  StateCovariance none = before;
  widen_for_imu_gaps(none, {});
  EXPECT_EQ(none, before);
}

}  // namespace
}  // namespace liod
