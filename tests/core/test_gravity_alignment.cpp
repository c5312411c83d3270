// Start-up alignment: tilt from the accelerometer, gyro bias from the mean rate at rest.
#include <gtest/gtest.h>

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
