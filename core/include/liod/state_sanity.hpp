#pragma once
// Whether the filter's numbers can be true at all: a state with a NaN, a rotation that is no
// rotation, a speed no road vehicle reaches, a bias no IMU has, or a covariance that is not
// positive definite (a filter that lost its numerical footing). The odometry re-initialises from
// such a state (lidar_inertial_odometry.cpp); the daemon checks every pose it publishes with the
// same functions (daemon/state_gate.hpp, flag `implausible`), with the limits of its
// pose_socket.* keys, which it hands to the odometry.

#include <Eigen/Core>
#include <cstdint>

#include "liod/imu_preintegration.hpp"

namespace liod {

enum class StateFault : std::uint8_t {
  kNone,
  kNotFinite,        ///< a NaN or infinity in time, pose, velocity, biases or gravity
  kRotation,         ///< the rotation is not a rotation (not orthonormal, or a reflection)
  kSpeed,            ///< faster than StateLimits::max_speed_mps
  kGyroBias,         ///< beyond StateLimits::max_gyro_bias_rad_s on some axis
  kAccelBias,        ///< beyond StateLimits::max_accel_bias_m_s2 on some axis
  kCovariance,       ///< not finite, not symmetric or not positive definite
};

/// Defaults: no road vehicle is faster than 100 m/s; an IMU of the class liod runs with (the
/// Xsens MTi-630: 0.2 deg/s in-run, 10 mg accelerometer bias) has no bias near 0.1 rad/s or 1 m/s^2.
struct StateLimits {
  double max_speed_mps = 100.0;
  double max_gyro_bias_rad_s = 0.1;
  double max_accel_bias_m_s2 = 1.0;
};

/// What is wrong with `state`, cheap enough for every IMU sample (no covariance).
StateFault check_state(const NavState& state, const StateLimits& limits);

/// What is wrong with a covariance (any square size): finite, symmetric to rounding, positive
/// definite (its Cholesky factorisation exists with a positive diagonal).
StateFault check_covariance(const Eigen::Ref<const Eigen::MatrixXd>& covariance);

}  // namespace liod
