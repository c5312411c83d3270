#pragma once
// Scan-to-local-map registration, tightly coupled with the IMU: an iterated error-state Kalman
// update (a Gauss-Newton MAP estimate) whose prior is the IMU-predicted state and covariance.
// The error state is error_state.hpp's; LiDAR residuals touch only the pose, and the prior's
// cross-covariances carry their information into velocity, biases and gravity.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "liod/error_state.hpp"
#include "liod/imu_preintegration.hpp"
#include "liod/map_correspondence.hpp"

namespace liod {

struct UpdateParams {
  int max_iterations = 5;
  double lidar_noise_m = 0.03;
  CorrespondenceParams correspondence;
  /// Iterations that search the map's neighbours afresh; later ones search again only if the pose
  /// moved more than research_translation_m / research_rotation_rad since the last search.
  int forced_searches = 1;
  double research_translation_m = 0.02;
  double research_rotation_rad = 0.002;
  /// Directions of the LiDAR information (eigenvalues of sum w h^T h, i.e. a weighted count of
  /// residuals) below this carry no LiDAR update: the prior holds them.
  double degeneracy_eigenvalue = 30.0;
  /// Whether those directions are also removed from the LiDAR update (else they are only counted).
  bool project_degenerate = true;
  /// Vehicle motion constraint: a wheeled vehicle's velocity has no component along its up axis
  /// (body frame), up to this std (suspension, bumps). 0: off.
  double vertical_velocity_std = 0.0;
  Eigen::Vector3d vertical_axis = Eigen::Vector3d::UnitZ();
  /// The LiDAR's origin in the body frame: edge residuals are then measured along the ray from it
  /// (line_correspondence's viewpoint). None: point-to-line distance.
  std::optional<Eigen::Vector3d> edge_viewpoint_body;
  /// With a viewpoint: an edge point whose nearest map edge points form a post is matched to the
  /// post's vertical axis (post_correspondence) before a fitted line is tried.
  std::optional<PostParams> posts;
  /// A body axis (the vehicle's forward axis) along which walls, and with ground_blind_too every
  /// plane, are not to pull: the search sets CorrespondenceParams::blind_along to it, turned
  /// into the world at the current pose.
  std::optional<Eigen::Vector3d> planes_blind_along_body;
  bool ground_blind_too = false;
};

struct UpdateResult {
  NavState state;
  StateCovariance covariance = StateCovariance::Zero();
  int residuals = 0;
  int iterations = 0;
  double rms_residual_m = 0.0;
  /// Smallest eigenvalue of the translational block of the LiDAR information (weighted count of
  /// constraints along the worst direction): low means the scene constrains the pose poorly.
  double min_translation_eigenvalue = 0.0;
  double min_rotation_eigenvalue = 0.0;
  /// How many of the 6 pose directions fell below UpdateParams::degeneracy_eigenvalue.
  int degenerate_directions = 0;
};

/// post_axis_map: the edge map's points as post axes (post_axes), for params.posts; without it
/// no edge is matched as a post.
UpdateResult iterated_update(const NavState& prior, const StateCovariance& prior_covariance,
                             const std::vector<Eigen::Vector3d>& planes_body, const LocalMap& plane_map,
                             const std::vector<Eigen::Vector3d>& edges_body, const LocalMap& edge_map,
                             const UpdateParams& params, const LocalMap* post_axis_map = nullptr);

}  // namespace liod
