#include "liod/imu_preintegration.hpp"

#include "liod/so3.hpp"

namespace liod {

ImuPreintegration::ImuPreintegration(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias,
                                     const ImuNoise& noise)
    : noise_(noise), gyro_bias_(gyro_bias), accel_bias_(accel_bias) {}

void ImuPreintegration::reset() {
  duration_ = 0.0;
  delta_r_.setIdentity();
  delta_v_.setZero();
  delta_p_.setZero();
  covariance_.setZero();
  dR_dbg_.setZero();
  dv_dbg_.setZero();
  dv_dba_.setZero();
  dp_dbg_.setZero();
  dp_dba_.setZero();
}

void ImuPreintegration::integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt) {
  if (!(dt > 0.0)) return;
  intervals_.push_back({gyro, accel, dt});
  integrate_interval(intervals_.back());
}

void ImuPreintegration::repropagate(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias) {
  gyro_bias_ = gyro_bias;
  accel_bias_ = accel_bias;
  reset();
  for (const auto& interval : intervals_) integrate_interval(interval);
}

void ImuPreintegration::integrate_interval(const Interval& interval) {
  const double dt = interval.dt;
  const Eigen::Vector3d w = interval.gyro - gyro_bias_;
  const Eigen::Vector3d a = interval.accel - accel_bias_;
  const Eigen::Matrix3d step_r = so3::exp(w * dt);
  const Eigen::Matrix3d jr = so3::right_jacobian(w * dt);
  const Eigen::Matrix3d a_hat = so3::hat(a);

  // Noise propagation, eq. (62)-(63): A and B use the rotation before this step.
  Eigen::Matrix<double, 9, 9> A = Eigen::Matrix<double, 9, 9>::Identity();
  A.block<3, 3>(0, 0) = step_r.transpose();
  A.block<3, 3>(3, 0) = -delta_r_ * a_hat * dt;
  A.block<3, 3>(6, 0) = -0.5 * delta_r_ * a_hat * dt * dt;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt;
  Eigen::Matrix<double, 9, 6> B = Eigen::Matrix<double, 9, 6>::Zero();
  B.block<3, 3>(0, 0) = jr * dt;
  B.block<3, 3>(3, 3) = delta_r_ * dt;
  B.block<3, 3>(6, 3) = 0.5 * delta_r_ * dt * dt;
  // Continuous densities to discrete per-sample variances.
  Eigen::Matrix<double, 6, 6> measurement_cov = Eigen::Matrix<double, 6, 6>::Zero();
  measurement_cov.diagonal().head<3>().setConstant(noise_.gyro_noise_density * noise_.gyro_noise_density / dt);
  measurement_cov.diagonal().tail<3>().setConstant(noise_.accel_noise_density * noise_.accel_noise_density / dt);
  covariance_ = A * covariance_ * A.transpose() + B * measurement_cov * B.transpose();

  // Bias Jacobians (Forster appendix B), position first: it uses the previous velocity terms.
  dp_dba_ += dv_dba_ * dt - 0.5 * delta_r_ * dt * dt;
  dp_dbg_ += dv_dbg_ * dt - 0.5 * delta_r_ * a_hat * dR_dbg_ * dt * dt;
  dv_dba_ -= delta_r_ * dt;
  dv_dbg_ -= delta_r_ * a_hat * dR_dbg_ * dt;
  dR_dbg_ = step_r.transpose() * dR_dbg_ - jr * dt;

  // Increments, eq. (24)-(26).
  delta_p_ += delta_v_ * dt + 0.5 * delta_r_ * a * dt * dt;
  delta_v_ += delta_r_ * a * dt;
  delta_r_ = so3::normalize(delta_r_ * step_r);
  duration_ += dt;
}

Eigen::Matrix3d ImuPreintegration::delta_rotation(const Eigen::Vector3d& gyro_bias) const {
  return delta_r_ * so3::exp(dR_dbg_ * (gyro_bias - gyro_bias_));
}

Eigen::Vector3d ImuPreintegration::delta_velocity(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias) const {
  return delta_v_ + dv_dbg_ * (gyro_bias - gyro_bias_) + dv_dba_ * (accel_bias - accel_bias_);
}

Eigen::Vector3d ImuPreintegration::delta_position(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias) const {
  return delta_p_ + dp_dbg_ * (gyro_bias - gyro_bias_) + dp_dba_ * (accel_bias - accel_bias_);
}

NavState ImuPreintegration::predict(const NavState& start, const Eigen::Vector3d& gravity) const {
  const double dt = duration_;
  NavState end = start;
  end.time = start.time + dt;
  end.rotation = so3::normalize(start.rotation * delta_rotation(start.gyro_bias));
  end.velocity = start.velocity + gravity * dt + start.rotation * delta_velocity(start.gyro_bias, start.accel_bias);
  end.position = start.position + start.velocity * dt + 0.5 * gravity * dt * dt +
                 start.rotation * delta_position(start.gyro_bias, start.accel_bias);
  return end;
}

}  // namespace liod
