#pragma once
// The LiDAR-IMU clock offset from the one signal both sensors see whatever their mounting: how
// fast the vehicle turns. The norm of the LiDAR's angular rate, scan to scan, is compared with the
// norm of the gyro's mean rate over the same interval moved by a candidate shift; the shift of
// the largest correlation, refined to a fraction of the search step by a parabola through the peak
// and its neighbours, is what the configured offset misses (t_true = t_configured + shift).

#include <vector>

#include "liod/calibration/motion_samples.hpp"

namespace liod::calibration {

struct TimeOffsetConfig {
  /// Shifts tried: [-search_s, search_s] in steps of step_s.
  static constexpr double kDefaultSearchS = 0.1;
  static constexpr double kDefaultStepS = 0.001;
  double search_s = kDefaultSearchS;
  double step_s = kDefaultStepS;
};

struct TimeShift {
  bool found = false;     // false: too few intervals, or the peak at the edge of the search
  double shift_s = 0.0;   // add to the configured offset
  double correlation = 0.0;
  std::size_t intervals = 0;
  /// Standard error of shift_s: the LiDAR's rates regressed on the gyro's at the shift, the
  /// residuals' spread against how fast a shift changes the gyro's side, with the effective sample
  /// size of residuals correlated from interval to interval (AR(1)). Large when the vehicle turns at
  /// a steady rate (a figure-8, a roundabout): shifting a steady rate changes nothing.
  double shift_std_s = 0.0;
};

TimeShift estimate_time_shift(const std::vector<LidarRate>& lidar, const GyroIntegral& gyro,
                              const TimeOffsetConfig& config = {});

}  // namespace liod::calibration
