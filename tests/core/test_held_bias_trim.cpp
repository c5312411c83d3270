#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "liod/held_bias_trim.hpp"

namespace {

constexpr double kScan_s = 0.1;

// The along-track speed of a held stretch, scan by scan: the IMU prediction drifts at the held
// bias's error, and the LiDAR takes back `lidar_share` of the speed error with `lidar_noise` of its
// own (m/s a scan). Returns the held bias after `seconds`, trimmed by `trim` when given.
struct HeldStretch {
  double true_bias = 0.0;
  double held_bias = 0.0;
  double speed_error = 0.0;
  double lidar_share = 0.5;
  double lidar_noise = 0.02;
  std::mt19937 rng{7};

  double run(double seconds, liod::HeldBiasTrim* trim) {
    std::normal_distribution<double> noise(0.0, lidar_noise);
    for (int i = 0; i < static_cast<int>(seconds / kScan_s); ++i) {
      // The prediction subtracts the held bias from the accelerometer, which carries the true one.
      speed_error += (true_bias - held_bias) * kScan_s;
      const double correction = -lidar_share * speed_error + noise(rng);
      speed_error += correction;
      if (trim == nullptr) continue;
      if (const auto change = trim->add_held_scan(correction, kScan_s)) held_bias += *change;
    }
    return held_bias;
  }
};

TEST(HeldBiasTrim, TakesAWronglyHeldBiasTowardsTheTruth) {
  // Noise-free highway seed 7: 0.17 m/s^2 learned at a gantry, true 0, held for the stretch after.
  HeldStretch untrimmed;
  untrimmed.held_bias = 0.17;
  EXPECT_DOUBLE_EQ(untrimmed.run(200.0, nullptr), 0.17);

  HeldStretch stretch;
  stretch.held_bias = 0.17;
  liod::HeldBiasTrim trim(20.0, 0.5);
  const double after_40s = stretch.run(40.0, &trim);
  EXPECT_LT(after_40s, 0.17 * 0.5) << "two windows, each halving the error";
  EXPECT_GT(after_40s, 0.0) << "no overshoot at a gain of 0.5";
  EXPECT_NEAR(stretch.run(160.0, &trim), 0.0, 0.01);
}

TEST(HeldBiasTrim, ARollingStartsSpeedFixIsNotABias) {
  // The first scans of a rolling start correct the speed found by the search (here 0.3 m/s a scan
  // for five scans), then the LiDAR's corrections are noise about a right bias: the median ignores
  // the fix, which the mean would have read as 0.075 m/s^2 (0.0375 after the gain).
  liod::HeldBiasTrim trim(20.0, 0.5);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::optional<double> change;
  for (int i = 0; i < 200 && !change; ++i) change = trim.add_held_scan(i < 5 ? 0.3 : noise(rng), kScan_s);
  ASSERT_TRUE(change.has_value()) << "200 scans of 0.1 s fill a 20 s window";
  EXPECT_LT(std::abs(*change), 0.01);
}

TEST(HeldBiasTrim, AReleaseStartsTheWindowAnew) {
  liod::HeldBiasTrim trim(0.95, 1.0);  // ten scans' time, summed, falls a rounding short of 1.0
  for (int i = 0; i < 9; ++i) EXPECT_FALSE(trim.add_held_scan(0.01, kScan_s).has_value());
  trim.reset();  // the hold released: the scans before do not count towards the next window
  for (int i = 0; i < 9; ++i) EXPECT_FALSE(trim.add_held_scan(0.02, kScan_s).has_value());
  const auto change = trim.add_held_scan(0.02, kScan_s);
  ASSERT_TRUE(change.has_value());
  EXPECT_NEAR(*change, -0.2, 1e-12) << "the prediction lost 0.2 m/s^2: the held bias is that much too large";
}

TEST(HeldBiasTrim, AZeroWindowNeverTrims) {
  liod::HeldBiasTrim off(0.0, 0.5);
  for (int i = 0; i < 1000; ++i) EXPECT_FALSE(off.add_held_scan(0.05, kScan_s).has_value());
  liod::HeldBiasTrim on(1.0, 0.5);
  for (int i = 0; i < 1000; ++i) EXPECT_FALSE(on.add_held_scan(0.05, 0.0).has_value()) << "a scan without duration adds nothing";
}

}  // namespace
