#pragma once
// What the calibration compares: the LiDAR's own motion (its poses from a registration against
// the map, on the IMU clock by the configured offset) and the IMU's samples. The LiDAR's angular
// rate over each scan-to-scan interval, and the gyro's mean over any interval.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "liod/types.hpp"

namespace liod::calibration {

/// The LiDAR's pose in the world at `time` (IMU clock, by the configured offset).
struct LidarPose {
  double time = 0.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // LiDAR to world
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

/// The LiDAR's mean angular rate (rad/s, LiDAR frame) between two consecutive poses.
struct LidarRate {
  double begin = 0.0;
  double end = 0.0;
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();
};

std::vector<LidarRate> lidar_rates(const std::vector<LidarPose>& poses);

/// The body's rotation between any two instants within the IMU's samples, integrated from the gyro
/// less a bias: what the LiDAR's 10 Hz poses miss between them (the body's rocking at 1-2 Hz).
class AttitudeTrack {
 public:
  AttitudeTrack(const std::vector<ImuSample>& samples, const Eigen::Vector3d& gyro_bias);
  /// The body's rotation from `from` to `to` (body frame at `from`); identity without samples.
  Eigen::Matrix3d relative(double from, double to) const;

 private:
  Eigen::Matrix3d at(double time) const;

  std::vector<double> times_;
  std::vector<Eigen::Quaterniond> attitudes_;  // from the first sample's body frame
  Eigen::Vector3d last_rate_ = Eigen::Vector3d::Zero();
};

/// The LiDAR's rotation at `time`: the pose at or before it, carried on by the gyro's track, with
/// `lidar_to_imu` the mounting the track's body rotation is turned by.
Eigen::Matrix3d lidar_rotation_at(const std::vector<LidarPose>& poses, const AttitudeTrack& track,
                                  const Eigen::Matrix3d& lidar_to_imu, double time);

/// The gyro's integral over any interval within its samples, from a running sum (trapezoids).
class GyroIntegral {
 public:
  explicit GyroIntegral(const std::vector<ImuSample>& samples);
  /// True when [begin, end] lies within the samples.
  bool covers(double begin, double end) const;
  /// Mean rate over [begin, end] (rad/s, IMU frame); the interval must be covered.
  Eigen::Vector3d mean(double begin, double end) const;

 private:
  Eigen::Vector3d integral_at(double time) const;

  std::vector<double> times_;
  std::vector<Eigen::Vector3d> rates_;
  std::vector<Eigen::Vector3d> sums_;  // integral from the first sample to each sample's time
};

}  // namespace liod::calibration
