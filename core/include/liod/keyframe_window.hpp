#pragma once
// The sliding window of keyframes and the local map it forms (the seed paper's module 2). A scan
// becomes a keyframe candidate after keyframe_distance_m of motion or keyframe_angle_deg of turn,
// and a keyframe when its Hausdorff distance to the last keyframe exceeds the threshold h1 (the
// paper's similarity gate: a candidate that shows the same scene adds nothing to the map). The map
// is the union of the window's keyframes in voxel hashes: planes, edges, and the edges placed on
// their posts' axes.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "liod/deskew.hpp"
#include "liod/keyframe.hpp"
#include "liod/local_map.hpp"

namespace liod {

enum class KeyframeGating { kHausdorff, kDistanceAngle };

struct KeyframeWindowConfig {
  KeyframeGating gating = KeyframeGating::kHausdorff;
  double keyframe_distance_m = 1.0;
  double keyframe_angle_deg = 10.0;
  double hausdorff_threshold_m = 0.6;  // h1
  double hausdorff_voxel_m = 1.0;      // both clouds are downsampled to this before the test
  int window_keyframes = 200;
  double map_voxel_m = 1.0;
  int map_points_per_voxel = 20;
  double map_min_point_spacing_m = 0.2;
  int map_min_observations = 1;  // LocalMap's: keyframes that must have seen a voxel before it is matched
  /// With posts: the LiDAR's origin in the body frame and how far behind an edge its post's axis
  /// lies (post_axes); none: no post map.
  std::optional<Eigen::Vector3d> post_viewpoint_body;
  double post_depth_m = 0.0;
};

class KeyframeWindow {
 public:
  explicit KeyframeWindow(const KeyframeWindowConfig& config);

  /// Adds the scan (its features at `state`) as a keyframe if the gate lets it: the first scan
  /// always. hausdorff_m: the test's distance, when it ran.
  bool consider(const DeskewedFeatures& features, const NavState& state, double& hausdorff_m);
  /// What the backend needs of the newest keyframe beyond its points: the filter's pose covariance
  /// and the IMU's measurements since the previous keyframe (keyframe.hpp).
  void set_newest_for_backend(const PoseCovariance& covariance, std::vector<ImuInterval> intervals) {
    keyframes_.back().pose_covariance = covariance;
    keyframes_.back().imu_since_previous = std::move(intervals);
  }
  /// Empties the window and the maps (the map is started afresh).
  void restart();

  const std::deque<Keyframe>& keyframes() const { return keyframes_; }
  const LocalMap& plane_map() const { return plane_map_; }
  const LocalMap& edge_map() const { return edge_map_; }
  const LocalMap& post_axis_map() const { return post_axis_map_; }

 private:
  void add(const DeskewedFeatures& features, const NavState& state, std::vector<Eigen::Vector3d> similarity_cloud);
  LocalMap empty_map() const;

  KeyframeWindowConfig config_;
  LocalMap plane_map_;
  LocalMap edge_map_;
  LocalMap post_axis_map_;  // the keyframes' post_axes_world
  std::deque<Keyframe> keyframes_;
  std::uint64_t next_id_ = 0;
};

}  // namespace liod
