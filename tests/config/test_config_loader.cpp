#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "liod/config.hpp"
#include "scratch_dir.hpp"

namespace {

std::string error_of(const std::string& yaml) {
  try {
    liod::load_config_from_string(yaml, "test.yaml");
  } catch (const liod::ConfigError& e) {
    return e.what();
  }
  return "";
}

std::filesystem::path write_temp(const std::string& name, const std::string& text) {
  const auto path = liod::test::program_scratch_dir() / name;
  std::ofstream(path) << text;
  return path;
}

TEST(ConfigLoader, ShippedConfigLoadsAndMatchesDefaults) {
  const auto config = liod::load_config({std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml"});
  const liod::Config defaults;
  EXPECT_EQ(config.lidar.msop_port, defaults.lidar.msop_port);
  EXPECT_DOUBLE_EQ(config.odometry.hausdorff_threshold_m, defaults.odometry.hausdorff_threshold_m);
  EXPECT_EQ(config.odometry.window_keyframes, 200);
  EXPECT_EQ(config.odometry.deskew, liod::DeskewMode::kImu);
  EXPECT_EQ(config.odometry.beam_range_calibration, defaults.odometry.beam_range_calibration);
  EXPECT_DOUBLE_EQ(config.odometry.post_max_width_m, defaults.odometry.post_max_width_m);
  EXPECT_DOUBLE_EQ(config.odometry.crossing_edge_tolerance_m, defaults.odometry.crossing_edge_tolerance_m);
  EXPECT_EQ(config.lidar.calibration_updates, defaults.lidar.calibration_updates);
  EXPECT_DOUBLE_EQ(config.imu.gyro_range_rad_s, defaults.imu.gyro_range_rad_s);
  EXPECT_DOUBLE_EQ(config.imu.accel_range_m_s2, defaults.imu.accel_range_m_s2);
}

TEST(ConfigLoader, InputHardeningKeys) {
  const auto c = liod::load_config_from_string(
      "lidar:\n  calibration_updates: follow\nimu:\n  gyro_range_rad_s: 8.7\n  accel_range_m_s2: 156.9\n", "t");
  EXPECT_EQ(c.lidar.calibration_updates, liod::CalibrationUpdates::kFollow);
  EXPECT_DOUBLE_EQ(c.imu.gyro_range_rad_s, 8.7);
  EXPECT_DOUBLE_EQ(c.imu.accel_range_m_s2, 156.9);
  EXPECT_EQ(liod::Config{}.lidar.calibration_updates, liod::CalibrationUpdates::kPin);
  // 2000 deg/s and 10 g (Xsens MTi-630), a little above so that a clipped reading is at, not beyond.
  EXPECT_GE(liod::Config{}.imu.gyro_range_rad_s, 2000.0 * M_PI / 180.0);
  EXPECT_GE(liod::Config{}.imu.accel_range_m_s2, 10.0 * 9.80665);
  EXPECT_NE(error_of("lidar:\n  calibration_updates: sometimes\n").find("follow"), std::string::npos);
  // The CAN table profile must map every axis: one it never receives would read 0 as if measured.
  const auto msg = error_of("drivers:\n  imu:\n    transport: can\n    can_profile: table\n    can_signals:\n"
                            "      - {quantity: gyro_x, id: 1}\n");
  EXPECT_NE(msg.find("gyro_y has none"), std::string::npos) << msg;
}

// The advanced keys' example lists every one of them at its default.
TEST(ConfigLoader, AdvancedExampleLoadsAndMatchesDefaults) {
  const auto config = liod::load_config({std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml",
                                         std::string(LIOD_SOURCE_DIR) + "/config/examples/advanced.yaml"});
  const liod::Config defaults;
  EXPECT_DOUBLE_EQ(config.odometry.lidar_noise_m, defaults.odometry.lidar_noise_m);
  EXPECT_DOUBLE_EQ(config.odometry.degeneracy_eigenvalue, defaults.odometry.degeneracy_eigenvalue);
  EXPECT_EQ(config.odometry.map_points_per_voxel, defaults.odometry.map_points_per_voxel);
  EXPECT_DOUBLE_EQ(config.backend.loop_max_rms_m, defaults.backend.loop_max_rms_m);
  EXPECT_EQ(config.threads.scan_ring, defaults.threads.scan_ring);
  EXPECT_DOUBLE_EQ(config.time.offset_window_s, defaults.time.offset_window_s);
}

// Constants that only a simulator with ground truth could tune are not keys: a file that sets
// one is told so rather than silently changing the estimator.
TEST(ConfigLoader, TuningConstantsAreNotKeys) {
  for (const char* key : {"move_off_distance_m", "hold_release_eigenvalue_factor", "held_bias_trim_gain",
                          "max_prediction_nis", "post_depth_m", "surface_end_extrapolation",
                          "standstill_gyro_bias_std"}) {
    const auto msg = error_of(std::string("odometry:\n  ") + key + ": 1\n");
    EXPECT_NE(msg.find("unknown key"), std::string::npos) << key << ": " << msg;
  }
}

TEST(ConfigLoader, UnknownKeyNamesFileKeyAndValue) {
  const auto msg = error_of("odometry:\n  window_keyframe: 25\n");
  EXPECT_NE(msg.find("test.yaml:2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("odometry.window_keyframe"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'25'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown key"), std::string::npos) << msg;
}

TEST(ConfigLoader, WrongTypeIsRejected) {
  const auto msg = error_of("lidar:\n  msop_port: fast\n");
  EXPECT_NE(msg.find("lidar.msop_port"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'fast'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("integer"), std::string::npos) << msg;
}

TEST(ConfigLoader, OutOfRangeIsRejected) {
  const auto msg = error_of("lidar:\n  msop_port: 70000\n");
  EXPECT_NE(msg.find("[1, 65535]"), std::string::npos) << msg;
  EXPECT_NE(error_of("odometry:\n  lidar_noise_m: .nan\n"), "");
  EXPECT_NE(error_of("odometry:\n  deskew: sometimes\n").find("imu"), std::string::npos);
  EXPECT_NE(error_of("odometry:\n  hold_release_yaw_rate_deg_s: -1\n").find("odometry.hold_release_yaw_rate_deg_s"),
            std::string::npos);
  EXPECT_EQ(error_of("odometry:\n  hold_release_yaw_rate_deg_s: 0\n"), "");  // always held (the ablation)
  EXPECT_NE(error_of("odometry:\n  post_max_width_m: -0.1\n").find("odometry.post_max_width_m"), std::string::npos);
  EXPECT_NE(error_of("odometry:\n  crossing_edge_tolerance_m: -0.01\n").find("odometry.crossing_edge_tolerance_m"),
            std::string::npos);
  // The local map's voxels hold at most 32 points: more is an error, not a silent cap.
  EXPECT_NE(error_of("odometry:\n  map_points_per_voxel: 33\n").find("[1, 32]"), std::string::npos);
  EXPECT_EQ(error_of("odometry:\n  map_points_per_voxel: 32\n"), "");
}

TEST(ConfigLoader, RelationsBetweenKeysAreChecked) {
  const auto msg = error_of("odometry:\n  min_range_m: 50\n  max_range_m: 40\n");
  EXPECT_NE(msg.find("odometry.max_range_m"), std::string::npos) << msg;
  EXPECT_NE(error_of("log:\n  level: loud\n").find("log.level"), std::string::npos);
}

TEST(ConfigLoader, QuaternionMustBeUnitAndListsNeedTheirLength) {
  EXPECT_NE(error_of("extrinsics:\n  lidar_to_imu:\n    rotation_xyzw: [0, 0, 0, 2]\n").find("unit quaternion"), std::string::npos);
  EXPECT_NE(error_of("extrinsics:\n  lidar_to_imu:\n    translation_m: [1, 2]\n").find("3 numbers"), std::string::npos);
}

TEST(ConfigLoader, ForwardAxisMustBeUnitAndHorizonPositive) {
  EXPECT_NE(error_of("odometry:\n  forward_axis: [0.5, 0, 0]\n").find("odometry.forward_axis"), std::string::npos);
  EXPECT_EQ(error_of("odometry:\n  forward_axis: [0, -1, 0]\n"), "");  // an IMU mounted with y to the rear
  EXPECT_NE(error_of("odometry:\n  up_axis: [0, 0, 2]\n").find("odometry.up_axis"), std::string::npos);
  EXPECT_NE(error_of("odometry:\n  up_axis: [1, 0, 0]\n").find("orthogonal"), std::string::npos);
  EXPECT_EQ(error_of("odometry:\n  forward_axis: [0, -1, 0]\n  up_axis: [1, 0, 0]\n"), "");
  EXPECT_NE(error_of("odometry:\n  vertical_velocity_std_mps: -0.1\n").find("odometry.vertical_velocity_std_mps"),
            std::string::npos);
  EXPECT_NE(error_of("pose_socket:\n  imu_rate_horizon_s: 0\n").find("pose_socket.imu_rate_horizon_s"), std::string::npos);
}

TEST(ConfigLoader, LaterFilesOverrideEarlierOnes) {
  const auto base = write_temp("liod_base.yaml", "odometry:\n  max_iterations: 7\nlidar:\n  msop_port: 7000\n");
  const auto overlay = write_temp("liod_overlay.yaml",
                                  "extrinsics:\n  lidar_to_imu:\n    translation_m: [0.5, 0, 1.0]\n"
                                  "    rotation_xyzw: [0, 0, 0.7071067811865476, 0.7071067811865476]\n"
                                  "  lidar_time_offset_s: 0.003\nlidar:\n  msop_port: 7001\n");
  const auto c = liod::load_config({base.string(), overlay.string()});
  EXPECT_EQ(c.odometry.max_iterations, 7);
  EXPECT_EQ(c.lidar.msop_port, 7001);
  EXPECT_NEAR(c.extrinsics.lidar_to_imu_translation.z(), 1.0, 1e-12);
  EXPECT_NEAR(c.extrinsics.lidar_time_offset_s, 0.003, 1e-12);
  const Eigen::Vector3d x_in_imu = c.extrinsics.lidar_to_imu_rotation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x_in_imu.y(), 1.0, 1e-9);  // a 90 degree yaw
}

// Found by fuzz_config: a complex key ("? ..." or "[a, b]: ...") made yaml-cpp throw its own
// bad-conversion exception instead of a ConfigError naming the file and key (so the daemon
// exited with a generic error and a message without the file name).
TEST(ConfigLoader, ComplexKeysAreConfigErrors) {
  const std::string fuzz_input = "#R lost\">\nlai-mu:\n ?  transport: serial  z     9 # senablerue\n";
  auto msg = error_of(fuzz_input);
  EXPECT_NE(msg.find("test.yaml:3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("key 'lai-mu'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("keys must be plain names"), std::string::npos) << msg;
  msg = error_of("[a, b]: 1\n");
  EXPECT_NE(msg.find("key '<top level>'"), std::string::npos) << msg;
  msg = error_of("drivers:\n  imu:\n    can_signals:\n      - {quantity: gyro_x, id: 1, [x]: 2}\n");
  EXPECT_NE(msg.find("drivers.imu.can_signals[0]"), std::string::npos) << msg;
  EXPECT_NE(msg.find("keys must be plain names"), std::string::npos) << msg;
}

TEST(ConfigLoader, MissingFileAndBrokenYamlAreReported) {
  try {
    liod::load_config({"/nonexistent/liod.yaml"});
    FAIL() << "expected an error";
  } catch (const liod::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/liod.yaml"), std::string::npos);
  }
  EXPECT_NE(error_of("odometry: [unclosed\n").find("not valid YAML"), std::string::npos);
  EXPECT_NE(error_of("- a\n- b\n").find("mapping"), std::string::npos);
}

}  // namespace
