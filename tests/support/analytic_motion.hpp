#pragma once
// A smooth analytic body motion with closed-form velocity and acceleration, and the IMU samples it
// produces: exact inputs for preintegration tests (R(t) = Exp(w t), p(t) sinusoids and a climb).

#include <Eigen/Core>
#include <deque>

#include "liod/imu_preintegration.hpp"
#include "liod/so3.hpp"
#include "liod/types.hpp"

namespace liod::test {

inline const Eigen::Vector3d kAnalyticGravity(0.0, 0.0, -9.80665);
inline const Eigen::Vector3d kAnalyticOmega(0.05, -0.1, 0.3);  // constant body rate, rad/s

inline Eigen::Matrix3d analytic_rotation(double t) { return so3::exp(kAnalyticOmega * t); }
inline Eigen::Vector3d analytic_position(double t) { return {10.0 * std::sin(0.5 * t), 4.0 * std::cos(0.3 * t), 0.2 * t * t}; }
inline Eigen::Vector3d analytic_velocity(double t) { return {5.0 * std::cos(0.5 * t), -1.2 * std::sin(0.3 * t), 0.4 * t}; }
inline Eigen::Vector3d analytic_acceleration(double t) { return {-2.5 * std::sin(0.5 * t), -0.36 * std::cos(0.3 * t), 0.4}; }

/// Samples at `rate` over [0, duration] of a gyro and accelerometer with constant biases.
inline std::deque<ImuSample> analytic_imu(double duration, double rate, const Eigen::Vector3d& gyro_bias,
                                          const Eigen::Vector3d& accel_bias) {
  std::deque<ImuSample> out;
  for (int k = 0; k <= static_cast<int>(duration * rate); ++k) {
    const double t = k / rate;
    ImuSample s;
    s.time = t;
    s.gyro = kAnalyticOmega + gyro_bias;
    s.accel = analytic_rotation(t).transpose() * (analytic_acceleration(t) - kAnalyticGravity) + accel_bias;
    out.push_back(s);
  }
  return out;
}

inline NavState analytic_state(double t) {
  NavState s;
  s.time = t;
  s.rotation = analytic_rotation(t);
  s.position = analytic_position(t);
  s.velocity = analytic_velocity(t);
  s.gravity = kAnalyticGravity;
  return s;
}

}  // namespace liod::test
