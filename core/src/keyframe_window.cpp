#include "liod/keyframe_window.hpp"

#include "liod/angles.hpp"
#include "liod/hausdorff.hpp"
#include "liod/map_correspondence.hpp"
#include "liod/so3.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace {

std::vector<Eigen::Vector3d> transformed(const std::vector<Eigen::Vector3d>& points, const NavState& s) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(s.to_world(p));
  return out;
}

// The scan's features in the world, downsampled for the Hausdorff test.
std::vector<Eigen::Vector3d> similarity_cloud(const DeskewedFeatures& features, const NavState& state, double voxel_m) {
  std::vector<Eigen::Vector3d> cloud = transformed(features.planes, state);
  const auto edges = transformed(features.edges, state);
  cloud.insert(cloud.end(), edges.begin(), edges.end());
  return voxel_downsample(cloud, voxel_m);
}

}  // namespace

KeyframeWindow::KeyframeWindow(const KeyframeWindowConfig& config)
    : config_(config), plane_map_(empty_map()), edge_map_(empty_map()), post_axis_map_(empty_map()) {}

LocalMap KeyframeWindow::empty_map() const {
  return LocalMap(config_.map_voxel_m, config_.map_points_per_voxel, config_.map_min_point_spacing_m,
                  config_.map_min_observations);
}

void KeyframeWindow::restart() {
  keyframes_.clear();
  plane_map_ = empty_map();
  edge_map_ = plane_map_;
  post_axis_map_ = plane_map_;
}

bool KeyframeWindow::consider(const DeskewedFeatures& features, const NavState& state, double& hausdorff_m) {
  if (keyframes_.empty()) {
    add(features, state, similarity_cloud(features, state, config_.hausdorff_voxel_m));
    return true;
  }
  const NavState& last = keyframes_.back().state;
  const double distance = (state.position - last.position).norm();
  const double angle = so3::log(last.rotation.transpose() * state.rotation).norm();
  if (distance < config_.keyframe_distance_m && angle < config_.keyframe_angle_deg * kDegToRad) return false;
  std::vector<Eigen::Vector3d> cloud = similarity_cloud(features, state, config_.hausdorff_voxel_m);
  if (config_.gating == KeyframeGating::kHausdorff) {
    hausdorff_m = hausdorff_distance(cloud, keyframes_.back().similarity_cloud_world, 4.0 * config_.hausdorff_threshold_m);
    if (hausdorff_m <= config_.hausdorff_threshold_m) return false;
  }
  add(features, state, std::move(cloud));
  return true;
}

void KeyframeWindow::add(const DeskewedFeatures& features, const NavState& state,
                         std::vector<Eigen::Vector3d> similarity_cloud_world) {
  // Only the newest keyframe's similarity cloud and IMU stretch are read (the next candidate's
  // Hausdorff test, the backend's copy): the window's older ones let theirs go.
  if (!keyframes_.empty()) {
    keyframes_.back().similarity_cloud_world.clear();
    keyframes_.back().similarity_cloud_world.shrink_to_fit();
    keyframes_.back().imu_since_previous.clear();
    keyframes_.back().imu_since_previous.shrink_to_fit();
  }
  Keyframe kf;
  kf.id = next_id_++;
  kf.state = state;
  kf.planes_world = transformed(features.map_planes, state);
  kf.edges_world = transformed(features.edges, state);
  kf.similarity_cloud_world = std::move(similarity_cloud_world);
  plane_map_.add(kf.planes_world, kf.id);
  edge_map_.add(kf.edges_world, kf.id);
  if (config_.post_viewpoint_body) {
    kf.post_axes_world = post_axes(kf.edges_world, state.to_world(*config_.post_viewpoint_body),
                                   -state.gravity.normalized(), config_.post_depth_m);
    post_axis_map_.add(kf.post_axes_world, kf.id);
  }
  keyframes_.push_back(std::move(kf));
  while (keyframes_.size() > static_cast<std::size_t>(config_.window_keyframes)) {
    const Keyframe& oldest = keyframes_.front();
    plane_map_.remove_keyframe(oldest.planes_world, oldest.id);
    edge_map_.remove_keyframe(oldest.edges_world, oldest.id);
    post_axis_map_.remove_keyframe(oldest.post_axes_world, oldest.id);
    keyframes_.pop_front();
  }
}

}  // namespace liod
