// A DIFOP after the first whose calibration differs (lidar.calibration_updates): counted, flagged on
// the sweeps it concerns, and never applied in the middle of a sweep, on a synthetic 10 Hz stream
// whose split falls in the middle of a packet.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "liod/drivers/rs_helios.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

using test::SyntheticBlock;

constexpr double kRangeM = 2.0;

/// Elevations of table A (-16..15 deg) and table B (each half a degree higher): the same ring order.
std::vector<double> elevations(double shift_deg) {
  std::vector<double> v;
  for (int i = 0; i < 32; ++i) v.push_back(-16.0 + i + shift_deg);
  return v;
}
const std::vector<double> kA = elevations(0.0);
const std::vector<double> kB = elevations(0.5);

/// Packet i of a 10 Hz single-return stream starting at 90 deg: the split at 0 deg falls on block 6
/// of packets 112, 262, 412, ... (block 1350 + 1800 k).
std::vector<std::uint8_t> packet(std::size_t i) {
  std::array<SyntheticBlock, 12> blocks{};
  for (std::size_t k = 0; k < 12; ++k) {
    blocks[k].azimuth = static_cast<std::uint16_t>((9000 + 20 * (12 * i + k)) % 36000);
    blocks[k].raw_distance.fill(static_cast<std::uint16_t>(kRangeM / 0.0025));
  }
  const auto t_us = static_cast<std::int64_t>(std::llround(1.7e15 + static_cast<double>(i) * 12 * helios::kBlockPeriodS * 1e6));
  return test::make_msop(t_us, static_cast<std::uint32_t>(i), blocks);
}

struct Sweep {
  std::size_t points = 0;
  std::size_t with_a = 0;  ///< points whose height is table A's for their ring
  std::size_t with_b = 0;
  bool flagged = false;
};

/// Feeds `first` (a DIFOP, unless empty), then packets 0..599 with `difop_at[i]` right after packet
/// i, and sorts each sweep's points by the table their height comes from.
std::vector<Sweep> run(HeliosOptions o, const std::vector<std::uint8_t>& first,
                       const std::map<std::size_t, std::vector<std::uint8_t>>& difop_at, HeliosStats& stats) {
  std::vector<Sweep> sweeps;
  RsHeliosDecoder dec(std::move(o), [&](Scan& scan, const SweepInfo& info) {
    Sweep s;
    s.flagged = info.calibration_changed;
    for (const LidarPoint& p : scan.points) {
      ++s.points;
      const double z_a = kRangeM * std::sin(kA[p.ring] * std::numbers::pi / 180.0);
      const double z_b = kRangeM * std::sin(kB[p.ring] * std::numbers::pi / 180.0);
      if (std::abs(static_cast<double>(p.z) - z_a) < 1e-4) ++s.with_a;
      if (std::abs(static_cast<double>(p.z) - z_b) < 1e-4) ++s.with_b;
    }
    sweeps.push_back(s);
  });
  if (!first.empty()) dec.feed(first);
  for (std::size_t i = 0; i < 600; ++i) {
    dec.feed(packet(i));
    if (const auto it = difop_at.find(i); it != difop_at.end()) dec.feed(it->second);
  }
  stats = dec.stats();
  return sweeps;
}

std::vector<std::uint8_t> difop(const std::vector<double>& vertical, std::uint16_t rpm = 600) {
  return test::make_difop(vertical, std::vector<double>(32, 0.0), helios::kReturnStrongest, rpm);
}

void expect_table(const std::vector<Sweep>& sweeps, std::size_t k, bool table_a, bool flagged) {
  SCOPED_TRACE("sweep " + std::to_string(k));
  ASSERT_LT(k, sweeps.size());
  const Sweep& s = sweeps[k];
  EXPECT_GT(s.points, 0U);
  EXPECT_EQ(table_a ? s.with_a : s.with_b, s.points) << "a sweep decoded with two calibrations";
  EXPECT_EQ(s.flagged, flagged);
}

// Sweeps 0..3: blocks 0-1349 (packets 0..112 block 5), 1350-3149 (..262), 3150-4949 (..412),
// 4950-6749 (..562).

TEST(CalibrationUpdates, ByDefaultADifferingDifopIsCountedAndFlaggedNotApplied) {
  // B arrives in sweep 1, A again in sweep 2: the sweeps stay A; those that saw B, or began while
  // the sensor's last word was B, are flagged.
  HeliosStats stats;
  const auto sweeps = run(HeliosOptions{}, difop(kA), {{200, difop(kB)}, {320, difop(kA)}}, stats);
  ASSERT_EQ(sweeps.size(), 4U);
  expect_table(sweeps, 0, true, false);
  expect_table(sweeps, 1, true, true);
  expect_table(sweeps, 2, true, true);
  expect_table(sweeps, 3, true, false);
  EXPECT_EQ(stats.calibration_changes, 1U);
  EXPECT_EQ(stats.difop, 3U);
}

TEST(CalibrationUpdates, FollowTakesADifferingDifopAtTheNextSweepBoundary) {
  // The boundary falls on block 6 of a packet: its first 6 blocks end the old sweep with the old
  // table, its last 6 begin the next one with the new.
  HeliosOptions o;
  o.calibration_updates = CalibrationUpdates::Follow;
  HeliosStats stats;
  const auto sweeps = run(o, difop(kA), {{200, difop(kB)}, {320, difop(kA)}}, stats);
  ASSERT_EQ(sweeps.size(), 4U);
  expect_table(sweeps, 0, true, false);
  expect_table(sweeps, 1, true, false);
  expect_table(sweeps, 2, false, true);
  expect_table(sweeps, 3, true, true);
  EXPECT_EQ(stats.calibration_changes, 2U);
  EXPECT_EQ(sweeps[1].points, 1800U * 32U);  // no block lost or doubled at the boundary
  EXPECT_EQ(sweeps[2].points, 1800U * 32U);
}

TEST(CalibrationUpdates, TheFirstDifopReplacesTheCsvTableAtASweepBoundary) {
  // Decoding starts with the CSV's table (A); the first DIFOP (B) comes within sweep 0. It is the
  // calibration from then on, not a change, but sweep 0 stays A to its end.
  HeliosOptions o;
  o.angles = AngleTable{kA, std::vector<double>(32, 0.0)};
  HeliosStats stats;
  const auto sweeps = run(o, {}, {{50, difop(kB)}}, stats);
  ASSERT_EQ(sweeps.size(), 4U);
  expect_table(sweeps, 0, true, false);
  for (std::size_t k = 1; k < 4; ++k) expect_table(sweeps, k, false, false);
  EXPECT_EQ(stats.calibration_changes, 0U);
}

TEST(CalibrationUpdates, ARotationRateOrReturnModeChangeIsOneToo) {
  HeliosStats stats;
  auto dual = difop(kA);
  dual[300] = helios::kReturnDual;
  const auto sweeps = run(HeliosOptions{}, difop(kA), {{200, difop(kA, 1200)}, {400, dual}}, stats);
  EXPECT_EQ(stats.calibration_changes, 2U);
  ASSERT_EQ(sweeps.size(), 4U);
  EXPECT_EQ(sweeps[0].flagged, false);
  EXPECT_EQ(sweeps[1].flagged, true);
  // Still single return: every sweep has 1800 firings of 32 lasers.
  for (std::size_t k = 1; k < 4; ++k) EXPECT_EQ(sweeps[k].points, 1800U * 32U) << k;
}

}  // namespace
}  // namespace liod::drivers
