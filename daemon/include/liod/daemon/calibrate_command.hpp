#pragma once
// `liod calibrate`: the LiDAR-IMU extrinsic and clock offset from a recorded drive with turns.
// The drive is replayed through the odometry with the configured extrinsics; the LiDAR's poses
// it finds and the IMU log go to the calibration (core/calibration/extrinsic_calibration.hpp);
// each further pass replays with the previous pass's estimate, which the odometry's poses then
// carry less of the configured error. The estimate is written as a config fragment (the
// `extrinsics:` keys) to layer over the configuration: `--config base.yaml --config OUT`.

#include <iosfwd>
#include <string>

#include "liod/config.hpp"

namespace liod {

struct CalibrateOptions {
  static constexpr int kDefaultPasses = 3;
  /// The start-up's speed search and map restart come first; their poses are not the LiDAR's
  /// settled registration.
  static constexpr double kDefaultSkipS = 2.0;
  /// The calibration wants the LiDAR's motion, not the filter's blend of it with the gyro's
  /// (which, with a wrong time offset, is the gyro's at another time): its passes take the gyro's
  /// noise density this many times the configured one, and the filter's attitude follows the
  /// LiDAR's registration more closely. A pass then recovers ~80 % of the remaining time-offset
  /// error instead of ~70 % (docs/design.md, "LiDAR-IMU calibration").
  static constexpr double kDefaultGyroNoiseScale = 20.0;
  std::string pcap;
  std::string imu_csv;
  std::string out;  // the config fragment
  int passes = kDefaultPasses;
  double skip_s = kDefaultSkipS;
  double gyro_noise_scale = kDefaultGyroNoiseScale;
};

/// Exit code of a drive that does not excite the calibration (the reasons are printed).
inline constexpr int kCalibrationRefusedExit = 3;

/// Returns the process exit code: 0 with the fragment written, kCalibrationRefusedExit when the
/// drive cannot calibrate, 1 on other errors; prints each pass's estimate to `out`.
int run_calibrate(const Config& config, const CalibrateOptions& options, std::ostream& out);

}  // namespace liod
