#pragma once
// A keyframe: a scan kept for the local map (keyframe_window.hpp) and handed to the backend.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "liod/imu_preintegration.hpp"  // NavState

namespace liod {

struct Keyframe {
  std::uint64_t id = 0;
  NavState state;  // body (IMU) frame at the scan's end, on the IMU clock
  std::vector<Eigen::Vector3d> planes_world;
  std::vector<Eigen::Vector3d> edges_world;
  std::vector<Eigen::Vector3d> post_axes_world;  // edges_world placed on their posts' axes (post_axes), with posts on
  std::vector<Eigen::Vector3d> similarity_cloud_world;  // downsampled, for the Hausdorff test; the newest keyframe's only
};

}  // namespace liod
