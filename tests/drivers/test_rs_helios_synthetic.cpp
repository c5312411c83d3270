// RS-Helios decoding of packets built here from the spec's layout, with known contents.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <set>

#include "liod/drivers/input_error.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

using test::SyntheticBlock;

// Spec §5: the RS-Helios-5515 calibration (packet channel order).
const std::vector<double> kVert = {14.94, 13.03, 10.92, 8.89,   6.96,   5.46,   3.98,   2.67,
                                   1.33,  0.00,  -1.33, -2.67,  -3.96,  -5.13,  -6.53,  -7.91,
                                   -9.89, -15.97, -12.90, -19.08, -22.02, -27.97, -25.16, -31.15,
                                   -34.09, -37.29, -40.25, -43.71, -46.70, -49.75, -52.70, -54.60};
const std::vector<double> kHoriz = {-4.07, 3.63, -4.02, 3.60, -3.99, 3.58, -3.98, 3.57, -3.97, 3.57, -3.97,
                                    3.57,  -3.98, 3.58, -3.99, 3.59, -4.01, 3.66, -4.04, 3.70, -4.19, 3.88,
                                    -4.26, 3.97, -4.52, 4.14, -4.76, 4.38, -5.03, 4.61, -5.32, 4.80};
constexpr double kT = 55.56e-6;
constexpr double kRx = 0.03498;

AngleTable table_5515() { return AngleTable{kVert, kHoriz}; }

struct Expected {
  double x, y, z, time;
  std::uint16_t ring;
  std::uint8_t ret;
  float intensity;
};

/// §3-§4 computed independently, in double, the channel azimuth not rounded.
Expected expected_point(double block_az, double step, double firing_us, double block_time, double d,
                        std::size_t laser, std::uint16_t ring, std::uint8_t ret, std::uint8_t intensity) {
  const double az_ch = block_az + step * (firing_us * 1e-6 / kT);
  const double az_final = az_ch + kHoriz[laser] * 100.0;
  const double rad = std::numbers::pi / 18000.0;
  const double el = kVert[laser] * std::numbers::pi / 180.0;
  return {d * std::cos(el) * std::cos(az_final * rad) + kRx * std::cos(az_ch * rad),
          -d * std::cos(el) * std::sin(az_final * rad) - kRx * std::sin(az_ch * rad),
          d * std::sin(el),
          block_time + firing_us * 1e-6,
          ring,
          ret,
          static_cast<float>(intensity)};
}

std::uint16_t ring_5515(std::size_t slot) {
  std::uint16_t r = 0;
  for (double v : kVert) r += v < kVert[slot] ? 1 : 0;
  return r;
}

/// A 5515 single-return packet whose blocks step 0.2° from `start_az`, with varied distances, some
/// slots empty and one return closer than the minimum range.
std::array<SyntheticBlock, 12> varied_blocks(std::uint16_t start_az, bool dual) {
  std::array<SyntheticBlock, 12> blocks{};
  for (std::size_t k = 0; k < 12; ++k) {
    const std::size_t firing = dual ? k / 2 : k;
    blocks[k].azimuth = static_cast<std::uint16_t>((start_az + 20 * firing) % 36000);
    for (std::size_t s = 0; s < 32; ++s) {
      blocks[k].raw_distance[s] = static_cast<std::uint16_t>(400 + 37 * s + 11 * k);  // 1..4.3 m
      blocks[k].intensity[s] = static_cast<std::uint8_t>(s * 7 + k);
    }
    blocks[k].raw_distance[(k * 5) % 32] = 0;  // no return
    blocks[k].raw_distance[(k * 3 + 1) % 32] = 20;  // 5 cm: below the 0.1 m minimum
  }
  return blocks;
}

void expect_point(const LidarPoint& p, const Expected& e, const std::string& where) {
  EXPECT_NEAR(p.x, e.x, 1e-4) << where;
  EXPECT_NEAR(p.y, e.y, 1e-4) << where;
  EXPECT_NEAR(p.z, e.z, 1e-4) << where;
  EXPECT_NEAR(p.time, e.time, 2e-7) << where;
  EXPECT_EQ(p.ring, e.ring) << where;
  EXPECT_EQ(p.return_index, e.ret) << where;
  EXPECT_EQ(p.intensity, e.intensity) << where;
}

MsopDecoder decoder_5515() {
  MsopDecoder dec(HeliosModel::Helios5515, MsopDecoderOptions{});
  dec.set_angles(kVert, kHoriz);
  return dec;
}

TEST(RsHeliosSynthetic, SingleReturn5515DecodesToTheSpecGeometryAndTimes) {
  const MsopDecoder dec = decoder_5515();
  const auto blocks = varied_blocks(35960, false);  // wraps 359.8° -> 0° inside the packet
  const std::int64_t t_us = 1'700'000'000'000'000LL + 123'456;
  const auto packet = test::make_msop(t_us, 7, blocks);
  auto out = std::make_unique<PacketPoints>();
  MsopHeader header;
  ASSERT_EQ(dec.decode(packet, false, 0, *out, header), MsopStatus::Ok);
  EXPECT_EQ(out->time_ns, t_us * 1000);
  EXPECT_EQ(header.bottom_counter, 7U);
  EXPECT_FLOAT_EQ(header.temperature_c, 55.4375F);  // spec §2: bc 1b -> 887 x 0.0625 = 55.4 °C
  ASSERT_EQ(out->block_count, 12U);
  std::size_t n = 0;
  for (std::size_t k = 0; k < 12; ++k) {
    EXPECT_EQ(out->blocks[k].azimuth, blocks[k].azimuth);
    EXPECT_EQ(out->blocks[k].first_point, n);
    for (std::size_t s = 0; s < 32; ++s) {
      const std::uint16_t raw = blocks[k].raw_distance[s];
      if (raw == 0 || raw == 20) continue;
      const Expected e = expected_point(blocks[k].azimuth, 20, helios::kFiringOffsetsUs[s], static_cast<double>(k) * kT,
                                        raw * 0.0025, s, ring_5515(s), 0, blocks[k].intensity[s]);
      ASSERT_LT(n, out->point_count);
      expect_point(out->points[n++], e, "block " + std::to_string(k) + " slot " + std::to_string(s));
    }
  }
  EXPECT_EQ(n, out->point_count);
  EXPECT_EQ(n, 12U * 30U);
}

TEST(RsHeliosSynthetic, ChannelAzimuthIsNotRoundedToTheTablesStep) {
  // §3.2 places a channel at block_az + step x firing_offset / 55.56 us: 5.46 units (0.01°) for
  // slot 9, which rs_driver and nebula round or truncate. The laser fires where the head has turned
  // to; rounding turns each channel's points by up to 0.005°, the same every turn: 8.7 mm at 100 m.
  const MsopDecoder dec = decoder_5515();
  std::array<SyntheticBlock, 12> blocks{};
  for (std::size_t k = 0; k < 12; ++k) {
    blocks[k].azimuth = static_cast<std::uint16_t>(12000 + 20 * k);
    for (std::size_t s = 0; s < 32; ++s) blocks[k].raw_distance[s] = static_cast<std::uint16_t>(40000 + 100 * s);  // 100-108 m
  }
  const auto packet = test::make_msop(1'700'000'000'000'000LL, 0, blocks);
  auto out = std::make_unique<PacketPoints>();
  MsopHeader header;
  ASSERT_EQ(dec.decode(packet, false, 0, *out, header), MsopStatus::Ok);
  ASSERT_EQ(out->point_count, 12U * 32U);
  double largest_error = 0.0;
  for (std::size_t k = 0; k < 12; ++k) {
    for (std::size_t s = 0; s < 32; ++s) {
      const Expected e = expected_point(blocks[k].azimuth, 20, helios::kFiringOffsetsUs[s], static_cast<double>(k) * kT,
                                        blocks[k].raw_distance[s] * 0.0025, s, ring_5515(s), 0, 0);
      const LidarPoint& p = out->points[k * 32 + s];
      largest_error = std::max(largest_error, std::hypot(static_cast<double>(p.x) - e.x, static_cast<double>(p.y) - e.y));
    }
  }
  // float coordinates at 100 m carry ~4 um; the interpolated cos/sin table 4e-9 rad.
  EXPECT_LT(largest_error, 5e-4);
}

TEST(RsHeliosSynthetic, DualReturn5515PairsBlocksAndLabelsReturns) {
  // No DIFOP: dual is detected from the duplicated block azimuths (§7).
  std::vector<Scan> sweeps;
  HeliosOptions o;
  o.angles = table_5515();
  o.emit_partial_sweep_on_flush = true;
  RsHeliosDecoder dec(o, [&](Scan& s, const SweepInfo&) { sweeps.push_back(s); });
  const auto blocks = varied_blocks(1000, true);
  const std::int64_t t_us = 1'700'000'000'000'000LL;
  ASSERT_EQ(dec.feed(test::make_msop(t_us, 1, blocks)), PacketKind::Msop);
  EXPECT_TRUE(dec.dual_return());
  dec.flush();
  ASSERT_EQ(sweeps.size(), 1U);
  const Scan& scan = sweeps[0];
  std::array<float, 32> sorted{};
  std::copy(helios::kFiringOffsetsUs.begin(), helios::kFiringOffsetsUs.end(), sorted.begin());
  std::sort(sorted.begin(), sorted.end());
  std::size_t n = 0;
  for (std::size_t k = 0; k < 12; ++k) {
    const std::size_t pair = k / 2;
    for (std::size_t s = 0; s < 32; ++s) {
      const std::uint16_t raw = blocks[k].raw_distance[s];
      if (raw == 0 || raw == 20) continue;
      // Pairs share azimuth and time (§3); the azimuth step is to the next pair (§3.2).
      const Expected e = expected_point(blocks[k].azimuth, 20, sorted[s], static_cast<double>(pair) * kT, raw * 0.0025, s,
                                        ring_5515(s), static_cast<std::uint8_t>(k % 2), blocks[k].intensity[s]);
      ASSERT_LT(n, scan.points.size());
      expect_point(scan.points[n++], e, "block " + std::to_string(k) + " slot " + std::to_string(s));
    }
  }
  EXPECT_EQ(n, scan.points.size());
  // Block 0 slot 0 has no return, but block 1 (the pair's second return) slot 0 fired at the
  // same instant: the sweep starts at the header time.
  EXPECT_NEAR(scan.start_time, static_cast<double>(t_us) * 1e-6, 1e-6);
  EXPECT_EQ(scan.points[30].return_index, 1);
  EXPECT_FLOAT_EQ(scan.points[30].time, 0.0F);
}

TEST(RsHeliosSynthetic, DifopReturnModeOverridesDetection) {
  HeliosOptions o;
  o.angles = table_5515();
  RsHeliosDecoder dec(o, [](Scan&, const SweepInfo&) {});
  const auto single = test::make_msop(1'700'000'000'000'000LL, 1, varied_blocks(1000, false));
  const auto dual = test::make_msop(1'700'000'000'001'000LL, 2, varied_blocks(1000, true));
  ASSERT_EQ(dec.feed(test::make_difop(kVert, kHoriz, helios::kReturnDual)), PacketKind::Difop);
  dec.feed(single);
  EXPECT_TRUE(dec.dual_return());
  // A later DIFOP's return mode is a calibration change: pinned by default (counted, not taken).
  dec.feed(test::make_difop(kVert, kHoriz, helios::kReturnLast));
  dec.feed(dual);
  EXPECT_TRUE(dec.dual_return());
  EXPECT_EQ(dec.stats().calibration_changes, 1U);

  RsHeliosDecoder detecting(o, [](Scan&, const SweepInfo&) {});  // no DIFOP: detected per packet
  detecting.feed(single);
  EXPECT_FALSE(detecting.dual_return());
  detecting.feed(dual);
  EXPECT_TRUE(detecting.dual_return());
}

TEST(RsHeliosSynthetic, Helios16PDualPutsTheSecondReturnInSlots16To31) {
  MsopDecoder dec(HeliosModel::Helios16P, MsopDecoderOptions{});
  dec.set_angles(std::vector<double>(kVert.begin(), kVert.begin() + 16), std::vector<double>(kHoriz.begin(), kHoriz.begin() + 16));
  std::array<SyntheticBlock, 12> blocks{};
  for (std::size_t k = 0; k < 12; ++k) {
    blocks[k].azimuth = static_cast<std::uint16_t>(500 + 20 * k);
    for (std::size_t s = 0; s < 32; ++s) blocks[k].raw_distance[s] = static_cast<std::uint16_t>(800 + s);
  }
  auto out = std::make_unique<PacketPoints>();
  MsopHeader header;
  ASSERT_EQ(dec.decode(test::make_msop(1'000'000, 1, blocks), true, 0, *out, header), MsopStatus::Ok);
  ASSERT_EQ(out->point_count, 12U * 32U);
  for (std::size_t s = 0; s < 16; ++s) {
    const LidarPoint& first = out->points[s];
    const LidarPoint& second = out->points[s + 16];
    EXPECT_EQ(first.return_index, 0);
    EXPECT_EQ(second.return_index, 1);
    EXPECT_EQ(first.ring, second.ring);
    EXPECT_FLOAT_EQ(first.time, second.time);  // same firing
  }
  // Single return: slots 16..31 are a second firing later in the same 55.56 µs block.
  ASSERT_EQ(dec.decode(test::make_msop(1'000'000, 1, blocks), false, 0, *out, header), MsopStatus::Ok);
  EXPECT_EQ(out->points[16].return_index, 0);
  EXPECT_NEAR(out->points[16].time, 26.53e-6, 1e-9);
  EXPECT_NEAR(out->points[12 * 32 - 1].time, 11 * kT + 45.15e-6, 1e-9);
  EXPECT_EQ(out->points[0].ring, out->points[16].ring);
}

TEST(RsHeliosSynthetic, RangeResolutionFollowsTheHeaderFlag) {
  const MsopDecoder dec = decoder_5515();
  auto out = std::make_unique<PacketPoints>();
  MsopHeader header;
  std::array<SyntheticBlock, 12> blocks{};
  for (std::size_t k = 0; k < 12; ++k) blocks[k].azimuth = static_cast<std::uint16_t>(20 * k);
  blocks[0].raw_distance[9] = 1000;  // slot 9: elevation 0°, horizontal offset +3.57°
  for (std::uint8_t flag : {std::uint8_t{1}, std::uint8_t{0}}) {
    ASSERT_EQ(dec.decode(test::make_msop(1'000'000, 1, blocks, flag), false, 0, *out, header), MsopStatus::Ok);
    ASSERT_EQ(out->point_count, 1U);
    const double expect_d = flag == 1 ? 2.5 : 5.0;
    const auto& p = out->points[0];
    EXPECT_NEAR(std::hypot(p.x, p.y), expect_d + kRx, 2e-3) << "flag " << int{flag};
    EXPECT_NEAR(p.z, 0.0, 1e-6);
  }
}

TEST(RsHeliosSynthetic, BadPacketsAreCountedNotFatal) {
  HeliosOptions o;
  o.angles = table_5515();
  RsHeliosDecoder dec(o, [](Scan&, const SweepInfo&) {});
  const auto good = test::make_msop(1'700'000'000'000'000LL, 1, varied_blocks(1000, false));

  auto short_packet = good;
  short_packet.pop_back();
  EXPECT_EQ(dec.feed(short_packet), PacketKind::Rejected);
  auto long_packet = good;
  long_packet.push_back(0);
  EXPECT_EQ(dec.feed(long_packet), PacketKind::Rejected);
  EXPECT_EQ(dec.feed(std::span<const std::uint8_t>()), PacketKind::Rejected);

  auto bad_magic = good;
  bad_magic[2] = 0x00;
  EXPECT_EQ(dec.feed(bad_magic), PacketKind::Rejected);

  auto bad_azimuth = good;
  store_be16(bad_azimuth.data() + 42 + 3 * 100 + 2, 36000);
  EXPECT_EQ(dec.feed(bad_azimuth), PacketKind::Rejected);

  auto bad_time = good;
  store_be32(bad_time.data() + 26, 1'000'000);
  EXPECT_EQ(dec.feed(bad_time), PacketKind::Rejected);

  auto broken_first = good;
  broken_first[42] = 0x00;
  EXPECT_EQ(dec.feed(broken_first), PacketKind::Rejected);

  auto difop_short = test::make_difop(kVert, kHoriz, 4);
  difop_short.resize(1000);
  EXPECT_EQ(dec.feed(difop_short), PacketKind::Rejected);

  const HeliosStats s = dec.stats();
  EXPECT_EQ(s.wrong_size, 4U);
  EXPECT_EQ(s.bad_magic, 1U);
  EXPECT_EQ(s.bad_azimuth, 1U);
  EXPECT_EQ(s.bad_timestamp, 1U);
  EXPECT_EQ(s.broken_first_block, 1U);
  EXPECT_EQ(s.rejected(), 8U);
  EXPECT_EQ(s.msop, 0U);
}

// Found with fuzz_rs_helios (a seed given extreme arrival times): on the arrival-time clock, a
// capture time near the int64 limits (a pcapng's timestamps can say anything) overflowed the packet
// time arithmetic, undefined behaviour. Such packets are now refused as bad timestamps.
TEST(RsHeliosSynthetic, ArrivalTimesOutsideTheTimestampRangeAreRefused) {
  HeliosOptions o;
  o.angles = table_5515();
  o.msop.time_source = TimeSource::ArrivalTime;
  std::vector<double> sweep_starts;
  RsHeliosDecoder dec(o, [&](Scan& scan, const SweepInfo&) { sweep_starts.push_back(scan.start_time); });
  const auto packet = test::make_msop(1'700'000'000'000'000LL, 1, varied_blocks(35900, false));
  constexpr std::int64_t kMaxNs = static_cast<std::int64_t>(helios::kMaxTimestampSeconds) * 1'000'000'000LL;
  for (const std::int64_t arrival : {std::numeric_limits<std::int64_t>::min() + 5, std::int64_t{-1}, kMaxNs + 1,
                                     std::numeric_limits<std::int64_t>::max() - 16})
    EXPECT_EQ(dec.feed(packet, arrival), PacketKind::Rejected) << arrival;
  EXPECT_EQ(dec.stats().bad_timestamp, 4U);
  // The bounds themselves are accepted, and a step from one to an ordinary time is just a gap.
  EXPECT_EQ(dec.feed(packet, kMaxNs), PacketKind::Msop);
  EXPECT_EQ(dec.feed(packet, 1'700'000'000'000'000'000LL), PacketKind::Msop);
  EXPECT_EQ(dec.stats().time_gaps, 1U);
  ASSERT_FALSE(sweep_starts.empty());
  for (const double t : sweep_starts) EXPECT_TRUE(std::isfinite(t));
}

TEST(RsHeliosSynthetic, BrokenBlockFlagKeepsTheBlocksBeforeIt) {
  const MsopDecoder dec = decoder_5515();
  const auto blocks = varied_blocks(1000, false);
  auto packet = test::make_msop(1'700'000'000'000'000LL, 1, blocks);
  packet[42 + 5 * 100 + 1] = 0xEF;  // block 5's flag broken
  auto out = std::make_unique<PacketPoints>();
  MsopHeader header;
  ASSERT_EQ(dec.decode(packet, false, 0, *out, header), MsopStatus::Partial);
  EXPECT_EQ(out->block_count, 5U);
  EXPECT_EQ(out->point_count, 5U * 30U);
  // The last kept block uses the nominal 0.2° step (§3.2): its geometry is unchanged here.
  const std::size_t s = 31;
  const Expected e = expected_point(blocks[4].azimuth, 20, helios::kFiringOffsetsUs[s], 4 * kT,
                                    blocks[4].raw_distance[s] * 0.0025, s, ring_5515(s), 0, blocks[4].intensity[s]);
  expect_point(out->points[out->point_count - 1], e, "last point");

  HeliosOptions o;
  o.angles = table_5515();
  RsHeliosDecoder stream(o, [](Scan&, const SweepInfo&) {});
  EXPECT_EQ(stream.feed(packet), PacketKind::Msop);
  EXPECT_EQ(stream.stats().broken_block_flag, 1U);
  EXPECT_EQ(stream.stats().points, 150U);
}

TEST(RsHeliosSynthetic, RandomGarbageNeverCrashes) {
  HeliosOptions o;
  o.angles = table_5515();
  RsHeliosDecoder dec(o, [](Scan&, const SweepInfo&) {});
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<std::uint8_t> p(helios::kPacketBytes);
  for (int i = 0; i < 2000; ++i) {
    for (auto& b : p) b = static_cast<std::uint8_t>(byte(rng));
    if (i % 2 == 0) std::copy(helios::kMsopMagic.begin(), helios::kMsopMagic.end(), p.begin());
    if (i % 4 == 1) std::copy(helios::kDifopMagic.begin(), helios::kDifopMagic.end(), p.begin());
    if (i % 3 == 0)
      for (std::size_t k = 0; k < 12; ++k) {
        p[42 + k * 100] = 0xFF;
        p[43 + k * 100] = 0xEE;
      }
    dec.feed(std::span<const std::uint8_t>(p.data(), i % 5 == 0 ? p.size() - static_cast<std::size_t>(i % 7) : p.size()));
  }
  dec.flush();
  const HeliosStats s = dec.stats();
  EXPECT_EQ(s.msop + s.difop + s.rejected(), 2000U);
}

TEST(RsHeliosSynthetic, DifopAnglesUseTheSignByteEncoding) {
  const std::vector<double> vert = {-54.6, 14.94, 0.0, -0.01};
  const std::vector<double> horiz = {4.8, -4.07, 0.0, 179.99};
  auto packet = test::make_difop(vert, horiz, helios::kReturnStrongest, 1200);
  // Any non-zero sign byte means negative (§6), not only 0x01.
  packet[468 + 3 * 3] = 0x80;
  HeliosDifop d;
  ASSERT_EQ(parse_difop(packet, d), DifopStatus::Ok);
  ASSERT_TRUE(d.angles_valid) << d.angles_rejected_reason;
  EXPECT_DOUBLE_EQ(d.angles.vertical_deg[0], -54.6);
  EXPECT_DOUBLE_EQ(d.angles.vertical_deg[1], 14.94);
  EXPECT_DOUBLE_EQ(d.angles.vertical_deg[3], -0.01);
  EXPECT_DOUBLE_EQ(d.angles.horizontal_deg[1], -4.07);
  EXPECT_DOUBLE_EQ(d.angles.horizontal_deg[3], 179.99);  // [−90°, 180°) accepts it
  EXPECT_DOUBLE_EQ(d.rotation_hz(), 20.0);
  const std::uint8_t bytes[3] = {0x01, 0x05, 0xD6};
  EXPECT_DOUBLE_EQ(decode_calibration_angle(bytes), -14.94);
}

TEST(RsHeliosSynthetic, DifopAngleTableRejectionRules) {
  struct Case {
    const char* name;
    std::size_t offset;
    std::uint8_t b0, b1, b2;
  };
  const Case cases[] = {
      {"0xFF vertical sign (unprogrammed)", 468 + 5 * 3, 0xFF, 0x00, 0x10},
      {"0xFF horizontal sign", 564 + 31 * 3, 0xFF, 0xFF, 0xFF},
      {"180.00 degrees", 564 + 2 * 3, 0x00, 0x46, 0x50},
      {"-90.01 degrees", 468, 0x01, 0x23, 0x29},
  };
  for (const Case& c : cases) {
    auto packet = test::make_difop(kVert, kHoriz, helios::kReturnStrongest);
    packet[c.offset] = c.b0;
    packet[c.offset + 1] = c.b1;
    packet[c.offset + 2] = c.b2;
    HeliosDifop d;
    ASSERT_EQ(parse_difop(packet, d), DifopStatus::Ok) << c.name;
    EXPECT_FALSE(d.angles_valid) << c.name;
    EXPECT_NE(std::string(d.angles_rejected_reason), "") << c.name;
    EXPECT_EQ(d.motor_rpm, 600) << c.name;  // the rest of the packet still parses
  }
  // A rejected DIFOP table leaves the CSV table in use; the first valid one replaces it, from the
  // next sweep on (no sweep is decoded with two tables), and is no change of calibration.
  HeliosOptions o;
  o.angles = table_5515();
  o.emit_partial_sweep_on_flush = true;
  std::vector<Scan> sweeps;
  RsHeliosDecoder dec(o, [&](Scan& s, const SweepInfo&) { sweeps.push_back(s); });
  auto unprogrammed = test::make_difop(std::vector<double>(32, 1.0), kHoriz, helios::kReturnStrongest);
  unprogrammed[468] = 0xFF;
  dec.feed(unprogrammed);
  EXPECT_EQ(dec.stats().difop_angles_rejected, 1U);
  std::array<SyntheticBlock, 12> blocks{};
  blocks[0].raw_distance[0] = 4000;  // 10 m on slot 0: 14.94° from the CSV
  auto packet_from = [&](std::uint16_t azimuth, std::uint32_t counter) {
    for (std::size_t k = 0; k < 12; ++k) blocks[k].azimuth = static_cast<std::uint16_t>(azimuth + 20 * k);
    return test::make_msop(1'000'000 + 667 * counter, counter, blocks);
  };
  dec.feed(packet_from(35520, 0));
  dec.feed(test::make_difop(std::vector<double>(32, -5.0), std::vector<double>(32, 0.0), helios::kReturnStrongest));
  dec.feed(packet_from(35760, 1));  // the same sweep: still the CSV's
  dec.feed(packet_from(0, 2));      // past the split: -5°
  dec.flush();
  ASSERT_EQ(sweeps.size(), 2U);
  ASSERT_EQ(sweeps[0].points.size(), 2U);
  ASSERT_EQ(sweeps[1].points.size(), 1U);
  for (const LidarPoint& p : sweeps[0].points) EXPECT_NEAR(p.z, 10.0 * std::sin(14.94 * std::numbers::pi / 180.0), 1e-4);
  EXPECT_NEAR(sweeps[1].points[0].z, 10.0 * std::sin(-5.0 * std::numbers::pi / 180.0), 1e-4);
  EXPECT_EQ(dec.stats().calibration_changes, 0U);
}

TEST(RsHeliosSynthetic, AngleTableMustFitTheModel) {
  HeliosOptions o;
  o.model = HeliosModel::Helios5515;
  o.angles = AngleTable{std::vector<double>(16, 0.0), std::vector<double>(16, 0.0)};
  EXPECT_THROW(RsHeliosDecoder(o, [](Scan&, const SweepInfo&) {}), InputError);
  o.model = HeliosModel::Helios16P;
  EXPECT_NO_THROW(RsHeliosDecoder(o, [](Scan&, const SweepInfo&) {}));
}

TEST(RsHeliosSynthetic, NothingIsDecodedWithoutCalibration) {
  HeliosOptions o;  // no CSV, no DIFOP yet
  RsHeliosDecoder dec(o, [](Scan&, const SweepInfo&) {});
  EXPECT_EQ(dec.feed(test::make_msop(1'000'000, 1, varied_blocks(0, false))), PacketKind::Rejected);
  EXPECT_EQ(dec.stats().no_calibration, 1U);
}

// Live, MSOP and DIFOP come on two sockets: packets that raced ahead of the first DIFOP are held
// and decoded once it arrives, giving exactly the sweeps of the capture's DIFOP-first order.
TEST(RsHeliosSynthetic, MsopBeforeTheFirstDifopIsHeldAndDecodedAfterIt) {
  std::vector<std::vector<std::uint8_t>> msop;
  // 2.4° per packet from 350°: the sweep wraps at 0° after 5 packets.
  for (int k = 0; k < 12; ++k) {
    msop.push_back(test::make_msop(1'700'000'000'000'000LL + 667LL * k, static_cast<std::uint32_t>(k + 1),
                                   varied_blocks(static_cast<std::uint16_t>((35000 + 240 * k) % 36000), false)));
  }
  const auto difop = test::make_difop(kVert, kHoriz, helios::kReturnStrongest);
  auto decode = [&](std::size_t difop_after, std::size_t max_held) {
    HeliosOptions o;
    o.max_held_packets = max_held;
    o.emit_partial_sweep_on_flush = true;
    std::vector<Scan> sweeps;
    RsHeliosDecoder dec(o, [&](Scan& s, const SweepInfo&) { sweeps.push_back(s); });
    for (std::size_t k = 0; k <= msop.size(); ++k) {
      if (k == difop_after) dec.feed(difop);
      if (k < msop.size()) dec.feed(msop[k]);
    }
    dec.flush();
    return std::make_pair(sweeps, dec.stats());
  };
  const auto [reference, reference_stats] = decode(0, 0);
  const auto [raced, raced_stats] = decode(3, 8);
  ASSERT_EQ(reference.size(), 2U);
  ASSERT_EQ(raced.size(), reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    EXPECT_EQ(raced[i].start_time, reference[i].start_time);
    EXPECT_EQ(raced[i].end_time, reference[i].end_time);
    ASSERT_EQ(raced[i].points.size(), reference[i].points.size());
    EXPECT_EQ(raced[i].points.back().x, reference[i].points.back().x);
  }
  EXPECT_EQ(raced_stats.held_for_calibration, 3U);
  EXPECT_EQ(raced_stats.msop, reference_stats.msop);
  EXPECT_EQ(raced_stats.no_calibration, 0U);
  // Bounded: past the limit they are refused as before.
  const auto [short_of_room, short_stats] = decode(3, 2);
  EXPECT_EQ(short_stats.held_for_calibration, 2U);
  EXPECT_EQ(short_stats.no_calibration, 1U);
  EXPECT_EQ(short_stats.msop, reference_stats.msop - 1);
}

}  // namespace
}  // namespace liod::drivers
