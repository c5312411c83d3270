#pragma once
// The last check before a pose goes out as `ok`: the filter's flags say how well the scan
// constrained it, not whether the numbers themselves can be true. A state with a NaN, a speed
// no road vehicle reaches, a bias no IMU has, or a covariance that is not positive definite
// (a filter that lost its numerical footing) is published flagged `implausible` and never `ok`
// (docs/pose-protocol.md). Recovering the filter from such a state is the odometry's business;
// this gate makes sure that nobody steers by it meanwhile.

#include <Eigen/Core>
#include <cstdint>

#include "liod/config.hpp"
#include "liod/imu_preintegration.hpp"

namespace liod {

enum class StateFault : std::uint8_t {
  kNone,
  kNotFinite,        ///< a NaN or infinity in time, pose, velocity, biases or gravity
  kRotation,         ///< the rotation is not a rotation (not orthonormal, or a reflection)
  kSpeed,            ///< faster than pose_socket.max_speed_mps
  kGyroBias,         ///< beyond pose_socket.max_gyro_bias_rad_s on some axis
  kAccelBias,        ///< beyond pose_socket.max_accel_bias_m_s2 on some axis
  kCovariance,       ///< not finite, not symmetric or not positive definite
};

const char* to_string(StateFault fault);

struct StateLimits {
  double max_speed_mps = 100.0;
  double max_gyro_bias_rad_s = 0.1;
  double max_accel_bias_m_s2 = 1.0;
};

StateLimits state_limits(const Config& config);

/// What is wrong with `state`, cheap enough for every IMU sample (no covariance).
StateFault check_state(const NavState& state, const StateLimits& limits);

/// What is wrong with a covariance (any square size): finite, symmetric to rounding, positive
/// definite (its Cholesky factorisation exists with a positive diagonal).
StateFault check_covariance(const Eigen::Ref<const Eigen::MatrixXd>& covariance);

}  // namespace liod
