#pragma once
// The LiDAR-to-IMU rotation and translation fitted to both IMU sensors at once, given the LiDAR's
// trajectory (poses on the IMU clock, the time offset already found).
//
// Gyro: each scan interval's mean rate, w_imu = R w_lidar + b_g (rotation_hand_eye.hpp). The
// rates fix R about the axes the vehicle turns across, but a car mostly yaws, and a rotation of R
// about the yaw axis leaves yaw rates unchanged.
//
// Accelerometer: for three LiDAR poses at t0 < t1 < t2 the IMU's positions p_imu = p_lidar -
// R_wl R^T t obey the divided difference
//   (p_imu(t2) - p_imu(t1)) / h2 - (p_imu(t1) - p_imu(t0)) / h1 = ∫ K(s) (R_wl(s) R^T (f(s) - b_a) + g) ds,
// K the hat from t0 to t2 with its peak 1 at t1. The lever arm t enters through the rotation's
// change across the three poses (turning and rocking), the rotation R through the direction of
// every specific force the vehicle feels (accelerating, braking, cornering), which is what
// determines R about the yaw axis. b_a and gravity g (world frame) are fitted alongside.
//
// Gauss-Newton over [dθ, b_g, t, b_a, g], each sensor's residuals weighted by their own scatter,
// re-estimated between rounds. The covariance counts each accelerometer triple once per its
// overlap with its neighbours (they share samples), so the standard deviations are not those of
// independent residuals.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "liod/calibration/motion_samples.hpp"
#include "liod/calibration/rotation_hand_eye.hpp"
#include "liod/types.hpp"

namespace liod::calibration {

/// A component of the lever arm kept at a known value instead of fitted: the part along the
/// vehicle's up axis, which a car's little roll and pitch hardly show (docs/design.md).
struct LeverArmHold {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // IMU frame, unit
  double value = 0.0;                               // m, axis · t
};

struct InertialFitConfig {
  /// Spacings of the three poses of the accelerometer residuals, s: short ones follow the body's
  /// rocking (1-2 Hz), long ones the turns.
  static constexpr double kDefaultShortSpacingS = 0.3;
  static constexpr double kDefaultLongSpacingS = 1.0;
  static constexpr int kDefaultIterations = 10;
  static constexpr int kDefaultWeightingRounds = 3;
  /// How tightly a held lever-arm component is held (m): a prior this sharp is a constraint.
  static constexpr double kDefaultHoldStdM = 1e-4;
  std::vector<double> spacings_s{kDefaultShortSpacingS, kDefaultLongSpacingS};
  int iterations = kDefaultIterations;
  int weighting_rounds = kDefaultWeightingRounds;
  double hold_std_m = kDefaultHoldStdM;
};

struct InertialFit {
  bool valid = false;
  Eigen::Matrix3d lidar_to_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // m, the LiDAR's origin in the IMU frame
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // world frame
  /// Standard deviations: the rotation about the IMU's x, y, z (rad) and the translation (m).
  Eigen::Vector3d rotation_std = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation_std = Eigen::Vector3d::Zero();
  double gyro_rms = 0.0;   // rad/s
  double accel_rms = 0.0;  // m/s, of the divided differences
  std::size_t gyro_residuals = 0;
  std::size_t accel_residuals = 0;
};

/// `rates`: the gyro's and the LiDAR's rates over each scan interval; `initial`: the rates' fit,
/// where R starts from, and whose R and gyro bias carry the LiDAR's rotation between its poses.
InertialFit fit_inertial(const std::vector<LidarPose>& poses, const std::vector<ImuSample>& imu,
                         const std::vector<RatePair>& rates, const RotationHandEye& initial,
                         const std::optional<LeverArmHold>& hold, const InertialFitConfig& config = {});

}  // namespace liod::calibration
