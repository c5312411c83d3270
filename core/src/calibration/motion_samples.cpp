#include "liod/calibration/motion_samples.hpp"

#include <Eigen/Geometry>
#include <algorithm>

#include "liod/so3.hpp"

namespace liod::calibration {

std::vector<LidarRate> lidar_rates(const std::vector<LidarPose>& poses) {
  std::vector<LidarRate> rates;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    const double dt = poses[k].time - poses[k - 1].time;
    if (!(dt > 0.0)) continue;
    const Eigen::Vector3d turned = so3::log(poses[k - 1].rotation.transpose() * poses[k].rotation);
    rates.push_back({poses[k - 1].time, poses[k].time, turned / dt});
  }
  return rates;
}

AttitudeTrack::AttitudeTrack(const std::vector<ImuSample>& samples, const Eigen::Vector3d& gyro_bias) {
  for (const ImuSample& s : samples) {
    if (!times_.empty() && !(s.time > times_.back())) continue;
    if (attitudes_.empty()) {
      attitudes_.push_back(Eigen::Quaterniond::Identity());
    } else {
      const double dt = s.time - times_.back();
      // The rate at the interval's middle: the mean of its ends (trapezoid, as GyroIntegral).
      const Eigen::Vector3d rate = 0.5 * (s.gyro + last_rate_) - gyro_bias;
      attitudes_.push_back((attitudes_.back() * Eigen::Quaterniond(so3::exp(rate * dt))).normalized());
    }
    times_.push_back(s.time);
    last_rate_ = s.gyro;
  }
}

Eigen::Matrix3d AttitudeTrack::at(double time) const {
  const auto it = std::upper_bound(times_.begin(), times_.end(), time);
  if (it == times_.begin()) return attitudes_.front().toRotationMatrix();
  if (it == times_.end()) return attitudes_.back().toRotationMatrix();
  const auto i = static_cast<std::size_t>(it - times_.begin()) - 1;
  const double u = (time - times_[i]) / (times_[i + 1] - times_[i]);
  return attitudes_[i].slerp(u, attitudes_[i + 1]).toRotationMatrix();
}

Eigen::Matrix3d AttitudeTrack::relative(double from, double to) const {
  if (times_.empty()) return Eigen::Matrix3d::Identity();
  return at(from).transpose() * at(to);
}

Eigen::Matrix3d lidar_rotation_at(const std::vector<LidarPose>& poses, const AttitudeTrack& track,
                                  const Eigen::Matrix3d& lidar_to_imu, double time) {
  auto after = std::upper_bound(poses.begin(), poses.end(), time, [](double t, const LidarPose& p) { return t < p.time; });
  const LidarPose& base = after == poses.begin() ? poses.front() : *(after - 1);
  // R_wl(t) = R_wi(t) R = R_wl(t0) R^T R_rel(t0, t) R.
  return base.rotation * lidar_to_imu.transpose() * track.relative(base.time, time) * lidar_to_imu;
}

GyroIntegral::GyroIntegral(const std::vector<ImuSample>& samples) {
  times_.reserve(samples.size());
  for (const ImuSample& s : samples) {
    if (!times_.empty() && !(s.time > times_.back())) continue;  // out of order or repeated: not a new instant
    if (sums_.empty()) {
      sums_.push_back(Eigen::Vector3d::Zero());
    } else {
      sums_.push_back(sums_.back() + 0.5 * (s.time - times_.back()) * (s.gyro + rates_.back()));
    }
    times_.push_back(s.time);
    rates_.push_back(s.gyro);
  }
}

bool GyroIntegral::covers(double begin, double end) const {
  return times_.size() >= 2 && begin >= times_.front() && end <= times_.back() && end > begin;
}

Eigen::Vector3d GyroIntegral::integral_at(double time) const {
  const auto it = std::upper_bound(times_.begin(), times_.end(), time);
  const auto i = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(it - times_.begin(), 1,
                                                                     static_cast<std::ptrdiff_t>(times_.size()) - 1)) - 1;
  // Within a sample interval the rate is linear, so the integral is the trapezoid up to `time`.
  const double h = time - times_[i];
  const double u = h / (times_[i + 1] - times_[i]);
  const Eigen::Vector3d rate = rates_[i] + u * (rates_[i + 1] - rates_[i]);
  return sums_[i] + 0.5 * h * (rates_[i] + rate);
}

Eigen::Vector3d GyroIntegral::mean(double begin, double end) const {
  return (integral_at(end) - integral_at(begin)) / (end - begin);
}

}  // namespace liod::calibration
