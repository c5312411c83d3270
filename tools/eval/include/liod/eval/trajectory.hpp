#pragma once
// A trajectory as the evaluator sees it: poses of the body in a world frame, optionally stamped.

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

namespace liod::eval {

using Poses = std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>>;

struct Trajectory {
  /// Where the poses came from, for messages ("gt.txt").
  std::string name;
  /// Seconds; empty when the source had no time (KITTI without a times file).
  std::vector<double> stamps;
  /// World-from-body transforms; rotations are exactly orthonormal (readers project onto SO(3)).
  Poses poses;

  [[nodiscard]] bool has_stamps() const { return !stamps.empty(); }
  [[nodiscard]] std::size_t size() const { return poses.size(); }
};

/// Cumulative path length of the positions: d[0] = 0, d[i] = d[i-1] + |p_i - p_{i-1}|.
std::vector<double> path_distances(const Poses& poses);

/// Rotation angle of R in radians, in [0, pi].
/// Uses atan2(|vee(R - R^T)|/2, (tr R - 1)/2): the same angle as KITTI's and evo's acos((tr R - 1)/2),
/// but without acos's loss of precision near 0, where all good trajectories live.
double rotation_angle(const Eigen::Matrix3d& R);

}  // namespace liod::eval
