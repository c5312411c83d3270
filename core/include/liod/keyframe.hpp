#pragma once
// A keyframe: a scan kept for the local map (keyframe_window.hpp) and handed to the backend.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "liod/imu_preintegration.hpp"  // NavState
#include "liod/imu_trajectory.hpp"     // ImuInterval

namespace liod {

/// A pose's covariance in the front end's error state order: [dtheta (right perturbation, body), dp (world)].
using PoseCovariance = Eigen::Matrix<double, 6, 6>;

struct Keyframe {
  std::uint64_t id = 0;
  NavState state;  // body (IMU) frame at the scan's end, on the IMU clock
  PoseCovariance pose_covariance = PoseCovariance::Zero();  // the filter's, after the scan's update; zero: unknown
  std::vector<Eigen::Vector3d> planes_world;
  std::vector<Eigen::Vector3d> edges_world;
  std::vector<Eigen::Vector3d> post_axes_world;  // edges_world placed on their posts' axes (post_axes), with posts on
  std::vector<Eigen::Vector3d> similarity_cloud_world;  // downsampled, for the Hausdorff test; the newest keyframe's only
  /// The IMU's measurements from the previous keyframe's time to this one's, as the prediction
  /// used them: the backend's preintegration factor between the two (LIO-SAM's graph). Empty when
  /// they do not measure that stretch (an IMU gap or a contradicted IMU in it, the first keyframe).
  std::vector<ImuInterval> imu_since_previous;
};

}  // namespace liod
