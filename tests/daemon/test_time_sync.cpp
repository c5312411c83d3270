// Time: the host/sensor offset tracker (minimum filter, clock jumps), the clock-step bridge and
// the PPS edge rule.
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

// Found by fuzz_time_sync: the readings come from outside (a capture file's times, a header),
// and host minus sensor, or edge plus half a second, overflowed int64.
TEST(OffsetTracker, ReadingsFromAnywhereInTheRangeKeepTheirSign) {
  OffsetTracker t(2'000'000'000, 100'000'000);
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();
  // A capture time near the start of the range against a header of the year 2096: the host is
  // behind by more than int64 holds; the offset reads as far behind as it can, not far ahead.
  EXPECT_EQ(t.add(kMin + 1000, 4'000'000'000'000'000'000LL), kMin);
  EXPECT_LT(t.offset_ns(), 0);
}

TEST(Pps, EdgeCorrectionAtTheEndOfTheRange) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();  // ...036 854 775 807 ns
  EXPECT_EQ(pps_edge_correction(kMax), 1'000'000'000 - 854'775'807);
  EXPECT_EQ(pps_edge_correction(-5'000'000'000LL - 1200), 1200);
}

TEST(Pps, MissingChipIsAnErrorNotACrash) {
  EXPECT_THROW(PpsDiscipline("gpiochip-does-not-exist", 0), std::runtime_error);
}

TEST(ClockJump, NoJumpWhenClockIsSteady) {
  ClockJumpDetector d(100000000);
  EXPECT_EQ(d.check(), 0);
  EXPECT_EQ(d.jumps(), 0U);
}

namespace {
constexpr std::int64_t kMs = 1000000;
constexpr std::int64_t kDataStart = 1700000000LL * 1000 * kMs;  // a Unix-epoch data clock
}  // namespace

TEST(ClockStepBridge, ForwardAndBackwardStepsAreTakenOut) {
  ClockStepBridge b(100 * kMs);
  std::int64_t data = kDataStart;
  std::int64_t arrival = 5000 * kMs;
  std::int64_t expected = data;
  for (int i = 0; i < 3000; ++i) {
    if (i == 1000) data += 3600 * 1000 * kMs;  // the sensor re-synchronised an hour ahead
    if (i == 2000) data -= 2500 * kMs;         // the host clock stepped back 2.5 s
    ASSERT_EQ(b.correct(data, arrival), expected) << "sample " << i;
    data += 5 * kMs;
    arrival += 5 * kMs + (i % 7) * 100000;  // delivery jitter up to 0.6 ms
    expected += 5 * kMs;
  }
  EXPECT_EQ(b.steps(), 2U);
  EXPECT_EQ(b.last_step_ns(), -2500 * kMs);
  EXPECT_EQ(b.correction_ns(), -3600 * 1000 * kMs + 2500 * kMs);
}

TEST(ClockStepBridge, LateDeliveryAndLostSamplesAreNotSteps) {
  ClockStepBridge b(100 * kMs);
  std::int64_t data = kDataStart;
  std::int64_t arrival = 0;
  for (int i = 0; i < 1000; ++i) {
    if (i == 300) arrival += 400 * kMs;  // the reader stalled: 80 samples arrive in a burst
    if (i > 300 && i < 380) arrival -= 5 * kMs;
    if (i == 600) {                      // 0.5 s of samples lost: both clocks advance
      data += 500 * kMs;
      arrival += 500 * kMs;
    }
    ASSERT_EQ(b.correct(data, arrival), data) << "sample " << i;
    data += 5 * kMs;
    arrival += 5 * kMs;
  }
  EXPECT_EQ(b.steps(), 0U);
}
