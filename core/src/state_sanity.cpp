#include "liod/state_sanity.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>

namespace liod {

StateFault check_state(const NavState& s, const StateLimits& limits) {
  if (!std::isfinite(s.time) || !s.rotation.allFinite() || !s.position.allFinite() || !s.velocity.allFinite() ||
      !s.gyro_bias.allFinite() || !s.accel_bias.allFinite() || !s.gravity.allFinite()) {
    return StateFault::kNotFinite;
  }
  // The filter keeps R on SO(3) to rounding; anything visibly off is a broken state, and the
  // quaternion published from it would mean nothing.
  constexpr double kOrthonormalTolerance = 1e-6;
  if ((s.rotation.transpose() * s.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > kOrthonormalTolerance ||
      s.rotation.determinant() <= 0.0) {
    return StateFault::kRotation;
  }
  if (s.velocity.norm() > limits.max_speed_mps) return StateFault::kSpeed;
  if (s.gyro_bias.cwiseAbs().maxCoeff() > limits.max_gyro_bias_rad_s) return StateFault::kGyroBias;
  if (s.accel_bias.cwiseAbs().maxCoeff() > limits.max_accel_bias_m_s2) return StateFault::kAccelBias;
  return StateFault::kNone;
}

StateFault check_covariance(const Eigen::Ref<const Eigen::MatrixXd>& c) {
  if (c.rows() != c.cols() || c.rows() == 0 || !c.allFinite()) return StateFault::kCovariance;
  const double scale = c.cwiseAbs().maxCoeff();
  // The filter symmetrises after each update; rounding leaves a relative asymmetry near 1e-16.
  if (scale <= 0.0 || (c - c.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return StateFault::kCovariance;
  const Eigen::LLT<Eigen::MatrixXd> llt(c);
  if (llt.info() != Eigen::Success) return StateFault::kCovariance;
  const Eigen::VectorXd d = llt.matrixL().toDenseMatrix().diagonal();
  return (d.array() > 0.0).all() ? StateFault::kNone : StateFault::kCovariance;
}

}  // namespace liod
