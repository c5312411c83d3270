#pragma once
// The true continuous motion of the vehicle (IMU/body frame): uniform cubic B-splines in time for
// position and ZYX Euler angles, plus analytic high-frequency vibration. Every derivative the IMU
// reports is taken analytically from this one representation, so the IMU, the LiDAR poses and the
// ground truth agree exactly.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

namespace liod::sim {

/// Channels: x, y, z (m), roll, pitch, yaw (rad; R = Rz(yaw) Ry(pitch) Rx(roll)).
using Sample6 = std::array<double, 6>;

struct Sinusoid {
  int channel = 2;
  double amplitude = 0.0;  // m or rad
  double frequency = 0.0;  // Hz
  double phase = 0.0;
};

struct BodyState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      // world
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      // world
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // world, kinematic (no gravity)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // world_from_body
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // body frame
};

struct Pose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

class Trajectory {
 public:
  /// samples[k] is the control value at time t0 + k * dt.
  Trajectory(double t0, double dt, std::vector<Sample6> samples, std::vector<Sinusoid> vibration);

  BodyState state(double t) const;
  Pose pose(double t) const;
  /// Range of times that can be evaluated.
  double begin_time() const { return t0_ + dt_; }
  double end_time() const { return t0_ + dt_ * static_cast<double>(samples_.size() - 3); }

 private:
  void channels(double t, int order, Sample6& v, Sample6& d, Sample6& dd) const;

  double t0_;
  double dt_;
  std::vector<Sample6> samples_;
  std::vector<Sinusoid> vibration_;
};

Eigen::Matrix3d rotation_from_euler(double roll, double pitch, double yaw);

}  // namespace liod::sim
