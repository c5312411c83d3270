#pragma once
// On-manifold IMU preintegration (Forster, Carlone, Dellaert, Scaramuzza, TRO 2016).
// Integrates the measurements between two times into relative motion increments that do not
// depend on the start state, with their covariance and first-order Jacobians w.r.t. the biases,
// so a bias update corrects the increments without re-integrating (eq. 44); a large update
// calls repropagate() with the stored samples.

#include <Eigen/Core>
#include <vector>

#include "liod/types.hpp"

namespace liod {

struct ImuNoise {
  double gyro_noise_density = 2.0e-3;   // rad/s/sqrt(Hz)
  double accel_noise_density = 2.0e-2;  // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 5.0e-5;
  double accel_bias_random_walk = 1.0e-3;
};

/// Navigation state of the body (IMU) frame in the gravity-aligned world frame.
struct NavState {
  double time = 0.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // R_world_body
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  /// Gravity in the world frame. The world is the first pose's frame, levelled by the start-up
  /// alignment, which takes the accelerometer's turn-on bias for tilt (0.3-0.6 deg a 0.05-0.1 m/s^2
  /// bias, more at a rolling start): the odometry estimates its direction (FAST-LIO2's S2 state).
  Eigen::Vector3d gravity{0.0, 0.0, -9.80665};

  /// A point given in the body frame, in the world.
  Eigen::Vector3d to_world(const Eigen::Vector3d& body_point) const { return rotation * body_point + position; }
};

class ImuPreintegration {
 public:
  ImuPreintegration(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias, const ImuNoise& noise);

  /// Adds one interval of duration dt measured with constant gyro/accel (Forster eqs. 24-26, 62-63).
  void integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt);

  /// Re-integrates all stored intervals with new linearisation biases.
  void repropagate(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias);

  /// Increments corrected to first order for biases that differ from the linearisation point (eq. 44).
  Eigen::Matrix3d delta_rotation(const Eigen::Vector3d& gyro_bias) const;
  Eigen::Vector3d delta_velocity(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias) const;
  Eigen::Vector3d delta_position(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias) const;

  /// The state at the end of the interval from the state at its start (eq. 33); biases stay constant.
  NavState predict(const NavState& start, const Eigen::Vector3d& gravity) const;

  double duration() const { return duration_; }
  /// Covariance of the increment noise [dphi, dv, dp] (eq. 63).
  const Eigen::Matrix<double, 9, 9>& covariance() const { return covariance_; }
  const Eigen::Matrix3d& d_rotation_d_gyro_bias() const { return dR_dbg_; }
  const Eigen::Matrix3d& d_velocity_d_gyro_bias() const { return dv_dbg_; }
  const Eigen::Matrix3d& d_velocity_d_accel_bias() const { return dv_dba_; }
  const Eigen::Matrix3d& d_position_d_gyro_bias() const { return dp_dbg_; }
  const Eigen::Matrix3d& d_position_d_accel_bias() const { return dp_dba_; }
  const Eigen::Vector3d& linearization_gyro_bias() const { return gyro_bias_; }
  const Eigen::Vector3d& linearization_accel_bias() const { return accel_bias_; }

 private:
  struct Interval {
    Eigen::Vector3d gyro;
    Eigen::Vector3d accel;
    double dt;
  };
  void reset();
  void integrate_interval(const Interval& interval);

  ImuNoise noise_;
  Eigen::Vector3d gyro_bias_;
  Eigen::Vector3d accel_bias_;
  std::vector<Interval> intervals_;
  double duration_ = 0.0;
  Eigen::Matrix3d delta_r_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d delta_v_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d delta_p_ = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 9, 9> covariance_ = Eigen::Matrix<double, 9, 9>::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dba_ = Eigen::Matrix3d::Zero();
};

}  // namespace liod
