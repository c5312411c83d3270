// Sweep splitting, time rebasing, loss accounting and buffer reuse, on synthetic packet streams.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "liod/drivers/rs_helios.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

using test::SyntheticBlock;


/// A 10 Hz single-return 5515 stream: packet i covers blocks 12i..12i+11 from `start_az`.
class Stream {
 public:
  explicit Stream(std::uint16_t start_az) : start_az_(start_az) {}
  std::vector<std::uint8_t> packet(std::size_t i) const {
    std::array<SyntheticBlock, 12> blocks{};
    for (std::size_t k = 0; k < 12; ++k) {
      blocks[k].azimuth = static_cast<std::uint16_t>((start_az_ + 20 * (12 * i + k)) % 36000);
      blocks[k].raw_distance.fill(800);  // 2 m
      blocks[k].intensity.fill(9);
    }
    const auto t_us = static_cast<std::int64_t>(std::llround(1.7e15 + static_cast<double>(i) * 12 * helios::kBlockPeriodS * 1e6));
    return test::make_msop(t_us, static_cast<std::uint32_t>(1000 + i), blocks);
  }

 private:
  std::uint16_t start_az_;
};

HeliosOptions options(double split_deg) {
  HeliosOptions o;
  o.angles = AngleTable{std::vector<double>(32, 0.0), std::vector<double>(32, 0.0)};
  for (std::size_t i = 0; i < 32; ++i) o.angles->vertical_deg[i] = -16.0 + static_cast<double>(i);
  o.split_azimuth_deg = split_deg;
  return o;
}

struct Collected {
  std::vector<Scan> scans;
  std::vector<SweepInfo> infos;
};

Collected run(HeliosOptions o, const Stream& stream, std::size_t packets, const std::set<std::size_t>& skip = {}) {
  Collected c;
  RsHeliosDecoder dec(std::move(o), [&](Scan& s, const SweepInfo& info) {
    c.scans.push_back(s);
    c.infos.push_back(info);
  });
  for (std::size_t i = 0; i < packets; ++i)
    if (!skip.contains(i)) dec.feed(stream.packet(i));
  dec.flush();
  return c;
}

TEST(SweepAssembly, SplitsAtZeroAcrossTheWrap) {
  // Start at 90°: a 270° first sweep, then full 360° sweeps of 150 packets.
  const Collected c = run(options(0.0), Stream(9000), 150 * 3);
  ASSERT_EQ(c.scans.size(), 3U);  // partial + 2 full; the last partial is dropped at flush
  EXPECT_EQ(c.infos[0].first_azimuth, 9000);
  EXPECT_EQ(c.infos[0].blocks, 1350U);
  EXPECT_NEAR(c.infos[0].azimuth_coverage_deg, 270.0, 1e-6);
  for (std::size_t i = 1; i < 3; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(c.infos[i].first_azimuth, 0);
    EXPECT_EQ(c.infos[i].last_azimuth, 35980);
    EXPECT_EQ(c.infos[i].blocks, 1800U);
    EXPECT_NEAR(c.infos[i].azimuth_coverage_deg, 360.0, 1e-6);
    EXPECT_EQ(c.scans[i].points.size(), 1800U * 32U);
    EXPECT_EQ(c.scans[i].sequence, i);
    EXPECT_EQ(c.scans[i].beam_count, 32);
    // 1800 blocks: the last block starts 1799 × 55.56 µs after the first, plus its last firing.
    EXPECT_NEAR(c.scans[i].end_time - c.scans[i].start_time, 1799 * helios::kBlockPeriodS + 45.15e-6, 2e-6);
    EXPECT_NEAR(c.scans[i].start_time - c.scans[i - 1].start_time, i == 1 ? 1350 * helios::kBlockPeriodS : 1800 * helios::kBlockPeriodS, 2e-6);
  }
  // Rings are the elevation ranks; all 32 present.
  std::set<std::uint16_t> rings;
  for (const LidarPoint& p : c.scans[1].points) rings.insert(p.ring);
  EXPECT_EQ(rings.size(), 32U);
}

TEST(SweepAssembly, SplitAngleInsideTheSweep) {
  const Collected c = run(options(180.0), Stream(0), 150 * 3);
  ASSERT_EQ(c.scans.size(), 3U);
  EXPECT_EQ(c.infos[0].first_azimuth, 0);
  EXPECT_EQ(c.infos[0].last_azimuth, 17980);
  for (std::size_t i = 1; i < 3; ++i) {
    EXPECT_EQ(c.infos[i].first_azimuth, 18000);
    EXPECT_EQ(c.infos[i].blocks, 1800U);
  }
}

TEST(SweepAssembly, SplitJustBeforeTheWrapAndFlushOfThePartialLastSweep) {
  HeliosOptions o = options(359.99);
  o.emit_partial_sweep_on_flush = true;
  const Collected c = run(o, Stream(9000), 150 * 2);
  ASSERT_EQ(c.scans.size(), 3U);
  EXPECT_EQ(c.infos[1].first_azimuth, 0);  // 359.8° -> 0° crosses 359.99°
  EXPECT_TRUE(c.infos[2].flushed);
  EXPECT_EQ(c.infos[2].blocks, 2U * 1800U - 1350U - 1800U);
}

TEST(SweepAssembly, LostPacketsAreCountedAndALongGapCutsTheSweep) {
  Collected c;
  HeliosStats stats;
  {
    RsHeliosDecoder dec(options(0.0), [&](Scan& s, const SweepInfo& info) {
      c.scans.push_back(s);
      c.infos.push_back(info);
    });
    const Stream stream(0);
    for (std::size_t i = 0; i < 400; ++i) {
      if (i == 10 || i == 11 || i == 12) continue;  // 3 packets lost: a 0.72° azimuth jump
      if (i >= 200 && i < 300) continue;            // 67 ms silent: more than max_block_gap_s
      dec.feed(stream.packet(i));
    }
    stats = dec.stats();
  }
  EXPECT_EQ(stats.lost_packets, 3U + 100U);
  EXPECT_EQ(stats.azimuth_jumps, 2U);  // 7.4° after the 3 lost packets, 240° after the 100
  EXPECT_EQ(stats.time_gaps, 1U);
  ASSERT_GE(c.scans.size(), 2U);
  // Loss is not coverage: the 7.4° jump over the 36 missing blocks is left out entirely.
  EXPECT_NEAR(c.infos[0].azimuth_coverage_deg, 360.0 - 37 * 0.2, 1e-6);
  EXPECT_TRUE(c.infos[1].ended_by_gap);
}

TEST(SweepAssembly, LateAndRepeatedPacketsJoinTheirSweepInTimeOrder) {
  // Delivery order of a 3-sweep stream: 50 after 51 and 52, 70 twice, and 149 (the last packet of
  // the first sweep) after 150 (the first of the second), when its sweep is already out.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < 451; ++i) {
    if (i == 50 || i == 149) continue;
    order.push_back(i);
    if (i == 52) order.push_back(50);
    if (i == 70) order.push_back(70);
    if (i == 150) order.push_back(149);
  }
  Collected c;
  HeliosStats stats;
  {
    RsHeliosDecoder dec(options(0.0), [&](Scan& s, const SweepInfo& info) {
      c.scans.push_back(s);
      c.infos.push_back(info);
    });
    const Stream stream(0);
    for (const std::size_t i : order) dec.feed(stream.packet(i));
    stats = dec.stats();
  }
  // No sweep cut short: the split stays where the azimuth crosses 0°.
  ASSERT_EQ(c.scans.size(), 3U);
  EXPECT_EQ(stats.time_gaps, 0U);
  EXPECT_EQ(stats.duplicate_packets, 1U);
  EXPECT_EQ(stats.late_packets, 1U);
  EXPECT_EQ(stats.late_packets_dropped, 1U);
  EXPECT_EQ(c.scans[0].points.size(), 149U * 12U * 32U);  // all but the packet that came too late
  EXPECT_EQ(c.scans[1].points.size(), 150U * 12U * 32U);
  EXPECT_EQ(c.scans[2].points.size(), 150U * 12U * 32U);
  // Each ring in time order, as the feature extraction walks it: one firing every 55.56 µs.
  std::vector<std::vector<float>> ring_times(32);
  for (const LidarPoint& p : c.scans[0].points) ring_times[p.ring].push_back(p.time);
  for (const auto& times : ring_times) {
    ASSERT_EQ(times.size(), 149U * 12U);
    for (std::size_t k = 1; k < times.size(); ++k) ASSERT_NEAR(times[k] - times[k - 1], helios::kBlockPeriodS, 1e-6) << k;
  }
}

TEST(SweepAssembly, BuffersAreRecycledWhenTheConsumerSwaps) {
  std::vector<const LidarPoint*> buffers;
  Scan recycled;
  RsHeliosDecoder dec(options(0.0), [&](Scan& s, const SweepInfo&) {
    std::swap(s, recycled);
    buffers.push_back(recycled.points.data());
  });
  const Stream stream(0);
  for (std::size_t i = 0; i < 150 * 8 + 1; ++i) dec.feed(stream.packet(i));
  ASSERT_EQ(buffers.size(), 8U);
  // Two buffers ping-pong between the decoder and the consumer: no new allocation per sweep.
  const std::set<const LidarPoint*> distinct(buffers.begin() + 1, buffers.end());
  EXPECT_LE(distinct.size(), 2U);
}

/// Packets whose 12 blocks all read one azimuth (a stalled motor, a stuck azimuth field, a foreign
/// sender), 12 blocks of 2 m returns each, timed as a 10 Hz single-return stream.
std::vector<std::uint8_t> stuck_packet(std::size_t i, std::uint16_t azimuth) {
  std::array<SyntheticBlock, 12> blocks{};
  for (auto& b : blocks) {
    b.azimuth = azimuth;
    b.raw_distance.fill(800);
    b.intensity.fill(9);
  }
  const auto t_us = static_cast<std::int64_t>(std::llround(1.7e15 + static_cast<double>(i) * 12 * helios::kBlockPeriodS * 1e6));
  return test::make_msop(t_us, static_cast<std::uint32_t>(i), blocks);
}

TEST(SweepAssembly, AStuckAzimuthIsCutAtTheSizeCap) {
  // 20 s of packets that never cross the split: without a cap the one open sweep held them all
  // (11.5 million points here; `liod decode` of 30 s of such a drive reached 700 MB).
  HeliosOptions o = options(0.0);
  o.emit_partial_sweep_on_flush = true;
  std::vector<SweepInfo> infos;
  std::size_t most_points = 0;
  std::size_t largest_capacity = 0;
  RsHeliosDecoder dec(o, [&](Scan& s, const SweepInfo& info) {
    infos.push_back(info);
    most_points = std::max(most_points, s.points.size());
    largest_capacity = std::max(largest_capacity, s.points.capacity());
  });
  constexpr std::size_t kPackets = 30000;
  for (std::size_t i = 0; i < kPackets; ++i) dec.feed(stuck_packet(i, 10000));
  dec.flush();
  // The cap: a quarter above one revolution at 5 Hz in dual return (7200 blocks, spec §3, §7).
  constexpr std::size_t kCapPoints = std::size_t{helios::kMaxSweepBlocks} * 32;
  EXPECT_EQ(kCapPoints, 288000U);
  ASSERT_EQ(infos.size(), kPackets * 12 / helios::kMaxSweepBlocks);  // 40, the last one flushed
  for (std::size_t k = 0; k < infos.size(); ++k) {
    EXPECT_TRUE(infos[k].truncated) << k;
    EXPECT_EQ(infos[k].blocks, helios::kMaxSweepBlocks) << k;
  }
  EXPECT_EQ(dec.stats().truncated_sweeps, infos.size());
  EXPECT_LE(most_points, kCapPoints);
  // The working buffer grows by doubling from its reserve, so it never holds more than twice the cap.
  EXPECT_LE(largest_capacity, 2 * kCapPoints);
}

TEST(SweepAssembly, AfterAStuckRunTheFirstSweepFromTheSplitIsWhole) {
  // 1.5 revolutions stuck at 100 deg, then the motor turns again from 100 deg: the sweep begun at
  // the last cut holds the rest of the stuck run and is truncated too; the one from 0 deg is whole.
  std::vector<SweepInfo> infos;
  RsHeliosDecoder dec(options(0.0), [&](Scan&, const SweepInfo& info) { infos.push_back(info); });
  std::size_t i = 0;
  for (; i < 1000; ++i) dec.feed(stuck_packet(i, 10000));
  const Stream turning(10000);
  for (std::size_t k = 0; k < 150 * 3; ++k, ++i) {
    auto p = turning.packet(k);
    const auto t_us = static_cast<std::int64_t>(std::llround(1.7e15 + static_cast<double>(i) * 12 * helios::kBlockPeriodS * 1e6));
    store_be48(p.data() + 20, static_cast<std::uint64_t>(t_us / 1'000'000));
    store_be32(p.data() + 26, static_cast<std::uint32_t>(t_us % 1'000'000));
    dec.feed(p);
  }
  ASSERT_EQ(infos.size(), 4U);  // cut at 9000 blocks, the rest to 0 deg, then two revolutions
  EXPECT_TRUE(infos[0].truncated);
  EXPECT_TRUE(infos[1].truncated);
  EXPECT_EQ(infos[1].blocks, 1000U * 12 - helios::kMaxSweepBlocks + 1300U);
  EXPECT_FALSE(infos[2].truncated);
  EXPECT_EQ(infos[2].blocks, 1800U);
  EXPECT_FALSE(infos[3].truncated);
  EXPECT_EQ(dec.stats().truncated_sweeps, 2U);
}

TEST(SweepAssembly, ARevolutionAtTheSlowestRateInDualReturnIsNotCut) {
  // 5 Hz (0.1° per block period), dual return: 7200 blocks per revolution, pairs share an azimuth.
  HeliosOptions o = options(0.0);
  o.return_mode = ReturnModePolicy::ForceDual;
  std::vector<SweepInfo> infos;
  RsHeliosDecoder dec(o, [&](Scan&, const SweepInfo& info) { infos.push_back(info); });
  for (std::size_t i = 0; i < 600 * 3 + 1; ++i) {
    std::array<SyntheticBlock, 12> blocks{};
    for (std::size_t k = 0; k < 12; ++k) {
      blocks[k].azimuth = static_cast<std::uint16_t>((10 * (6 * i + k / 2)) % 36000);
      blocks[k].raw_distance.fill(800);
    }
    const auto t_us = static_cast<std::int64_t>(std::llround(1.7e15 + static_cast<double>(i) * 6 * helios::kBlockPeriodS * 1e6));
    dec.feed(test::make_msop(t_us, static_cast<std::uint32_t>(i), blocks));
  }
  ASSERT_EQ(infos.size(), 3U);
  for (const SweepInfo& info : infos) {
    EXPECT_FALSE(info.truncated);
    EXPECT_EQ(info.blocks, 7200U);
  }
  EXPECT_EQ(dec.stats().truncated_sweeps, 0U);
}

TEST(SweepAssembly, ArrivalTimeStampsReplaceTheSensorClock) {
  HeliosOptions o = options(0.0);
  o.msop.time_source = TimeSource::ArrivalTime;
  o.emit_partial_sweep_on_flush = true;
  std::vector<Scan> scans;
  RsHeliosDecoder dec(o, [&](Scan& s, const SweepInfo&) { scans.push_back(s); });
  const Stream stream(0);
  const std::int64_t arrival = 5'000'000'000LL;
  dec.feed(stream.packet(0), arrival);
  dec.flush();
  ASSERT_EQ(scans.size(), 1U);
  // §3: arrival minus one packet duration (12 × 55.56 µs) is block 0's time.
  EXPECT_NEAR(scans[0].start_time, 5.0 - 12 * helios::kBlockPeriodS, 1e-7);
}

}  // namespace
}  // namespace liod::drivers
