#pragma once
// IMU samples turned into integration intervals and into a continuous body trajectory, so that
// the prediction and the per-point deskew integrate the same measurements the same way.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <deque>
#include <vector>

#include "liod/imu_preintegration.hpp"
#include "liod/types.hpp"

namespace liod {

struct ImuInterval {
  double start_time = 0.0;
  double dt = 0.0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // mean over the interval (trapezoid)
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
};

/// Intervals covering [from, to] from time-ordered samples, with the measurements linearly
/// interpolated at both ends. Before the first sample / after the last one the nearest sample
/// is held. Returns an empty list if from >= to or there are no samples.
std::vector<ImuInterval> imu_intervals(const std::deque<ImuSample>& samples, double from, double to);

/// A rigid pose as rotation + translation.
struct Pose {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  Pose operator*(const Pose& other) const { return {rotation * other.rotation, rotation * other.translation + translation}; }
  Pose inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return {inv, -(inv * translation)};
  }
};

/// Time-stamped poses with interpolation (slerp + linear) in between; held at the ends.
class PoseTable {
 public:
  void clear() { times_.clear(); poses_.clear(); }
  void add(double time, const Pose& pose) { times_.push_back(time); poses_.push_back(pose); }
  bool empty() const { return times_.empty(); }
  Pose at(double time) const;
  /// Every pose expressed relative to `reference`: reference^-1 * pose.
  void make_relative_to(const Pose& reference);

 private:
  std::vector<double> times_;
  std::vector<Pose> poses_;
};

/// Integrates the intervals from `start` (its biases applied) and records the body pose at each
/// interval boundary.
PoseTable integrate_imu_poses(const NavState& start, const std::vector<ImuInterval>& intervals,
                              const Eigen::Vector3d& gravity);

}  // namespace liod
