// The point-cloud input path: rings recovered from elevation, times from azimuth, the binary point
// records' parsing and errors, and the Ouster metadata reader's errors.

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <fstream>
#include <numbers>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/cloud_sweep.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/ouster_sample.hpp"
#include "liod/drivers/point_records.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

LidarPoint at(double range, double elevation_deg, double azimuth_deg) {
  LidarPoint p;
  p.x = static_cast<float>(range * std::cos(elevation_deg * kDeg) * std::cos(azimuth_deg * kDeg));
  p.y = static_cast<float>(range * std::cos(elevation_deg * kDeg) * std::sin(azimuth_deg * kDeg));
  p.z = static_cast<float>(range * std::sin(elevation_deg * kDeg));
  return p;
}

TEST(CloudSweep, RingsComeFromTheNearestBeamElevationLowestFirst) {
  CloudScanConfig config;
  config.beam_elevations_deg = {2.0, -8.0, -24.0, -3.0};  // any order
  config.max_elevation_error_deg = 0.5;
  CloudSweep sweep;
  sweep.has_time = true;
  for (const double e : {-24.2, -7.9, -3.1, 1.8, 5.0}) sweep.points.push_back(at(20.0, e, 30.0));
  CloudScanStats stats;
  const Scan scan = make_scan(sweep, config, &stats);
  EXPECT_EQ(scan.beam_count, 4);
  ASSERT_EQ(scan.points.size(), 4U);
  EXPECT_EQ(stats.no_beam, 1U);  // 5 deg: 3 deg above the highest beam
  for (std::uint16_t k = 0; k < 4; ++k) EXPECT_EQ(scan.points[k].ring, k);
}

TEST(CloudSweep, ElevationIsTakenFromTheBeamsOriginNotTheAxis) {
  // An Ouster-like head: beams leave 15.8 mm out from the axis, the head sits 36 mm above the
  // cloud's origin. Two beams 0.35 deg apart, a return 2 m out on the lower one.
  CloudScanConfig config;
  config.beam_elevations_deg = {20.0, 20.35};
  config.beam_origin_offset_m = 0.0158;
  config.head_in_cloud.translation() = Eigen::Vector3d(0.0, 0.0, 0.036);
  const double e = 20.0 * kDeg;
  CloudSweep sweep;
  sweep.has_time = true;
  LidarPoint p;
  p.x = static_cast<float>(0.0158 + 2.0 * std::cos(e));
  p.z = static_cast<float>(0.036 + 2.0 * std::sin(e));
  sweep.points.push_back(p);
  EXPECT_EQ(make_scan(sweep, config).points.at(0).ring, 0);
  // Seen from the cloud's origin it is at 20.8 deg: the upper beam's.
  config.head_in_cloud = Eigen::Isometry3d::Identity();
  config.beam_origin_offset_m = 0.0;
  EXPECT_EQ(make_scan(sweep, config).points.at(0).ring, 1) << "the head's geometry made no difference";
}

TEST(CloudSweep, TimesComeFromTheAzimuthTurningClockwiseFromTheStart) {
  CloudScanConfig config;
  config.beam_elevations_deg = {0.0};
  config.sweep_period_s = 0.1;
  config.start_azimuth_deg = 180.0;  // behind, as KITTI's sweeps begin
  CloudSweep sweep;
  sweep.start_time = 50.0;
  // Clockwise from behind: left (90 deg) a quarter turn on, ahead half, right three quarters.
  for (const double az : {-90.0, 0.0, 90.0, 179.0}) sweep.points.push_back(at(10.0, 0.0, az));
  const Scan scan = make_scan(sweep, config);
  ASSERT_EQ(scan.points.size(), 4U);
  // Sorted into firing order: 179 deg (just after the start), 90, 0, -90.
  EXPECT_NEAR(scan.points[0].time, 0.1 * 1.0 / 360.0, 1e-6);
  EXPECT_NEAR(scan.points[1].time, 0.025, 1e-6);
  EXPECT_NEAR(scan.points[2].time, 0.05, 1e-6);
  EXPECT_NEAR(scan.points[3].time, 0.075, 1e-6);
  EXPECT_GT(scan.points[1].y, 0.0F);
  EXPECT_DOUBLE_EQ(scan.end_time, 50.1);
  config.clockwise = false;
  const Scan ccw = make_scan(sweep, config);
  EXPECT_NEAR(ccw.points[0].time, 0.025, 1e-6);  // -90 deg first
  EXPECT_LT(ccw.points[0].y, 0.0F);
}

TEST(CloudSweep, AGivenRingAndTimeAreKept) {
  CloudSweep sweep;
  sweep.has_time = true;
  sweep.has_ring = true;
  sweep.start_time = 1.0;
  LidarPoint a = at(5.0, 10.0, 0.0);
  a.ring = 7;
  a.time = 0.02F;
  LidarPoint b = at(5.0, -10.0, 0.0);
  b.ring = 2;
  b.time = 0.01F;
  sweep.points = {a, b};
  const Scan scan = make_scan(sweep, CloudScanConfig{});
  EXPECT_EQ(scan.beam_count, 8);
  EXPECT_EQ(scan.points[0].ring, 2);
  EXPECT_EQ(scan.points[1].ring, 7);
  EXPECT_DOUBLE_EQ(scan.end_time, 1.0 + static_cast<double>(0.02F));
}

TEST(CloudSweep, NoRingsAndNoBeamTableIsAnError) {
  CloudSweep sweep;
  sweep.points.push_back(at(5.0, 0.0, 0.0));
  EXPECT_THROW((void)make_scan(sweep, CloudScanConfig{}), std::invalid_argument);
}

std::vector<std::uint8_t> records(const std::vector<float>& values) {
  std::vector<std::uint8_t> bytes(values.size() * 4);
  for (std::size_t i = 0; i < values.size(); ++i) store_le32(bytes.data() + 4 * i, std::bit_cast<std::uint32_t>(values[i]));
  return bytes;
}

TEST(PointRecords, ParsesLittleEndianFloat32Records) {
  const auto bytes = records({1.5F, -2.0F, 0.25F, 40.0F, 3.0F, 4.0F, 5.0F, 6.0F});
  const auto points = parse_point_records(bytes, kKittiVelodyneLayout, "two.bin");
  ASSERT_EQ(points.size(), 2U);
  EXPECT_EQ(points[0].x, 1.5F);
  EXPECT_EQ(points[0].y, -2.0F);
  EXPECT_EQ(points[0].z, 0.25F);
  EXPECT_EQ(points[0].intensity, 40.0F);
  EXPECT_EQ(points[1].intensity, 6.0F);
  const auto timed = parse_point_records(records({1, 2, 3, 4, 0.05F}), kXyziTimeLayout, "t.bin");
  EXPECT_EQ(timed.at(0).time, 0.05F);
}

TEST(PointRecords, ATruncatedFileNamesTheFileAndTheOffset) {
  auto bytes = records({1, 2, 3, 4, 5, 6, 7, 8});
  bytes.resize(bytes.size() - 3);
  try {
    (void)parse_point_records(bytes, kKittiVelodyneLayout, "0000000042.bin");
    FAIL() << "a truncated record was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("0000000042.bin"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("byte offset 16"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)parse_point_records(records({1, 2, 3, 4, -0.5F}), kXyziTimeLayout, "t.bin"), InputError);
  EXPECT_THROW((void)parse_point_records(records({1, 2, 3, 4, NAN}), kXyziTimeLayout, "t.bin"), InputError);
  test::TempDir dir;
  EXPECT_THROW((void)read_point_records(dir / "missing.bin", kKittiVelodyneLayout), InputError);
}

TEST(OusterMetadata, ReadsTheTransformsInMetresAndNamesAMissingKey) {
  test::TempDir dir;
  const auto path = dir / "meta.json";
  std::ofstream(path) << R"({"beam_altitude_angles": [1.0, -1.0], "lidar_origin_to_beam_origin_mm": 15.8,
    "lidar_to_sensor_transform": [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1],
    "imu_to_sensor_transform": [1, 0, 0, 6.253, 0, 1, 0, -11.775, 0, 0, 1, 7.645, 0, 0, 0, 1]})";
  const OusterMetadata m = read_ouster_metadata(path);
  EXPECT_EQ(m.beam_altitude_deg.size(), 2U);
  EXPECT_NEAR(m.beam_origin_offset_m, 0.0158, 1e-12);
  EXPECT_NEAR(m.lidar_to_sensor.translation().z(), 0.03618, 1e-12);
  EXPECT_NEAR(m.lidar_to_sensor.linear()(0, 0), -1.0, 1e-12);
  // A point at the IMU's origin is at the IMU's offset in the sensor frame.
  EXPECT_NEAR((m.sensor_to_imu() * Eigen::Vector3d(0.006253, -0.011775, 0.007645)).norm(), 0.0, 1e-12);
  std::ofstream(path) << R"({"beam_altitude_angles": [1.0], "lidar_origin_to_beam_origin_mm": 15.8})";
  try {
    (void)read_ouster_metadata(path);
    FAIL() << "metadata without transforms was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lidar_to_sensor_transform"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace liod::drivers
