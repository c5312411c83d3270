#include "liod/imu_trajectory.hpp"

#include <algorithm>

#include "liod/so3.hpp"

namespace liod {
namespace {

ImuSample interpolate(const ImuSample& a, const ImuSample& b, double t) {
  const double span = b.time - a.time;
  const double s = span > 0.0 ? std::clamp((t - a.time) / span, 0.0, 1.0) : 0.0;
  ImuSample out;
  out.time = t;
  out.gyro = (1.0 - s) * a.gyro + s * b.gyro;
  out.accel = (1.0 - s) * a.accel + s * b.accel;
  return out;
}

ImuSample sample_at(const std::deque<ImuSample>& samples, double t) {
  if (t <= samples.front().time) {
    ImuSample s = samples.front();
    s.time = t;
    return s;
  }
  if (t >= samples.back().time) {
    ImuSample s = samples.back();
    s.time = t;
    return s;
  }
  const auto it = std::lower_bound(samples.begin(), samples.end(), t,
                                   [](const ImuSample& s, double time) { return s.time < time; });
  return interpolate(*(it - 1), *it, t);
}

}  // namespace

std::vector<ImuInterval> imu_intervals(const std::deque<ImuSample>& samples, double from, double to) {
  std::vector<ImuInterval> out;
  if (samples.empty() || !(to > from)) return out;
  ImuSample previous = sample_at(samples, from);
  auto it = std::upper_bound(samples.begin(), samples.end(), from,
                             [](double time, const ImuSample& s) { return time < s.time; });
  auto push = [&](const ImuSample& next) {
    const double dt = next.time - previous.time;
    if (dt > 1e-9) {
      out.push_back({previous.time, dt, 0.5 * (previous.gyro + next.gyro), 0.5 * (previous.accel + next.accel)});
      previous = next;
    }
  };
  for (; it != samples.end() && it->time < to; ++it) push(*it);
  push(sample_at(samples, to));
  return out;
}

Pose PoseTable::at(double time) const {
  if (times_.empty()) return {};
  if (time <= times_.front()) return poses_.front();
  if (time >= times_.back()) return poses_.back();
  const auto it = std::upper_bound(times_.begin(), times_.end(), time);
  const auto k = static_cast<std::size_t>(it - times_.begin());
  const double s = (time - times_[k - 1]) / (times_[k] - times_[k - 1]);
  const Pose& a = poses_[k - 1];
  const Pose& b = poses_[k];
  // Normalised linear interpolation: between IMU samples the rotation changes by well under a
  // degree, where it equals slerp to ~1e-9 rad and costs no trigonometry.
  Eigen::Quaterniond q_b = b.rotation;
  if (a.rotation.dot(q_b) < 0.0) q_b.coeffs() = -q_b.coeffs();
  Eigen::Quaterniond q;
  q.coeffs() = (1.0 - s) * a.rotation.coeffs() + s * q_b.coeffs();
  return {q.normalized(), (1.0 - s) * a.translation + s * b.translation};
}

void PoseTable::make_relative_to(const Pose& reference) {
  const Pose inverse = reference.inverse();
  for (auto& pose : poses_) pose = inverse * pose;
}

PoseTable integrate_imu_poses(const NavState& start, const std::vector<ImuInterval>& intervals,
                              const Eigen::Vector3d& gravity) {
  PoseTable table;
  Eigen::Matrix3d r = start.rotation;
  Eigen::Vector3d p = start.position;
  Eigen::Vector3d v = start.velocity;
  double t = start.time;
  table.add(t, {Eigen::Quaterniond(r), p});
  for (const auto& interval : intervals) {
    // Same discretisation as ImuPreintegration::integrate_interval.
    const Eigen::Vector3d a_world = r * (interval.accel - start.accel_bias) + gravity;
    p += v * interval.dt + 0.5 * a_world * interval.dt * interval.dt;
    v += a_world * interval.dt;
    r = so3::normalize(r * so3::exp((interval.gyro - start.gyro_bias) * interval.dt));
    t = interval.start_time + interval.dt;
    table.add(t, {Eigen::Quaterniond(r), p});
  }
  return table;
}

}  // namespace liod
