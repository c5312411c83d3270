// Time: the host/sensor offset tracker (minimum filter, clock jumps) and the PPS edge rule.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "liod/drivers/time_sync.hpp"

using namespace liod::drivers;

TEST(OffsetTracker, MinimumFilterIgnoresQueueingDelay) {
  constexpr std::int64_t kMs = 1000000;
  OffsetTracker t(2000 * kMs, 100 * kMs);
  std::mt19937 rng(7);
  std::exponential_distribution<double> delay(1.0 / 2.0);  // mean 2 ms of jitter on top of 0.1 ms
  const std::int64_t offset = 123456789012LL;
  for (int i = 0; i < 2000; ++i) {
    const std::int64_t sensor = 1000000000000LL + i * kMs;
    const auto d = static_cast<std::int64_t>((0.1 + delay(rng)) * kMs);
    t.add(sensor + offset + d, sensor);
  }
  EXPECT_NEAR(static_cast<double>(t.offset_ns() - offset), 0.1 * kMs, 0.05 * kMs);
  EXPECT_EQ(t.jumps(), 0U);
}

TEST(OffsetTracker, SurvivesClockJumpAndSingleOutlier) {
  constexpr std::int64_t kMs = 1000000;
  OffsetTracker t(1000 * kMs, 100 * kMs, 3);
  std::int64_t local = 0;
  for (int i = 0; i < 100; ++i, local += kMs) t.add(local, local - 5 * kMs);
  EXPECT_EQ(t.offset_ns(), 5 * kMs);
  t.add(local, local - 900 * kMs);  // one late packet: ignored
  local += kMs;
  EXPECT_EQ(t.offset_ns(), 5 * kMs);
  EXPECT_EQ(t.jumps(), 0U);
  for (int i = 0; i < 10; ++i, local += kMs) t.add(local, local + 3600000 * kMs);  // sensor clock stepped 1 h
  EXPECT_EQ(t.jumps(), 1U);
  EXPECT_EQ(t.offset_ns(), -3600000 * kMs);
}

TEST(Pps, EdgeCorrection) {
  EXPECT_EQ(pps_edge_correction(5000000000LL + 1200), -1200);
  EXPECT_EQ(pps_edge_correction(5000000000LL - 300000), 300000);
  EXPECT_EQ(pps_edge_correction(5500000000LL), std::numeric_limits<std::int64_t>::min());
}

TEST(Pps, MissingChipIsAnErrorNotACrash) {
  EXPECT_THROW(PpsDiscipline("gpiochip-does-not-exist", 0), std::runtime_error);
}

TEST(ClockJump, NoJumpWhenClockIsSteady) {
  ClockJumpDetector d(100000000);
  EXPECT_EQ(d.check(), 0);
  EXPECT_EQ(d.jumps(), 0U);
}
