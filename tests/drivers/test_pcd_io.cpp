#include <gtest/gtest.h>

#include <fstream>

#include "liod/drivers/input_error.hpp"
#include "liod/drivers/pcd_io.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

TEST(PcdIo, BinaryScanRoundTrips) {
  test::TempDir dir;
  Scan scan;
  scan.sequence = 42;
  scan.start_time = 1483724884.201573;
  scan.end_time = scan.start_time + 0.1;
  scan.beam_count = 32;
  for (int i = 0; i < 1000; ++i)
    scan.points.push_back(LidarPoint{0.001F * i, -2.5F + 0.01F * i, 1e-3F * (i % 7), static_cast<float>(i % 256),
                                     1e-4F * i, static_cast<std::uint16_t>(i % 32), 0});
  write_pcd_binary(dir / "s.pcd", scan);
  const PcdCloud cloud = read_pcd(dir / "s.pcd");
  ASSERT_EQ(cloud.fields, (std::vector<std::string>{"x", "y", "z", "intensity", "time", "ring"}));
  ASSERT_EQ(cloud.points(), scan.points.size());
  EXPECT_EQ(cloud.width, 1000U);
  EXPECT_EQ(cloud.height, 1U);
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    const LidarPoint& p = scan.points[i];
    EXPECT_EQ(cloud.value(i, 0), p.x);
    EXPECT_EQ(cloud.value(i, 1), p.y);
    EXPECT_EQ(cloud.value(i, 2), p.z);
    EXPECT_EQ(cloud.value(i, 3), p.intensity);
    EXPECT_EQ(cloud.value(i, 4), p.time);
    EXPECT_EQ(cloud.value(i, 5), p.ring);
  }
  const auto pts = read_pcd_points(dir / "s.pcd");
  EXPECT_EQ(pts[33].channel, 1);
  EXPECT_FLOAT_EQ(static_cast<float>(pts[10].time_stamp), 1e-3F);
  // Header lines PCL requires, with the sweep's absolute times in a comment.
  std::ifstream in(dir / "s.pcd");
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(first, "# .PCD v0.7 - Point Cloud Data file format");
  const auto at = second.find("start_time=");
  ASSERT_NE(at, std::string::npos) << second;
  EXPECT_NEAR(std::stod(second.substr(at + 11)), scan.start_time, 1e-6) << second;

  Scan empty;
  write_pcd_binary(dir / "e.pcd", empty);
  EXPECT_EQ(read_pcd(dir / "e.pcd").points(), 0U);
}

TEST(PcdIo, ReadsTheReferenceHelios32Clouds) {
  const auto dir = test::robosense_dir() / "helios32_decoded";
  LIOD_REQUIRE_SHARED(dir);
  const auto pts = read_pcd_points(dir / "1691141763462381376.pcd");
  ASSERT_EQ(pts.size(), 37508U);  // README: 37,508 returns in the first scan
  // First row: 0.23427171 -0.013176575 0.046219546 6 3 30 376 1303 0.205 1483229792
  EXPECT_FLOAT_EQ(pts[0].x, 0.23427171F);
  EXPECT_FLOAT_EQ(pts[0].y, -0.013176575F);
  EXPECT_FLOAT_EQ(pts[0].intensity, 6.0F);
  EXPECT_EQ(pts[0].channel, 30);
  EXPECT_EQ(pts[0].time_stamp, 1483229792.0);
  std::uint16_t max_channel = 0;
  for (const auto& p : pts) max_channel = std::max(max_channel, p.channel);
  EXPECT_EQ(max_channel, 31);
  const PcdCloud cloud = read_pcd(dir / "1691141763462381376.pcd");
  EXPECT_EQ(cloud.field_index("elevation"), 7);
  EXPECT_EQ(cloud.value(0, 7), 1303.0);
}

TEST(PcdIo, MalformedFilesThrowNamingTheFile) {
  test::TempDir dir;
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return dir / name;
  };
  const std::string header = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
  EXPECT_NO_THROW((void)read_pcd(write("ok.pcd", header + "DATA ascii\n1 2 3\n4 5 6\n")));
  try {
    (void)read_pcd(write("bad.pcd", header + "DATA ascii\n1 2 3\n4 five 6\n"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.pcd:11"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)read_pcd(write("short.pcd", header + "DATA ascii\n1 2 3\n")), InputError);
  EXPECT_THROW((void)read_pcd(write("shortbin.pcd", header + "DATA binary\n123")), InputError);
  EXPECT_THROW((void)read_pcd(write("lzf.pcd", header + "DATA binary_compressed\n")), InputError);
  EXPECT_THROW((void)read_pcd(write("nodata.pcd", header)), InputError);
  EXPECT_THROW((void)read_pcd_points(write("noxyz.pcd", "FIELDS a\nSIZE 4\nTYPE F\nCOUNT 1\nPOINTS 1\nDATA ascii\n1\n")),
               InputError);
}

}  // namespace
}  // namespace liod::drivers
