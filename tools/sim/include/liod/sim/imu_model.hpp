#pragma once
// A typical automotive MEMS IMU: white noise, bias random walk, bias instability (first-order
// Gauss-Markov), a turn-on bias, small scale-factor and axis-misalignment errors, all applied to
// the exact angular rate and specific force of the true trajectory.

#include <Eigen/Core>
#include <cstdint>

#include "liod/sim/rng.hpp"
#include "liod/sim/trajectory.hpp"

namespace liod::sim {

constexpr double kGravity = 9.80665;

struct ImuNoise {
  bool enabled = true;
  double gyro_noise_density = 5.8e-5;      // rad/s/sqrt(Hz)  (0.2 deg/sqrt(h) ARW)
  double gyro_bias_random_walk = 2.0e-5;   // rad/s^2/sqrt(Hz)
  double gyro_bias_instability = 2.4e-5;   // rad/s (5 deg/h), correlation time below
  double gyro_turn_on_min = 0.1;           // deg/s per axis, random sign
  double gyro_turn_on_max = 0.3;
  double accel_noise_density = 1.3e-3;     // m/s^2/sqrt(Hz)  (0.078 m/s/sqrt(h) VRW)
  double accel_bias_random_walk = 4.0e-4;  // m/s^3/sqrt(Hz)
  double accel_bias_instability = 5.0e-4;  // m/s^2 (50 ug)
  double accel_turn_on_min = 0.05;         // m/s^2 per axis, random sign
  double accel_turn_on_max = 0.10;
  double bias_correlation_time = 300.0;    // s
  double gyro_scale_sigma = 3.0e-4;        // 300 ppm
  double accel_scale_sigma = 5.0e-4;
  double misalignment_sigma = 5.0e-4;      // rad (0.03 deg) cross-axis

  /// A consumer-grade MEMS IMU, the Bosch BMI088 (liod-sim --imu-grade consumer), from its data
  /// sheet (BST-BMI088-DS001); imu_model.cpp gives each figure and its conversion.
  static ImuNoise bmi088();
};

struct ImuReading {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
};

/// The exact specific force and angular rate in the body frame: f = R^T (a - g), g = (0,0,-9.80665).
ImuReading ideal_imu(const BodyState& state);

class ImuModel {
 public:
  ImuModel(const ImuNoise& noise, double rate_hz, std::uint64_t seed);
  /// Next sample; call once per sample in time order.
  ImuReading measure(const BodyState& state);

  Eigen::Vector3d initial_gyro_bias() const { return gyro_bias0_; }
  Eigen::Vector3d initial_accel_bias() const { return accel_bias0_; }
  const Eigen::Matrix3d& gyro_error_matrix() const { return gyro_m_; }
  const Eigen::Matrix3d& accel_error_matrix() const { return accel_m_; }

 private:
  Eigen::Vector3d gaussian3(double sigma);

  ImuNoise noise_;
  double dt_;
  Rng rng_;
  Eigen::Matrix3d gyro_m_ = Eigen::Matrix3d::Identity();   // scale and misalignment
  Eigen::Matrix3d accel_m_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d gyro_bias0_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias0_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_rw_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_rw_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_gm_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_gm_ = Eigen::Vector3d::Zero();
};

}  // namespace liod::sim
