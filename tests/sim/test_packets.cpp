// The capture follows the RS-Helios spec, read back with the test's own minimal reader.

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "helios_reader.hpp"
#include "sim_test_util.hpp"

namespace liod::sim::test {
namespace {

struct Capture {
  std::vector<UdpRecord> msop;
  std::vector<UdpRecord> difop;
  double offset = 0.0;
};

Capture run(bool dual, const std::string& name) {
  const std::string dir = scratch_dir(name);
  SimConfig c = short_config(RouteKind::Urban, 3, 2.5, dir);
  c.dual_return = dual;
  const Simulation sim(c);
  sim.write_all();
  Capture cap;
  cap.offset = sim.time_offset();
  for (auto& r : read_pcap(dir + "/lidar.pcap")) {
    (r.dst_port == 6699 ? cap.msop : cap.difop).push_back(std::move(r));
  }
  return cap;
}

void check_stream(const Capture& cap, bool dual) {
  ASSERT_GT(cap.msop.size(), 3000U);
  const std::uint8_t lidar_ip[4] = {192, 168, 1, 200};
  const std::uint8_t host_ip[4] = {192, 168, 1, 102};
  std::map<std::uint64_t, int> per_100ms;
  int prev_az = -1;
  std::uint64_t prev_time = 0;
  std::uint32_t prev_counter = 0;
  std::uint64_t prev_record = 0;
  for (std::size_t i = 0; i < cap.msop.size(); ++i) {
    const auto& r = cap.msop[i];
    const auto& p = r.payload;
    ASSERT_EQ(p.size(), 1248U);
    ASSERT_TRUE(std::equal(lidar_ip, lidar_ip + 4, r.src_ip.begin()));
    ASSERT_TRUE(std::equal(host_ip, host_ip + 4, r.dst_ip.begin()));
    ASSERT_EQ(r.src_port, 6699);
    ASSERT_EQ(p[0], 0x55);
    ASSERT_EQ(p[1], 0xAA);
    ASSERT_EQ(p[2], 0x05);
    ASSERT_EQ(p[3], 0x5A);
    ASSERT_EQ(p[17], 0x01) << "range resolution flag must say 2.5 mm";
    ASSERT_EQ(p[1246], 0x00);
    ASSERT_EQ(p[1247], 0xFF);
    const std::uint32_t counter = rd_be32(p.data() + 12);
    const std::uint64_t t = header_time_us(p.data() + 20);
    if (i > 0) {
      ASSERT_EQ(counter, prev_counter + 1);
      // 12 firings (6 in dual mode) of 55.556 us each, truncated to whole microseconds.
      const std::uint64_t dt = t - prev_time;
      if (dual) {
        ASSERT_TRUE(dt == 333 || dt == 334) << dt;
      } else {
        ASSERT_TRUE(dt == 666 || dt == 667) << dt;
      }
      ASSERT_GE(r.record_us, prev_record);
    }
    // Captured on the host once the packet is complete, after a sub-millisecond network delay.
    const double lag = static_cast<double>(r.record_us) - static_cast<double>(t) - cap.offset * 1e6;
    ASSERT_GT(lag, dual ? 333.0 : 666.0);
    ASSERT_LT(lag, 3000.0);
    prev_counter = counter;
    prev_time = t;
    prev_record = r.record_us;
    ++per_100ms[t / 100000U];
    const double temp = ((p[39] & 0x7F) << 5 | p[38] >> 3) * 0.0625;
    ASSERT_GT(temp, 20.0);
    ASSERT_LT(temp, 70.0);
    for (int b = 0; b < 12; ++b) {
      const std::uint8_t* blk = p.data() + 42 + 100 * b;
      ASSERT_EQ(blk[0], 0xFF);
      ASSERT_EQ(blk[1], 0xEE);
      const int az = rd_be16(blk + 2);
      ASSERT_LT(az, 36000);
      if (dual && b % 2 == 1) {
        ASSERT_EQ(az, prev_az) << "dual-return blocks come in pairs of equal azimuth";
        continue;
      }
      if (prev_az >= 0) {
        ASSERT_EQ((az - prev_az + 36000) % 36000, 20) << "packet " << i << " block " << b;
      }
      prev_az = az;
    }
  }
  // Whole 100 ms windows hold one revolution: 150 packets (300 in dual mode).
  const int expected = dual ? 300 : 150;
  int full = 0;
  for (auto it = std::next(per_100ms.begin()); it != per_100ms.end(); ++it) {
    if (std::next(it) == per_100ms.end()) {
      break;
    }
    EXPECT_NEAR(it->second, expected, 1) << "window " << it->first;
    ++full;
  }
  EXPECT_GE(full, 20);
}

void check_difop(const Capture& cap, bool dual) {
  // About 1 Hz: at 0.3 s and 1.3 s and 2.3 s of a 2.5 s drive.
  ASSERT_EQ(cap.difop.size(), 3U);
  std::array<double, 32> vert{};
  std::array<double, 32> horiz{};
  {
    std::ifstream in(angles_csv());
    std::string line;
    for (std::size_t c = 0; c < 32 && std::getline(in, line); ++c) {
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream ls(line);
      ls >> vert[c] >> horiz[c];
    }
  }
  std::uint64_t prev = 0;
  for (const auto& r : cap.difop) {
    const auto& p = r.payload;
    ASSERT_EQ(p.size(), 1248U);
    ASSERT_EQ(r.src_port, 7788);
    const std::uint8_t magic[8] = {0xA5, 0xFF, 0x00, 0x5A, 0x11, 0x11, 0x55, 0x55};
    ASSERT_TRUE(std::equal(magic, magic + 8, p.begin()));
    EXPECT_EQ(rd_be16(p.data() + 8), 600);
    EXPECT_EQ(rd_be16(p.data() + 32), 0);
    EXPECT_EQ(rd_be16(p.data() + 34), 36000);
    EXPECT_EQ(p[300], dual ? 0x00 : 0x04);
    EXPECT_EQ(p[302], 2);
    const std::uint64_t t = header_time_us(p.data() + 303);
    if (prev != 0) {
      EXPECT_NEAR(static_cast<double>(t - prev) * 1e-6, 1.0, 0.01);
    }
    prev = t;
    for (std::size_t c = 0; c < 32; ++c) {
      for (int table = 0; table < 2; ++table) {
        const std::uint8_t* a = p.data() + (table == 0 ? 468 : 564) + 3 * c;
        const double mag = rd_be16(a + 1) * 0.01;
        const double v = a[0] == 0 ? mag : -mag;
        EXPECT_NEAR(v, table == 0 ? vert[c] : horiz[c], 0.0051) << "channel " << c;
      }
    }
  }
}

TEST(SimPackets, SingleReturnStreamFollowsSpec) {
  LIOD_SIM_REQUIRE_SHARED();
  const Capture cap = run(false, "pk-single");
  check_stream(cap, false);
  check_difop(cap, false);
}

TEST(SimPackets, DualReturnStreamFollowsSpec) {
  LIOD_SIM_REQUIRE_SHARED();
  const Capture cap = run(true, "pk-dual");
  check_stream(cap, true);
  check_difop(cap, true);
}

TEST(SimPackets, ReturnsLookLikeAStreetScan) {
  LIOD_SIM_REQUIRE_SHARED();
  const Capture cap = run(false, "pk-scan");
  std::array<double, 32> vert{};
  std::array<double, 32> horiz{};
  std::vector<DecodedPoint> pts;
  for (std::size_t i = 150; i < 300; ++i) {
    decode_msop(cap.msop[i].payload, vert, horiz, pts);
  }
  // Some but not all beams return (sky, glass, dark paint, grazing ground); intensities vary.
  EXPECT_GT(pts.size(), 0.4 * 57600);
  EXPECT_LT(pts.size(), 0.98 * 57600);
  int far = 0;
  int bright = 0;
  for (const auto& p : pts) {
    far += p.range > 30.0 ? 1 : 0;
    bright += p.intensity > 150 ? 1 : 0;
    ASSERT_LE(p.range, 150.0);
    ASSERT_GE(p.range, 0.2);
  }
  EXPECT_GT(far, 500);
  EXPECT_LT(bright, static_cast<int>(pts.size() / 20));
}

}  // namespace
}  // namespace liod::sim::test
