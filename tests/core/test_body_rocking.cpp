#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "liod/body_rocking.hpp"

namespace {

constexpr double kRate = 200.0;
constexpr double kNoiseDensity = 5e-4;  // rad/s/sqrt(Hz), liod.yaml's

// `seconds` of gyro at 200 Hz: a bias, white noise of kNoiseDensity, a steady turn about z, and
// whatever `motion(t)` adds.
template <typename Motion>
std::deque<liod::ImuSample> gyro_samples(double seconds, unsigned seed, Motion motion) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kNoiseDensity * std::sqrt(kRate));
  std::deque<liod::ImuSample> samples;
  for (int i = 0; i < static_cast<int>(seconds * kRate); ++i) {
    liod::ImuSample s;
    s.time = 100.0 + i / kRate;
    s.gyro = Eigen::Vector3d(0.004, -0.007, 0.05) + motion(s.time) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    s.accel = Eigen::Vector3d(0.0, 0.0, 9.81);
    samples.push_back(s);
  }
  return samples;
}

liod::BodyRockingParams params() {
  liod::BodyRockingParams p;
  p.gyro_noise_density = kNoiseDensity;
  return p;
}

const Eigen::Vector3d kUp = Eigen::Vector3d::UnitZ();

TEST(BodyRocking, AtRestTheGyrosNoiseBiasTurnAndEngineAreStill) {
  // A 25 Hz engine shake of 0.3 deg/s about x: averaged over 50 ms windows, little stays.
  const auto samples = gyro_samples(2.0, 1, [](double t) {
    return Eigen::Vector3d(0.005 * std::sin(2.0 * M_PI * 25.0 * t), 0.0, 0.0);
  });
  for (unsigned seed = 2; seed < 12; ++seed) {
    const auto quiet = gyro_samples(1.5, seed, [](double) { return Eigen::Vector3d::Zero(); });
    EXPECT_EQ(liod::body_motion(quiet, quiet.back().time, kUp, params()), liod::BodyMotion::kStill) << seed;
  }
  EXPECT_EQ(liod::body_motion(samples, samples.back().time, kUp, params()), liod::BodyMotion::kStill);
  // About what the noise alone spreads over 50 ms means (root of 2 d^2 / 0.05 s: 3.2 mrad/s).
  EXPECT_LT(liod::rocking_rate(samples, samples.back().time, kUp, params()), 0.004);
}

TEST(BodyRocking, PitchAndRollModesOfARollingCarRock) {
  // liod-sim's drives rock at 6-34 mrad/s under way (half-second windows); the smallest of those,
  // 4 mrad/s rms about each axis at the body's pitch and roll frequencies, over a gyro 10x noisier
  // than the simulated one (0.0057 and 0.0032 rad/s in quadrature).
  const auto samples = gyro_samples(2.0, 3, [](double t) {
    return Eigen::Vector3d(0.004 * std::sqrt(2.0) * std::sin(2.0 * M_PI * 1.9 * t + 1.0),
                           0.004 * std::sqrt(2.0) * std::sin(2.0 * M_PI * 1.6 * t), 0.0);
  });
  EXPECT_NEAR(liod::rocking_rate(samples, samples.back().time, kUp, params()), 0.0065, 0.0015);
  EXPECT_EQ(liod::body_motion(samples, samples.back().time, kUp, params()), liod::BodyMotion::kRocking);
  // The same rate about the vertical (a swerve) is a turn, not rocking.
  const auto swerving = gyro_samples(2.0, 3, [](double t) {
    return Eigen::Vector3d(0.0, 0.0, 0.05 * std::sin(2.0 * M_PI * 1.6 * t));
  });
  EXPECT_EQ(liod::body_motion(swerving, swerving.back().time, kUp, params()), liod::BodyMotion::kStill);
}

TEST(BodyRocking, TooLittleOfTheImuIsUnknownAndOnlyTheWindowCounts) {
  const auto samples = gyro_samples(3.0, 4, [](double t) {
    return t < 101.5 ? Eigen::Vector3d(0.02 * std::sin(2.0 * M_PI * 1.6 * t), 0.0, 0.0) : Eigen::Vector3d::Zero();
  });
  EXPECT_EQ(liod::body_motion(samples, 100.3, kUp, params()), liod::BodyMotion::kUnknown);
  EXPECT_LT(liod::rocking_rate(samples, 100.3, kUp, params()), 0.0);
  EXPECT_EQ(liod::body_motion(samples, 101.4, kUp, params()), liod::BodyMotion::kRocking);
  // Stopped half a second before the window's start: still; after the samples end: unknown.
  EXPECT_EQ(liod::body_motion(samples, 102.9, kUp, params()), liod::BodyMotion::kStill);
  EXPECT_EQ(liod::body_motion(samples, 110.0, kUp, params()), liod::BodyMotion::kUnknown);
  // A NaN sample is left out, not spread over the window.
  auto with_nan = gyro_samples(1.5, 5, [](double) { return Eigen::Vector3d::Zero(); });
  with_nan[100].gyro.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(liod::body_motion(with_nan, with_nan.back().time, kUp, params()), liod::BodyMotion::kStill);
}

}  // namespace
