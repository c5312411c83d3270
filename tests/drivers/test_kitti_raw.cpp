// KITTI raw files: timestamps, OXTS lines, the IMU-to-Velodyne calibration, the sweep list.

#include <gtest/gtest.h>

#include <fstream>

#include "liod/drivers/input_error.hpp"
#include "liod/drivers/kitti_raw.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

TEST(KittiRaw, TimestampsAreSecondsSince1970WithTheirNanoseconds) {
  // 2011-09-26 is day 15243 after 1970-01-01.
  EXPECT_DOUBLE_EQ(parse_kitti_timestamp("2011-09-26 13:02:25.964389445", "t", 1), 15243.0 * 86400 + 46945.964389445);
  EXPECT_DOUBLE_EQ(parse_kitti_timestamp("2012-03-01 00:00:00", "t", 1) - parse_kitti_timestamp("2012-02-28 00:00:00", "t", 1),
                   2.0 * 86400);  // a leap year's February
  try {
    (void)parse_kitti_timestamp("2011-09-26 13:02", "velodyne_points/timestamps.txt", 7);
    FAIL() << "a short timestamp was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("velodyne_points/timestamps.txt:7"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)parse_kitti_timestamp("2011-13-26 13:02:25.1", "t", 1), InputError);
  EXPECT_THROW((void)parse_kitti_timestamp("2011-09-26 -1:02:25.1", "t", 1), InputError);
  EXPECT_THROW((void)parse_kitti_timestamp("", "t", 1), InputError);
}

TEST(KittiRaw, OxtsLinesGiveTheBodyRatesAndAccelerations) {
  std::string line;
  for (int f = 0; f < 30; ++f) line += std::to_string(f) + ".5 ";
  const ImuSample s = parse_oxts_line(line, 12.0, "oxts.txt");
  EXPECT_EQ(s.time, 12.0);
  EXPECT_EQ(s.accel, Eigen::Vector3d(11.5, 12.5, 13.5));  // ax ay az
  EXPECT_EQ(s.gyro, Eigen::Vector3d(17.5, 18.5, 19.5));   // wx wy wz
  EXPECT_THROW((void)parse_oxts_line("1 2 3", 0.0, "oxts.txt"), InputError);
  EXPECT_THROW((void)parse_oxts_line(line + "x", 0.0, "oxts.txt"), InputError);
  std::string not_finite;
  for (int f = 0; f < 30; ++f) not_finite += f == 18 ? "nan " : "0 ";
  EXPECT_THROW((void)parse_oxts_line(not_finite, 0.0, "oxts.txt"), InputError);
}

TEST(KittiRaw, TheCalibrationIsReadFromTheDriveOrItsDateFolder) {
  test::TempDir dir;
  const auto drive = dir / "2011_09_26_drive_0001_extract";
  std::filesystem::create_directories(drive);
  std::ofstream(dir / "calib_imu_to_velo.txt") << "calib_time: 25-May-2012 16:47:16\n"
                                                   "R: 1 0 0 0 1 0 0 0 1\nT: -0.81 0.32 -0.8\n";
  const Eigen::Isometry3d m = read_kitti_imu_to_velo(drive);
  EXPECT_TRUE(m.linear().isIdentity());
  EXPECT_EQ(m.translation(), Eigen::Vector3d(-0.81, 0.32, -0.8));
  std::ofstream(drive / "calib_imu_to_velo.txt") << "R: 1 0 0\nT: 0 0 0\n";
  EXPECT_THROW((void)read_kitti_imu_to_velo(drive), InputError);  // the drive's own file comes first
}

TEST(KittiRaw, TheSweepListNeedsEveryListedFile) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "velodyne_points" / "data");
  std::ofstream(dir / "velodyne_points" / "timestamps_start.txt") << "2011-09-26 13:02:25.0\n2011-09-26 13:02:25.1\n";
  std::ofstream(dir / "velodyne_points" / "timestamps_end.txt") << "2011-09-26 13:02:25.1\n2011-09-26 13:02:25.2\n";
  std::ofstream(dir / "velodyne_points" / "data" / "0000000000.bin");
  EXPECT_THROW((void)read_kitti_sweep_list(dir.path()), InputError);
  std::ofstream(dir / "velodyne_points" / "data" / "0000000001.bin");
  const auto sweeps = read_kitti_sweep_list(dir.path());
  ASSERT_EQ(sweeps.size(), 2U);
  EXPECT_NEAR(sweeps[1].end_s - sweeps[1].start_s, 0.1, 1e-6);
}

TEST(KittiRaw, TheBeamTableIsTheHdl64eNominalOne) {
  const auto e = hdl64e_elevations_deg();
  ASSERT_EQ(e.size(), 64U);
  EXPECT_DOUBLE_EQ(e.front(), 2.0);
  EXPECT_NEAR(e[31], -8.333, 1e-3);
  EXPECT_DOUBLE_EQ(e[32], -8.83);
  EXPECT_NEAR(e.back(), -24.33, 1e-9);
  EXPECT_FALSE(kitti_cloud_config().clockwise);
  EXPECT_EQ(kitti_cloud_config().start_azimuth_deg, 180.0);
}

}  // namespace
}  // namespace liod::drivers
