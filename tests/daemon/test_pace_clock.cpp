// The replay's pace clock: recorded relative timing, and no sleeping for years on a capture time
// that is far off (a corrupt pcap record, a recording spanning a long pause).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <limits>

#include "liod/daemon/sources.hpp"

using namespace liod;

namespace {

struct Timed {
  bool released;
  double seconds;
};

Timed timed_wait(const PaceClock& clock, std::int64_t data_ns) {
  std::atomic<bool> stop{false};
  const auto t0 = std::chrono::steady_clock::now();
  const bool released = clock.wait_until(data_ns, stop, [] {});
  return {released, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
}

void start(PaceClock& clock, double pace) {
  clock.pace = pace;
  clock.data_start_ns = 1'700'000'000'000'000'000;
  clock.host_start_steady_ns = steady_ns();
  clock.max_offset_ns = 2'000'000'000;
}

}  // namespace

TEST(PaceClock, KeepsRecordedSpacingAtTwicePace) {
  PaceClock clock;
  start(clock, 2.0);
  const auto t = timed_wait(clock, clock.data_start_ns + 200'000'000);  // 0.2 s of data = 0.1 s at 2x
  EXPECT_TRUE(t.released);
  EXPECT_GE(t.seconds, 0.095);
  EXPECT_LT(t.seconds, 0.5);
  EXPECT_EQ(clock.reanchors(), 0U);
}

TEST(PaceClock, FarFutureCaptureTimeIsReleasedAtOnceAndPacingContinuesFromIt) {
  PaceClock clock;
  start(clock, 1.0);
  const std::int64_t far = clock.data_start_ns + 3'000'000'000'000'000'000;  // ~95 years on
  const auto jump = timed_wait(clock, far);
  EXPECT_TRUE(jump.released);
  EXPECT_LT(jump.seconds, 0.5);
  EXPECT_EQ(clock.reanchors(), 1U);
  // The stream continues after its pause: 0.15 s later in data is 0.15 s later on the host.
  const auto next = timed_wait(clock, far + 150'000'000);
  EXPECT_GE(next.seconds, 0.14);
  EXPECT_LT(next.seconds, 0.6);
  EXPECT_EQ(clock.reanchors(), 1U);
}

TEST(PaceClock, AnOutlierDoesNotStallTheOtherStream) {
  PaceClock clock;
  start(clock, 1.0);
  // One stream's corrupt time (near the int64 limit) moves the clock; the other stream, still on
  // the recorded timeline, moves it back instead of waiting or racing.
  EXPECT_LT(timed_wait(clock, std::numeric_limits<std::int64_t>::max()).seconds, 0.5);
  EXPECT_LT(timed_wait(clock, std::numeric_limits<std::int64_t>::min()).seconds, 0.5);
  EXPECT_LT(timed_wait(clock, clock.data_start_ns + 50'000'000).seconds, 0.5);
  const auto paced = timed_wait(clock, clock.data_start_ns + 250'000'000);
  EXPECT_GE(paced.seconds, 0.19);
  EXPECT_LT(paced.seconds, 0.7);
  EXPECT_EQ(clock.reanchors(), 3U);
}

TEST(PaceClock, StopEndsTheWait) {
  PaceClock clock;
  start(clock, 1.0);
  std::atomic<bool> stop{true};
  EXPECT_FALSE(clock.wait_until(clock.data_start_ns + 1'000'000'000, stop, [] {}));
}
