#include "liod/error_state.hpp"

#include <cmath>

#include "liod/so3.hpp"

namespace liod {

Eigen::Matrix<double, 3, 2> gravity_tangent_basis(const Eigen::Vector3d& gravity) {
  const Eigen::Vector3d down = gravity.normalized();
  // The world x axis made orthogonal to gravity: smooth for any tilt short of 90 deg.
  Eigen::Vector3d across = Eigen::Vector3d::UnitX() - down.x() * down;
  if (across.norm() < 1e-6) across = Eigen::Vector3d::UnitY() - down.y() * down;
  Eigen::Matrix<double, 3, 2> basis;
  basis.col(0) = across.normalized();
  basis.col(1) = down.cross(basis.col(0));
  return basis;
}

NavState boxplus(const NavState& x, const StateVector& delta) {
  NavState out = x;
  out.rotation = so3::normalize(x.rotation * so3::exp(delta.segment<3>(0)));
  out.position += delta.segment<3>(3);
  out.velocity += delta.segment<3>(6);
  out.gyro_bias += delta.segment<3>(9);
  out.accel_bias += delta.segment<3>(12);
  out.gravity = so3::exp(gravity_tangent_basis(x.gravity) * delta.segment<2>(kGravityIndex)) * x.gravity;
  return out;
}

StateVector boxminus(const NavState& a, const NavState& b) {
  StateVector d;
  d.segment<3>(0) = so3::log(b.rotation.transpose() * a.rotation);
  d.segment<3>(3) = a.position - b.position;
  d.segment<3>(6) = a.velocity - b.velocity;
  d.segment<3>(9) = a.gyro_bias - b.gyro_bias;
  d.segment<3>(12) = a.accel_bias - b.accel_bias;
  // The rotation vector taking b's gravity direction to a's, in b's tangent basis.
  const Eigen::Vector3d from = b.gravity.normalized();
  const Eigen::Vector3d to = a.gravity.normalized();
  const Eigen::Vector3d axis = from.cross(to);
  const double sine = axis.norm();
  const Eigen::Vector3d turn = sine < 1e-12 ? axis : Eigen::Vector3d(axis * (std::atan2(sine, from.dot(to)) / sine));
  d.segment<2>(kGravityIndex) = gravity_tangent_basis(b.gravity).transpose() * turn;
  return d;
}

StateCovariance imu_transition(const ImuPreintegration& pre, const NavState& start) {
  // Error-state transition over the whole interval (derived from the prediction of
  // ImuPreintegration::predict with R = R_hat Exp(dtheta), biases and gravity held constant).
  const double dt = pre.duration();
  const Eigen::Matrix3d& r = start.rotation;
  const Eigen::Matrix3d dr = pre.delta_rotation(start.gyro_bias);
  const Eigen::Vector3d dv = pre.delta_velocity(start.gyro_bias, start.accel_bias);
  const Eigen::Vector3d dp = pre.delta_position(start.gyro_bias, start.accel_bias);
  StateCovariance f = StateCovariance::Identity();
  f.block<3, 3>(0, 0) = dr.transpose();
  f.block<3, 3>(0, 9) = pre.d_rotation_d_gyro_bias();
  f.block<3, 3>(3, 0) = -r * so3::hat(dp);
  f.block<3, 3>(3, 6) = Eigen::Matrix3d::Identity() * dt;
  f.block<3, 3>(3, 9) = r * pre.d_position_d_gyro_bias();
  f.block<3, 3>(3, 12) = r * pre.d_position_d_accel_bias();
  f.block<3, 3>(6, 0) = -r * so3::hat(dv);
  f.block<3, 3>(6, 9) = r * pre.d_velocity_d_gyro_bias();
  f.block<3, 3>(6, 12) = r * pre.d_velocity_d_accel_bias();
  // Gravity acts as g dt on the velocity and g dt^2 / 2 on the position; g (+) dg = Exp(B dg) g.
  const Eigen::Matrix<double, 3, 2> d_gravity = -so3::hat(start.gravity) * gravity_tangent_basis(start.gravity);
  f.block<3, 2>(3, kGravityIndex) = 0.5 * dt * dt * d_gravity;
  f.block<3, 2>(6, kGravityIndex) = dt * d_gravity;
  return f;
}

}  // namespace liod
