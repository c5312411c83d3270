#pragma once
// The LiDAR-to-IMU rotation from angular rates: the gyro reads the LiDAR's rate turned into the
// IMU frame plus its bias, w_imu = R w_lidar + b. Centring both sets of rates removes the bias, and
// the rotation that best maps the centred LiDAR rates onto the centred gyro rates is Kabsch's
// (SVD of their cross-covariance). It is determined only about the axes the rates vary across:
// the spread of the centred LiDAR rates along each principal axis is the drive's excitation.

#include <Eigen/Core>
#include <vector>

namespace liod::calibration {

/// One interval's mean rates, rad/s: the LiDAR's (LiDAR frame) and the gyro's (IMU frame).
struct RatePair {
  Eigen::Vector3d lidar = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
};

struct RotationHandEye {
  bool valid = false;                                          // false: fewer than 3 pairs
  Eigen::Matrix3d lidar_to_imu = Eigen::Matrix3d::Identity();  // R
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();         // rad/s
  /// Standard deviation of the LiDAR rates along their principal axes, smallest first (rad/s),
  /// and those axes in the IMU frame (columns).
  Eigen::Vector3d rate_spread = Eigen::Vector3d::Zero();
  Eigen::Matrix3d spread_axes = Eigen::Matrix3d::Identity();
  double residual_rms = 0.0;  // rad/s, per axis
};

RotationHandEye rotation_from_rates(const std::vector<RatePair>& pairs);

}  // namespace liod::calibration
