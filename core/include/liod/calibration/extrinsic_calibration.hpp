#pragma once
// The LiDAR-IMU calibration of a recorded drive (`liod calibrate`): the clock offset from the
// turn-rate correlation (time_offset.hpp), the rotation from the rates (rotation_hand_eye.hpp),
// then rotation and translation together from both IMU sensors (inertial_fit.hpp). A drive that
// does not excite every axis gives no estimate: the result lists why, axis by axis.

#include <string>
#include <vector>

#include "liod/algorithm_config.hpp"
#include "liod/calibration/inertial_fit.hpp"
#include "liod/calibration/motion_samples.hpp"
#include "liod/calibration/rotation_hand_eye.hpp"
#include "liod/calibration/time_offset.hpp"

namespace liod::calibration {

struct CalibrationConfig {
  /// The turns a calibration needs: the LiDAR's rate varies by at least this (rad/s, standard
  /// deviation along its most varied axis). Town driving reaches 0.1-0.2, a motorway ~0.01.
  static constexpr double kDefaultMinTurnRateSpread = 0.05;
  /// The rate correlation's peak: below this the two sensors' turns do not line up.
  static constexpr double kDefaultMinCorrelation = 0.9;
  /// Largest standard deviations accepted for an estimate: an axis beyond is not excited.
  static constexpr double kDefaultMaxRotationStdRad = 0.1 * 3.14159265358979 / 180.0;
  static constexpr double kDefaultMaxTranslationStdM = 0.01;
  double min_turn_rate_spread = kDefaultMinTurnRateSpread;
  double min_correlation = kDefaultMinCorrelation;
  double max_rotation_std = kDefaultMaxRotationStdRad;
  double max_translation_std = kDefaultMaxTranslationStdM;
  /// The lever arm's component along the vehicle's up axis (IMU frame) is kept at the configured
  /// value (`hold_up_lever_arm`): fitted, it came out 1-8 cm off on a minute in town while its
  /// formal standard deviation read 2 cm (docs/results.md). A tape measure does better.
  bool hold_up_lever_arm = true;
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
  TimeOffsetConfig time;
  InertialFitConfig fit;
};

struct CalibrationResult {
  bool accepted = false;
  /// A fit and a time offset were found (perhaps not precise enough to accept): the drive turns.
  bool usable = false;
  /// Why the estimate is not accepted, one line a reason (empty when accepted).
  std::vector<std::string> refusals;
  ExtrinsicsConfig estimate;  // when accepted: `fitted`; the configured values otherwise
  ExtrinsicsConfig fitted;    // what the fit found, accepted or not (when usable)
  TimeShift time_shift;
  RotationHandEye hand_eye;
  InertialFit fit;
};

/// `poses`: the LiDAR's poses, stamped on the IMU clock with `configured`'s offset.
CalibrationResult calibrate_extrinsics(const std::vector<LidarPose>& poses, const std::vector<ImuSample>& imu,
                                       const ExtrinsicsConfig& configured, const CalibrationConfig& config = {});

}  // namespace liod::calibration
