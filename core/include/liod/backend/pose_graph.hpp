#pragma once
// The keyframe pose graph (the seed paper, loop closure): one SE(3) node per keyframe, relative-pose
// factors between consecutive keyframes (LiDAR-inertial odometry) and across loops (scan-to-map
// registration), a tilt factor per node (roll/pitch are observable from gravity in the
// tightly coupled front end, so they must not absorb a loop's correction) and the first node
// held fixed (the prior that defines the world frame). LIO-SAM's graph adds to a node its velocity
// and IMU biases and an IMU preintegration factor to its predecessor (imu_factor.hpp); a node
// reached by none keeps its pose only. Solved with Ceres; Ceres stays inside pose_graph.cpp so
// that its headers never reach the rest of liod.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "liod/imu_preintegration.hpp"

namespace liod {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Relative-pose information: residual order is [translation (m), rotation (rad, 2 * vec(dq))].
Matrix6d relative_pose_information(double translation_sigma_m, double rotation_sigma_rad);

enum class RobustLoss { kNone, kHuber, kCauchy };

struct PoseGraphFactor {
  std::size_t from = 0;  // node indices
  std::size_t to = 0;
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();  // T_from_to
  Matrix6d information = Matrix6d::Identity();
  bool loop = false;  // loop factors carry the robust loss
};

/// A node's velocity (world frame) and IMU biases: the states an IMU factor reaches.
struct NodeMotion {
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
};

/// The IMU between two nodes, preintegrated (Forster et al. eq. 45), and the biases' random walk
/// over that stretch.
struct ImuGraphFactor {
  std::size_t from = 0;
  std::size_t to = 0;
  std::shared_ptr<const ImuPreintegration> preintegration;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // in the graph's world frame
  double gyro_bias_walk_sigma = 1.0;   // rad/s over the stretch
  double accel_bias_walk_sigma = 1.0;  // m/s^2 over the stretch
};

struct SolveReport {
  double solve_ms = 0.0;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  bool converged = false;
  std::size_t nodes = 0;    // nodes optimised (not held)
  std::size_t factors = 0;  // relative-pose factors in the problem
  std::size_t imu_factors = 0;
};

class PoseGraph {
 public:
  PoseGraph() = default;

  /// Appends a node; the first node added is held fixed. Returns its index.
  std::size_t add_node(const Eigen::Isometry3d& initial);
  /// A tilt (gravity direction) measurement of a node: the world z axis seen in the body frame,
  /// R^T e_z, with a standard deviation in rad on each component.
  void set_tilt(std::size_t node, const Eigen::Vector3d& up_in_body, double sigma_rad);
  void add_factor(const PoseGraphFactor& factor);
  void set_motion(std::size_t node, const NodeMotion& motion) { motions_[node] = motion; }
  void add_imu_factor(ImuGraphFactor factor) { imu_factors_.push_back(std::move(factor)); }
  /// Moves every node rigidly into another world frame (poses, velocities, gravity): the factors
  /// are relative and stay as they are.
  void transform(const Eigen::Isometry3d& delta);
  /// Removes the most recent factor (a loop the consistency check rejected).
  void pop_factor() { factors_.pop_back(); }

  /// Solve (Levenberg-Marquardt, sparse Cholesky) from the current poses. Loop factors get
  /// `loss` with `scale` in whitened units (sigmas); kCauchy runs a Huber pass first.
  /// `first_free`: nodes before it are held at their current poses and only the factors that
  /// reach a node from it on take part (0: the full graph; node 0 is always held).
  SolveReport optimize(RobustLoss loss, double scale, int max_iterations, std::size_t first_free = 0);

  std::size_t size() const { return poses_.size(); }
  const std::vector<Eigen::Isometry3d>& poses() const { return poses_; }
  const Eigen::Isometry3d& pose(std::size_t node) const { return poses_[node]; }
  void set_pose(std::size_t node, const Eigen::Isometry3d& pose) { poses_[node] = pose; }
  const std::vector<PoseGraphFactor>& factors() const { return factors_; }
  const NodeMotion& motion(std::size_t node) const { return motions_[node]; }
  const std::vector<ImuGraphFactor>& imu_factors() const { return imu_factors_; }
  /// Whitened residual norm of a factor at the current poses (sqrt of its squared Mahalanobis distance).
  double whitened_error(const PoseGraphFactor& factor) const;
  /// The same of an IMU factor's 9 preintegration residuals [rotation, velocity, position].
  Eigen::Matrix<double, 9, 1> whitened_error(const ImuGraphFactor& factor) const;

 private:
  SolveReport solve(RobustLoss loss, double scale, int max_iterations, std::size_t first_free);

  std::vector<Eigen::Isometry3d> poses_;
  std::vector<Eigen::Vector3d> tilt_up_;
  std::vector<double> tilt_sigma_;
  std::vector<PoseGraphFactor> factors_;
  std::vector<NodeMotion> motions_;
  std::vector<ImuGraphFactor> imu_factors_;
};

}  // namespace liod
