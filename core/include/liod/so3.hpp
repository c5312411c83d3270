#pragma once
// SO(3) helpers (Forster et al. 2016, "On-Manifold Preintegration", Sec. II/III).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace liod::so3 {

inline Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

/// Exponential map (Rodrigues), Forster eq. (3).
inline Eigen::Matrix3d exp(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-10) return Eigen::Matrix3d::Identity() + hat(phi);
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

/// Logarithm map, Forster eq. (5).
inline Eigen::Vector3d log(const Eigen::Matrix3d& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  Eigen::Vector3d phi = aa.angle() * aa.axis();
  return phi;
}

/// Right Jacobian of SO(3), Forster eq. (8).
inline Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  const Eigen::Matrix3d w = hat(phi);
  if (angle < 1e-6) return Eigen::Matrix3d::Identity() - 0.5 * w;
  const double a2 = angle * angle;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(angle)) / a2 * w + (angle - std::sin(angle)) / (a2 * angle) * w * w;
}

/// Mean rate (rad/s) at which a body turned from `from` to `to` (body-to-world rotations) over
/// dt seconds, about the world axis `axis` (unit): a vehicle's yaw rate with axis = up.
inline double turn_rate_about(const Eigen::Matrix3d& from, const Eigen::Matrix3d& to, const Eigen::Vector3d& axis, double dt) {
  return (from * log(from.transpose() * to)).dot(axis) / dt;
}

/// Re-orthonormalises a rotation that accumulated rounding error.
inline Eigen::Matrix3d normalize(const Eigen::Matrix3d& r) { return Eigen::Quaterniond(r).normalized().toRotationMatrix(); }

}  // namespace liod::so3
