// The SPSC ring: order, drops when full, the swap hand-off, and a two-thread stress test (run
// under TSan by scripts/test.sh).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "liod/drivers/spsc_ring.hpp"

using liod::drivers::Notifier;
using liod::drivers::SpscRing;

TEST(SpscRing, CapacityRoundsUpAndDropsWhenFull) {
  SpscRing<int> ring(5);
  ASSERT_EQ(ring.capacity(), 8U);
  for (int i = 0; i < 8; ++i) {
    int v = i;
    EXPECT_TRUE(ring.try_push(v));
  }
  int extra = 99;
  EXPECT_FALSE(ring.try_push(extra));
  EXPECT_FALSE(ring.try_push(extra));
  EXPECT_EQ(ring.drops(), 2U);
  EXPECT_EQ(ring.size(), 8U);
  for (int i = 0; i < 8; ++i) {
    int v = -1;
    ASSERT_TRUE(ring.try_pop(v));
    EXPECT_EQ(v, i);
  }
  int v = 0;
  EXPECT_FALSE(ring.try_pop(v));
  EXPECT_EQ(ring.drops(), 2U);  // pops do not reset the count
}

TEST(SpscRing, SwapHandOffRecyclesBuffers) {
  SpscRing<std::vector<int>> ring(2);
  std::vector<int> a(1000, 1);
  const int* buffer = a.data();
  ASSERT_TRUE(ring.try_push(a));
  EXPECT_TRUE(a.empty());  // got the slot's (empty) object back
  std::vector<int> out;
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out.data(), buffer);  // the same allocation travelled through
  EXPECT_EQ(out.size(), 1000U);
}

TEST(SpscRing, CloseAndDrained) {
  SpscRing<int> ring(4);
  int v = 1;
  ring.try_push(v);
  EXPECT_FALSE(ring.drained());
  ring.close();
  EXPECT_FALSE(ring.drained());  // one item still queued
  ASSERT_TRUE(ring.try_pop(v));
  EXPECT_TRUE(ring.drained());
}

TEST(SpscRing, NotifierWakesAndTimesOut) {
  Notifier n;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(n.wait(std::chrono::milliseconds(20)));
  EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(15));
  SpscRing<int> ring(4, &n);
  int v = 3;
  ring.try_push(v);
  EXPECT_TRUE(n.wait(std::chrono::milliseconds(1000)));
}

// Producer pushes a sequence as fast as it can (never blocking); the consumer checks that what
// arrives is strictly increasing and that received + dropped == pushed attempts.
TEST(SpscRing, TwoThreadStressLossy) {
  SpscRing<std::uint64_t> ring(64);
  constexpr std::uint64_t kCount = 2000000;
  std::atomic<bool> done{false};
  std::uint64_t received = 0;
  std::uint64_t last = 0;
  bool ordered = true;
  std::thread consumer([&] {
    std::uint64_t v = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      if (ring.try_pop(v)) {
        if (received > 0 && v <= last) ordered = false;
        last = v;
        ++received;
      } else if (done.load() && ring.size() == 0) {
        if (!ring.try_pop(v)) break;
        if (received > 0 && v <= last) ordered = false;
        last = v;
        ++received;
      }
    }
  });
  for (std::uint64_t i = 1; i <= kCount; ++i) {
    std::uint64_t v = i;
    ring.try_push(v);
  }
  done.store(true);
  consumer.join();
  EXPECT_TRUE(ordered);
  EXPECT_EQ(received + ring.drops(), kCount);
  EXPECT_GT(received, 0U);
}

// Lossless mode (replay): push_wait never drops and delivers everything in order.
TEST(SpscRing, TwoThreadStressLossless) {
  SpscRing<std::uint64_t> ring(16);
  constexpr std::uint64_t kCount = 200000;
  std::atomic<bool> stop{false};
  std::uint64_t expected = 1;
  bool ok = true;
  std::thread consumer([&] {
    std::uint64_t v = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (expected <= kCount && std::chrono::steady_clock::now() < deadline) {
      if (ring.try_pop(v)) {
        if (v != expected) ok = false;
        ++expected;
      }
    }
    stop.store(true);  // unblocks the producer if the deadline hit
  });
  for (std::uint64_t i = 1; i <= kCount; ++i) {
    std::uint64_t v = i;
    if (!ring.push_wait(v, stop)) break;
  }
  consumer.join();
  EXPECT_TRUE(ok);
  EXPECT_EQ(expected, kCount + 1);
  EXPECT_EQ(ring.drops(), 0U);
}
