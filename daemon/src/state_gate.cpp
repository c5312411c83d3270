#include "liod/daemon/state_gate.hpp"

namespace liod {

const char* to_string(StateFault fault) {
  switch (fault) {
    case StateFault::kNone: return "plausible";
    case StateFault::kNotFinite: return "not finite";
    case StateFault::kRotation: return "rotation not orthonormal";
    case StateFault::kSpeed: return "speed beyond pose_socket.max_speed_mps";
    case StateFault::kGyroBias: return "gyro bias beyond pose_socket.max_gyro_bias_rad_s";
    case StateFault::kAccelBias: return "accelerometer bias beyond pose_socket.max_accel_bias_m_s2";
    case StateFault::kCovariance: return "covariance not positive definite";
  }
  return "?";
}

StateLimits state_limits(const Config& config) {
  const auto& p = config.pose_socket;
  return {p.max_speed_mps, p.max_gyro_bias_rad_s, p.max_accel_bias_m_s2};
}

}  // namespace liod
