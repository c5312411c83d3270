// The calibration's math on motion made from formulas: a body that turns about every axis and
// accelerates, its IMU samples, and the poses of a LiDAR mounted on it with a known rotation,
// lever arm and clock offset.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "liod/calibration/extrinsic_calibration.hpp"
#include "liod/so3.hpp"

namespace {

using liod::ImuSample;
using liod::calibration::LidarPose;

constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Motion {
  /// true: only drives straight on at constant speed.
  bool straight = false;
  Eigen::Matrix3d rotation(double t) const {
    if (straight) return Eigen::Matrix3d::Identity();
    const double yaw = 0.6 * std::sin(0.35 * t) + 0.05 * t;
    const double pitch = 0.03 * std::sin(1.7 * t + 1.0);
    const double roll = 0.04 * std::sin(2.1 * t);
    return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
  }
  Eigen::Vector3d position(double t) const {
    if (straight) return {10.0 * t, 0.0, 0.0};
    return {40.0 * std::sin(0.2 * t), 30.0 * std::sin(0.27 * t + 0.5), 0.3 * std::sin(0.9 * t)};
  }
  Eigen::Vector3d acceleration(double t) const {
    if (straight) return Eigen::Vector3d::Zero();
    return {-40.0 * 0.04 * std::sin(0.2 * t), -30.0 * 0.0729 * std::sin(0.27 * t + 0.5), -0.3 * 0.81 * std::sin(0.9 * t)};
  }
  Eigen::Vector3d body_rate(double t) const {
    constexpr double h = 1e-5;
    return liod::so3::log(rotation(t - h).transpose() * rotation(t + h)) / (2.0 * h);
  }
};

struct Mounting {
  Eigen::Matrix3d rotation = (Eigen::AngleAxisd(3.0 * kDeg, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(-1.5 * kDeg, Eigen::Vector3d::UnitY()) *
                              Eigen::AngleAxisd(2.0 * kDeg, Eigen::Vector3d::UnitX()))
                                 .toRotationMatrix();
  Eigen::Vector3d translation{0.5, -0.03, 1.05};
  double offset = 0.0073;  // t_imu = t_lidar + offset
};

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
const Eigen::Vector3d kGyroBias(0.002, -0.003, 0.004);
const Eigen::Vector3d kAccelBias(0.05, -0.04, 0.08);

std::vector<ImuSample> imu_samples(const Motion& m, double duration) {
  std::vector<ImuSample> out;
  for (int i = 0; i * 0.005 <= duration; ++i) {
    const double t = i * 0.005;
    ImuSample s;
    s.time = t;
    s.gyro = m.body_rate(t) + kGyroBias;
    s.accel = m.rotation(t).transpose() * (m.acceleration(t) - kGravity) + kAccelBias;
    out.push_back(s);
  }
  return out;
}

/// The LiDAR's poses every 0.1 s, stamped as the configured offset `configured_offset` puts them.
std::vector<LidarPose> lidar_poses(const Motion& m, const Mounting& mount, double duration, double configured_offset) {
  std::vector<LidarPose> out;
  for (int k = 2; k * 0.1 <= duration - 0.2; ++k) {
    const double t_true = k * 0.1;                      // IMU clock
    const double t_lidar = t_true - mount.offset;       // LiDAR clock
    const Eigen::Matrix3d r = m.rotation(t_true);
    out.push_back({t_lidar + configured_offset, r * mount.rotation, m.position(t_true) + r * mount.translation});
  }
  return out;
}

TEST(CalibrationMath, GyroIntegralIsExactForARateLinearInTime) {
  std::vector<ImuSample> samples;
  for (int i = 0; i <= 100; ++i) {
    ImuSample s;
    s.time = i * 0.01;
    s.gyro = Eigen::Vector3d(1.0 + 2.0 * s.time, -s.time, 0.5);
    samples.push_back(s);
  }
  const liod::calibration::GyroIntegral gyro(samples);
  ASSERT_TRUE(gyro.covers(0.123, 0.777));
  EXPECT_FALSE(gyro.covers(-0.1, 0.5));
  const Eigen::Vector3d mean = gyro.mean(0.123, 0.777);
  const double mid = 0.5 * (0.123 + 0.777);
  EXPECT_NEAR(mean.x(), 1.0 + 2.0 * mid, 1e-12);
  EXPECT_NEAR(mean.y(), -mid, 1e-12);
  EXPECT_NEAR(mean.z(), 0.5, 1e-12);
}

TEST(CalibrationMath, TimeShiftIsTheClockOffsetTheConfigurationMisses) {
  const Motion m;
  const Mounting mount;
  const auto imu = imu_samples(m, 60.0);
  // Configured 12 ms late: the poses are stamped 12 - 7.3 ms after their true time.
  const auto poses = lidar_poses(m, mount, 60.0, 0.012);
  const auto shift = liod::calibration::estimate_time_shift(liod::calibration::lidar_rates(poses),
                                                            liod::calibration::GyroIntegral(imu));
  ASSERT_TRUE(shift.found);
  EXPECT_NEAR(shift.shift_s, mount.offset - 0.012, 1e-4);
  EXPECT_GT(shift.correlation, 0.99);
}

// A yaw rate seen by a 200 Hz gyro and, `shift` later on its clock and with noise, by the LiDAR's
// scan-to-scan rates.
liod::calibration::TimeShift shift_of_yaw_rate(const std::function<double(double)>& yaw_rate, double shift) {
  std::vector<ImuSample> imu;
  for (int k = 0; k <= 200 * 62; ++k) {
    ImuSample s;
    s.time = k / 200.0;
    s.gyro = Eigen::Vector3d(0.0, 0.0, yaw_rate(s.time));
    s.accel = -kGravity;
    imu.push_back(s);
  }
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.003);
  std::vector<liod::calibration::LidarRate> lidar;
  for (int k = 5; k < 600; ++k) {
    liod::calibration::LidarRate r;
    r.begin = k * 0.1;
    r.end = r.begin + 0.1;
    double mean = 0.0;
    for (int i = 0; i < 100; ++i) mean += yaw_rate(r.begin + shift + (i + 0.5) * 0.001) / 100.0;
    r.rate = Eigen::Vector3d(0.0, 0.0, mean + noise(rng));
    lidar.push_back(r);
  }
  return liod::calibration::estimate_time_shift(lidar, liod::calibration::GyroIntegral(imu));
}

TEST(CalibrationMath, TimeShiftUncertaintyGrowsWhenTheTurnRateIsSteady) {
  constexpr double kShift = 0.005;
  const auto varied = shift_of_yaw_rate([](double t) { return 0.3 * std::sin(0.5 * t) + 0.1 * std::sin(1.7 * t); }, kShift);
  const auto steady = shift_of_yaw_rate([](double t) { return 0.3 + 0.004 * std::sin(0.5 * t); }, kShift);
  ASSERT_TRUE(varied.found);
  EXPECT_LT(varied.shift_std_s, 1e-3);
  EXPECT_LT(std::abs(varied.shift_s - kShift), 3.0 * varied.shift_std_s);
  // A steady turn hardly changes with the shift: the estimate is one, the standard error says so.
  EXPECT_GT(steady.shift_std_s, 10.0 * varied.shift_std_s);
}

TEST(CalibrationMath, RatesGiveTheRotationAndTheGyroBias) {
  const Motion m;
  const Mounting mount;
  std::vector<liod::calibration::RatePair> pairs;
  for (int k = 0; k < 600; ++k) {
    const double t = k * 0.1;
    const Eigen::Vector3d imu_rate = m.body_rate(t);
    pairs.push_back({mount.rotation.transpose() * imu_rate, imu_rate + kGyroBias});
  }
  const auto r = liod::calibration::rotation_from_rates(pairs);
  ASSERT_TRUE(r.valid);
  EXPECT_LT(Eigen::AngleAxisd(r.lidar_to_imu.transpose() * mount.rotation).angle(), 1e-6);
  EXPECT_LT((r.gyro_bias - kGyroBias).norm(), 1e-6);
  EXPECT_GT(r.rate_spread(0), 0.01);  // the rocking: every axis varies
}

liod::calibration::CalibrationResult calibrate_from_wrong_start(const Mounting& mount, bool hold_up_lever_arm) {
  const Motion m;
  const auto imu = imu_samples(m, 60.0);
  liod::ExtrinsicsConfig configured;
  configured.lidar_time_offset_s = mount.offset + 0.015;
  configured.lidar_to_imu_translation = Eigen::Vector3d(0.4, 0.05, mount.translation.z());  // the height measured
  const auto poses = lidar_poses(m, mount, 60.0, configured.lidar_time_offset_s);
  liod::calibration::CalibrationConfig config;
  config.hold_up_lever_arm = hold_up_lever_arm;
  return liod::calibration::calibrate_extrinsics(poses, imu, configured, config);
}

TEST(CalibrationMath, RecoversRotationLeverArmAndOffsetFromAWrongStart) {
  const Mounting mount;
  for (const bool hold : {true, false}) {
    const auto r = calibrate_from_wrong_start(mount, hold);
    ASSERT_TRUE(r.accepted) << (r.refusals.empty() ? "" : r.refusals.front());
    const Eigen::Matrix3d estimated = r.estimate.lidar_to_imu_rotation.toRotationMatrix();
    EXPECT_LT(Eigen::AngleAxisd(estimated.transpose() * mount.rotation).angle(), 0.01 * kDeg) << hold;
    EXPECT_LT((r.estimate.lidar_to_imu_translation - mount.translation).norm(), 0.003) << hold;
    EXPECT_NEAR(r.estimate.lidar_time_offset_s, mount.offset, 2e-4) << hold;
    EXPECT_LT((r.fit.accel_bias - kAccelBias).norm(), 0.01) << hold;
  }
}

TEST(CalibrationMath, TheHeldLeverArmComponentKeepsTheConfiguredValue) {
  Mounting mount;
  // The truth 5 cm higher than configured: held, the estimate keeps the configured height, and the
  // horizontal components still come out right.
  mount.translation.z() += 0.05;
  const Mounting configured_mount;
  const auto r = [&] {
    const Motion m;
    const auto imu = imu_samples(m, 60.0);
    liod::ExtrinsicsConfig configured;
    configured.lidar_time_offset_s = mount.offset;
    configured.lidar_to_imu_translation = configured_mount.translation;
    return liod::calibration::calibrate_extrinsics(lidar_poses(m, mount, 60.0, mount.offset), imu, configured);
  }();
  ASSERT_TRUE(r.accepted) << (r.refusals.empty() ? "" : r.refusals.front());
  EXPECT_NEAR(r.estimate.lidar_to_imu_translation.z(), configured_mount.translation.z(), 1e-3);
  EXPECT_LT((r.estimate.lidar_to_imu_translation - mount.translation).head<2>().norm(), 0.01);
}

TEST(CalibrationMath, RefusesAStraightDriveNamingTheMissingRotation) {
  Motion m;
  m.straight = true;
  const Mounting mount;
  const auto imu = imu_samples(m, 60.0);
  liod::ExtrinsicsConfig configured;
  configured.lidar_time_offset_s = mount.offset;
  const auto r = liod::calibration::calibrate_extrinsics(lidar_poses(m, mount, 60.0, mount.offset), imu, configured);
  EXPECT_FALSE(r.accepted);
  EXPECT_FALSE(r.usable);
  ASSERT_FALSE(r.refusals.empty());
  EXPECT_NE(r.refusals.front().find("too little rotation"), std::string::npos) << r.refusals.front();
  // Refused, the estimate stays the configured one.
  EXPECT_EQ(r.estimate.lidar_to_imu_translation, configured.lidar_to_imu_translation);
}

}  // namespace
