#include "liod/imu_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace liod {
namespace {

// How much a road vehicle's motion may change over an IMU gap, 1 sigma: its angular rate by
// this much, and its acceleration by this much.
constexpr double kGapAngularRateStd = 0.5;   // rad/s
constexpr double kGapAccelerationStd = 1.0;  // m/s^2

}  // namespace

void ImuBuffer::add(const ImuSample& sample) {
  const bool finite = std::isfinite(sample.time) && sample.gyro.allFinite() && sample.accel.allFinite();
  // Within the range a sample may be saturated but is a measurement; beyond it, it is not one.
  const bool in_range = finite && sample.gyro.cwiseAbs().maxCoeff() <= gyro_range_ &&
                        sample.accel.cwiseAbs().maxCoeff() <= accel_range_;
  if (!in_range || (!samples_.empty() && sample.time <= samples_.back().time)) {
    ++dropped_;
    return;
  }
  samples_.push_back(sample);
  // Without scans (a LiDAR dead or not yet connected) nothing else trims the buffer, and a daemon
  // left so for a day would hold a gigabyte of samples. A scan after a longer silence is
  // predicted across the missing start as over any IMU gap.
  while (samples_.size() > 2 && samples_.front().time < sample.time - history_s_) samples_.pop_front();
}

void ImuBuffer::forget_before(double time) {
  while (samples_.size() > 2 && samples_[1].time < time) samples_.pop_front();
}

double ImuBuffer::latest_time() const {
  return samples_.empty() ? -std::numeric_limits<double>::infinity() : samples_.back().time;
}

std::vector<TimeSpan> ImuBuffer::gaps(double from, double to, double max_gap) const {
  if (samples_.empty()) return to > from ? std::vector<TimeSpan>{{from, to}} : std::vector<TimeSpan>{};
  std::vector<TimeSpan> gaps;
  auto add = [&](double a, double b) {
    a = std::max(a, from);
    b = std::min(b, to);
    if (b > a) gaps.push_back({a, b});
  };
  if (samples_.front().time - from > max_gap) add(from, samples_.front().time);
  for (std::size_t i = 1; i < samples_.size(); ++i) {
    if (samples_[i].time - samples_[i - 1].time > max_gap) add(samples_[i - 1].time, samples_[i].time);
  }
  if (to - samples_.back().time > max_gap) add(samples_.back().time, to);
  return gaps;
}

void bridge_imu_gaps(std::vector<ImuInterval>& intervals, const std::vector<TimeSpan>& gaps, const NavState& start,
                     const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& gravity) {
  const Eigen::Vector3d v_body = start.rotation.transpose() * start.velocity;
  const Eigen::Vector3d gyro = angular_rate + start.gyro_bias;
  const Eigen::Vector3d accel = angular_rate.cross(v_body) - start.rotation.transpose() * gravity + start.accel_bias;
  for (auto& iv : intervals) {
    const double mid = iv.start_time + 0.5 * iv.dt;
    for (const auto& gap : gaps) {
      if (mid > gap.from && mid < gap.to) {
        iv.gyro = gyro;
        iv.accel = accel;
        break;
      }
    }
  }
}

void widen_for_imu_gaps(StateCovariance& p, const std::vector<TimeSpan>& gaps) {
  double gap = 0.0;
  for (const auto& g : gaps) gap += g.to - g.from;
  const Eigen::Matrix3d i = Eigen::Matrix3d::Identity();
  const double w = kGapAngularRateStd * gap;
  const double a2 = kGapAccelerationStd * kGapAccelerationStd;
  p.block<3, 3>(0, 0) += i * w * w;
  p.block<3, 3>(3, 3) += i * a2 * std::pow(gap, 4) / 4.0;  // p += a t^2 / 2
  p.block<3, 3>(3, 6) += i * a2 * std::pow(gap, 3) / 2.0;
  p.block<3, 3>(6, 3) += i * a2 * std::pow(gap, 3) / 2.0;
  p.block<3, 3>(6, 6) += i * a2 * gap * gap;  // v += a t
}

}  // namespace liod
