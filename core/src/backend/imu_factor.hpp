#pragma once
// The IMU preintegration factor between two keyframe states (Forster, Carlone, Dellaert,
// Scaramuzza, TRO 2016, eq. 45; LIO-SAM's graph), for Ceres' automatic differentiation:
//   r_R = Log(dR(b_g)^T R_i^T R_j)
//   r_v = R_i^T (v_j - v_i - g dt) - dv(b_g, b_a)
//   r_p = R_i^T (p_j - p_i - v_i dt - g dt^2 / 2) - dp(b_g, b_a)
// whitened by the preintegration's covariance, with the increments corrected to first order for
// the bias estimate of node i (eq. 44), and the biases' random walk between the two nodes. Private
// to pose_graph.cpp (Ceres' rotation helpers stay out of every header).

#include <ceres/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "liod/backend/pose_graph.hpp"

namespace liod {

class ImuError {
 public:
  explicit ImuError(const ImuGraphFactor& f) : dt_(f.preintegration->duration()), gravity_(f.gravity) {
    const ImuPreintegration& pre = *f.preintegration;
    gyro_bias_ = pre.linearization_gyro_bias();
    accel_bias_ = pre.linearization_accel_bias();
    delta_rotation_ = Eigen::Quaterniond(pre.delta_rotation(gyro_bias_)).normalized();
    delta_velocity_ = pre.delta_velocity(gyro_bias_, accel_bias_);
    delta_position_ = pre.delta_position(gyro_bias_, accel_bias_);
    dr_dbg_ = pre.d_rotation_d_gyro_bias();
    dv_dbg_ = pre.d_velocity_d_gyro_bias();
    dv_dba_ = pre.d_velocity_d_accel_bias();
    dp_dbg_ = pre.d_position_d_gyro_bias();
    dp_dba_ = pre.d_position_d_accel_bias();
    // L with L^T L = covariance^-1; a floor on the diagonal keeps a short stretch's (nearly
    // noiseless) increments from an infinite weight.
    Eigen::Matrix<double, 9, 9> covariance = pre.covariance();
    covariance.diagonal().array() += 1e-12;
    const Eigen::Matrix<double, 9, 9> information = covariance.inverse();
    sqrt_information_ = Eigen::LLT<Eigen::Matrix<double, 9, 9>>(0.5 * (information + information.transpose())).matrixL().transpose();
    inverse_bias_sigma_ << Eigen::Vector3d::Constant(1.0 / f.gyro_bias_walk_sigma), Eigen::Vector3d::Constant(1.0 / f.accel_bias_walk_sigma);
  }

  // Parameters: q (x, y, z, w), p, v, b = (b_g, b_a) of node i, then of node j.
  template <typename T>
  bool operator()(const T* qi_ptr, const T* pi_ptr, const T* vi_ptr, const T* bi_ptr, const T* qj_ptr, const T* pj_ptr,
                  const T* vj_ptr, const T* bj_ptr, T* residual_ptr) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_i(qi_ptr), q_j(qj_ptr);
    const Eigen::Map<const Vec3> p_i(pi_ptr), v_i(vi_ptr), p_j(pj_ptr), v_j(vj_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 6, 1>> b_i(bi_ptr), b_j(bj_ptr);
    const Vec3 dbg = b_i.template head<3>() - gyro_bias_.cast<T>();
    const Vec3 dba = b_i.template tail<3>() - accel_bias_.cast<T>();

    // dR(b_g) = dR Exp(J_R dbg), eq. 44.
    const Vec3 rotation_correction = dr_dbg_.cast<T>() * dbg;
    T correction_wxyz[4];
    ceres::AngleAxisToQuaternion(rotation_correction.data(), correction_wxyz);
    const Eigen::Quaternion<T> correction(correction_wxyz[0], correction_wxyz[1], correction_wxyz[2], correction_wxyz[3]);
    const Eigen::Quaternion<T> delta_rotation = delta_rotation_.cast<T>() * correction;
    const Vec3 delta_velocity = delta_velocity_.cast<T>() + dv_dbg_.cast<T>() * dbg + dv_dba_.cast<T>() * dba;
    const Vec3 delta_position = delta_position_.cast<T>() + dp_dbg_.cast<T>() * dbg + dp_dba_.cast<T>() * dba;

    const Eigen::Quaternion<T> q_i_inverse = q_i.conjugate();
    const Vec3 g = gravity_.cast<T>();
    const T dt(dt_);
    Eigen::Quaternion<T> rotation_error = delta_rotation.conjugate() * q_i_inverse * q_j;
    if (rotation_error.w() < T(0)) rotation_error.coeffs() = -rotation_error.coeffs();
    Eigen::Matrix<T, 9, 1> r;
    r.template head<3>() = T(2.0) * rotation_error.vec();
    r.template segment<3>(3) = q_i_inverse * (v_j - v_i - g * dt) - delta_velocity;
    r.template tail<3>() = q_i_inverse * (p_j - p_i - v_i * dt - T(0.5) * g * dt * dt) - delta_position;

    Eigen::Map<Eigen::Matrix<T, 15, 1>> residual(residual_ptr);
    residual.template head<9>() = sqrt_information_.cast<T>() * r;
    residual.template tail<6>() = (b_j - b_i).cwiseProduct(inverse_bias_sigma_.cast<T>());
    return true;
  }

 private:
  double dt_;
  Eigen::Vector3d gravity_;
  Eigen::Vector3d gyro_bias_, accel_bias_;
  Eigen::Quaterniond delta_rotation_;
  Eigen::Vector3d delta_velocity_, delta_position_;
  Eigen::Matrix3d dr_dbg_, dv_dbg_, dv_dba_, dp_dbg_, dp_dba_;
  Eigen::Matrix<double, 9, 9> sqrt_information_;
  Eigen::Matrix<double, 6, 1> inverse_bias_sigma_;
};

}  // namespace liod
