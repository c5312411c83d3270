#include "liod/calibration/extrinsic_calibration.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>

namespace liod::calibration {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

std::vector<RatePair> rate_pairs(const std::vector<LidarRate>& lidar, const GyroIntegral& gyro, double shift) {
  std::vector<RatePair> pairs;
  for (const LidarRate& r : lidar) {
    if (gyro.covers(r.begin + shift, r.end + shift)) pairs.push_back({r.rate, gyro.mean(r.begin + shift, r.end + shift)});
  }
  return pairs;
}

/// The axes whose standard deviation exceeds `limit`, e.g. "x 0.31, z 0.12" in `unit`.
std::string axes_beyond(const Eigen::Vector3d& std_dev, double limit, double scale, const char* unit) {
  std::ostringstream s;
  s.precision(2);
  for (int a = 0; a < 3; ++a) {
    if (!(std_dev(a) <= limit)) s << (s.tellp() > 0 ? ", " : "") << "xyz"[a] << " ±" << std_dev(a) * scale << ' ' << unit;
  }
  return s.str();
}

void check_excitation(CalibrationResult& r, const CalibrationConfig& config) {
  std::ostringstream s;
  s.precision(3);
  if (r.hand_eye.valid && r.hand_eye.rate_spread(2) < config.min_turn_rate_spread) {
    s << "too little rotation: the LiDAR's turn rate varies by " << r.hand_eye.rate_spread(2)
      << " rad/s at most (at least " << config.min_turn_rate_spread << " needed): drive a route with turns";
    r.refusals.push_back(s.str());
  }
  if (!r.time_shift.found || r.time_shift.correlation < config.min_correlation) {
    s.str("");
    s << "time offset: no clear peak of the turn-rate correlation (" << r.time_shift.correlation << " at best, "
      << config.min_correlation << " needed)";
    r.refusals.push_back(s.str());
  }
  if (!r.fit.valid) {
    r.refusals.push_back("the fit did not converge (too few scans or IMU samples in common)");
    return;
  }
  const std::string rot = axes_beyond(r.fit.rotation_std, config.max_rotation_std, kRadToDeg, "deg");
  if (!rot.empty()) r.refusals.push_back("rotation not excited about the IMU's axes " + rot);
  const std::string trans = axes_beyond(r.fit.translation_std, config.max_translation_std, 100.0, "cm");
  if (!trans.empty()) r.refusals.push_back("translation not excited along the IMU's axes " + trans);
}

}  // namespace

CalibrationResult calibrate_extrinsics(const std::vector<LidarPose>& poses, const std::vector<ImuSample>& imu,
                                       const ExtrinsicsConfig& configured, const CalibrationConfig& config) {
  CalibrationResult r;
  r.estimate = configured;
  const GyroIntegral gyro(imu);
  const std::vector<LidarRate> lidar = lidar_rates(poses);
  r.time_shift = estimate_time_shift(lidar, gyro, config.time);
  // The poses on the IMU clock by the offset just found.
  std::vector<LidarPose> shifted = poses;
  for (LidarPose& p : shifted) p.time += r.time_shift.shift_s;
  const std::vector<RatePair> pairs = rate_pairs(lidar, gyro, r.time_shift.shift_s);
  r.hand_eye = rotation_from_rates(pairs);
  std::optional<LeverArmHold> hold;
  if (config.hold_up_lever_arm) {
    const Eigen::Vector3d up = config.up_axis.normalized();
    hold = LeverArmHold{up, up.dot(configured.lidar_to_imu_translation)};
  }
  if (r.hand_eye.valid) r.fit = fit_inertial(shifted, imu, pairs, r.hand_eye, hold, config.fit);
  check_excitation(r, config);
  r.accepted = r.refusals.empty();
  r.usable = r.fit.valid && r.time_shift.found && r.hand_eye.rate_spread(2) >= config.min_turn_rate_spread;
  r.fitted = configured;
  if (r.usable) {
    r.fitted.lidar_to_imu_rotation = Eigen::Quaterniond(r.fit.lidar_to_imu).normalized();
    r.fitted.lidar_to_imu_translation = r.fit.translation;
    r.fitted.lidar_time_offset_s = configured.lidar_time_offset_s + r.time_shift.shift_s;
  }
  if (r.accepted) r.estimate = r.fitted;
  return r;
}

}  // namespace liod::calibration
