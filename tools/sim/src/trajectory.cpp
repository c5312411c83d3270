#include "liod/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace liod::sim {

Eigen::Matrix3d rotation_from_euler(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Trajectory::Trajectory(double t0, double dt, std::vector<Sample6> samples,
                       std::vector<Sinusoid> vibration)
    : t0_(t0), dt_(dt), samples_(std::move(samples)), vibration_(std::move(vibration)) {
  if (samples_.size() < 5) {
    throw std::runtime_error("trajectory needs at least 5 samples");
  }
}

void Trajectory::channels(double t, int order, Sample6& v, Sample6& d, Sample6& dd) const {
  const double x = (t - t0_) / dt_;
  const int n = static_cast<int>(samples_.size());
  const int k = std::clamp(static_cast<int>(std::floor(x)), 1, n - 3);
  const double u = x - k;
  const double iu = 1.0 - u;
  const double b[4] = {iu * iu * iu / 6.0, (3 * u * u * u - 6 * u * u + 4) / 6.0,
                       (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6.0, u * u * u / 6.0};
  const double db[4] = {-iu * iu / 2.0, (3 * u * u - 4 * u) / 2.0, (-3 * u * u + 2 * u + 1) / 2.0,
                        u * u / 2.0};
  const double ddb[4] = {iu, 3 * u - 2, 1 - 3 * u, u};
  for (std::size_t c = 0; c < 6; ++c) {
    double s0 = 0.0;
    double s1 = 0.0;
    double s2 = 0.0;
    for (int j = 0; j < 4; ++j) {
      const double cp = samples_[static_cast<std::size_t>(k - 1 + j)][c];
      s0 += b[j] * cp;
      s1 += db[j] * cp;
      s2 += ddb[j] * cp;
    }
    v[c] = s0;
    d[c] = s1 / dt_;
    dd[c] = s2 / (dt_ * dt_);
  }
  for (const auto& s : vibration_) {
    const double w = 2.0 * std::numbers::pi * s.frequency;
    const double arg = w * t + s.phase;
    const auto c = static_cast<std::size_t>(s.channel);
    v[c] += s.amplitude * std::sin(arg);
    if (order >= 1) {
      d[c] += s.amplitude * w * std::cos(arg);
      dd[c] -= s.amplitude * w * w * std::sin(arg);
    }
  }
}

BodyState Trajectory::state(double t) const {
  Sample6 v{};
  Sample6 d{};
  Sample6 dd{};
  channels(t, 2, v, d, dd);
  BodyState s;
  s.position = Eigen::Vector3d(v[0], v[1], v[2]);
  s.velocity = Eigen::Vector3d(d[0], d[1], d[2]);
  s.acceleration = Eigen::Vector3d(dd[0], dd[1], dd[2]);
  const double roll = v[3];
  const double pitch = v[4];
  const double yaw = v[5];
  s.rotation = rotation_from_euler(roll, pitch, yaw);
  // Body rates of a ZYX Euler sequence.
  const double sr = std::sin(roll);
  const double cr = std::cos(roll);
  const double sp = std::sin(pitch);
  const double cp = std::cos(pitch);
  s.angular_velocity = Eigen::Vector3d(d[3] - d[5] * sp, d[4] * cr + d[5] * sr * cp,
                                       -d[4] * sr + d[5] * cr * cp);
  return s;
}

Pose Trajectory::pose(double t) const {
  Sample6 v{};
  Sample6 d{};
  Sample6 dd{};
  channels(t, 0, v, d, dd);
  return Pose{rotation_from_euler(v[3], v[4], v[5]), Eigen::Vector3d(v[0], v[1], v[2])};
}

}  // namespace liod::sim
