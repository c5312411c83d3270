#include "liod/unit_configs.hpp"

namespace liod {

ImuNoise imu_noise(const ImuConfig& imu) {
  ImuNoise noise;
  noise.gyro_noise_density = imu.gyro_noise_density;
  noise.accel_noise_density = imu.accel_noise_density;
  noise.gyro_bias_random_walk = imu.gyro_bias_random_walk;
  noise.accel_bias_random_walk = imu.accel_bias_random_walk;
  return noise;
}

FeatureParams feature_params(const FrontEndConfig& config) {
  const OdometryConfig& o = config.odometry;
  const ExtrinsicsConfig& extrinsics = config.extrinsics;
  FeatureParams p;
  p.neighbourhood = o.curvature == CurvatureMode::kAdaptive ? CurvatureNeighbourhood::kDistanceAdaptive
                                                             : CurvatureNeighbourhood::kFixed;
  p.min_range_m = o.min_range_m;
  p.max_range_m = o.max_range_m;
  p.occlusion_jump_m = o.occlusion_jump_m;
  p.edge_curvature = o.edge_curvature;
  p.plane_curvature = o.plane_curvature;
  p.sectors_per_ring = o.sectors_per_ring;
  p.max_edges_per_sector = o.max_edges_per_sector;
  p.post_max_width_m = o.post_edges ? o.post_max_width_m : 0.0;
  p.crossing_edge_tolerance_m = o.crossing_edge_tolerance_m;
  if ((o.crop_box_min_m.array() < o.crop_box_max_m.array()).all()) {
    CropBox box;
    box.sensor_to_body.linear() = extrinsics.lidar_to_imu_rotation.toRotationMatrix().cast<float>();
    box.sensor_to_body.translation() = extrinsics.lidar_to_imu_translation.cast<float>();
    box.min = o.crop_box_min_m.cast<float>();
    box.max = o.crop_box_max_m.cast<float>();
    p.self_crop = box;
  }
  return p;
}

StartUpConfig start_up_config(const FrontEndConfig& config) {
  const OdometryConfig& o = config.odometry;
  StartUpConfig s;
  s.forward_axis = o.forward_axis;
  s.up_axis = o.up_axis;
  s.lidar_to_imu = {config.extrinsics.lidar_to_imu_rotation, config.extrinsics.lidar_to_imu_translation};
  s.lidar_time_offset_s = config.extrinsics.lidar_time_offset_s;
  s.min_range_m = o.min_range_m;
  s.self_crop = feature_params(config).self_crop;
  s.gyro_noise_density = config.imu.gyro_noise_density;
  s.max_imu_gap_s = config.imu.max_gap_s;
  s.gravity_m_s2 = config.imu.gravity_m_s2;
  s.tilt_std_deg = o.init_tilt_std_deg;
  s.velocity_std = o.init_velocity_std;
  s.gyro_bias_std = o.init_gyro_bias_std;
  s.accel_bias_std = o.init_accel_bias_std;
  return s;
}

BiasHoldConfig bias_hold_config(const OdometryConfig& o) {
  BiasHoldConfig h;
  h.forward_axis = o.forward_axis;
  h.up_axis = o.up_axis;
  h.degeneracy_eigenvalue = o.degeneracy_eigenvalue;
  h.release_yaw_rate_deg_s = o.hold_release_yaw_rate_deg_s;
  return h;
}

MoveOffConfig move_off_config(const OdometryConfig& o) {
  MoveOffConfig m;
  m.enabled = o.move_off_planes_across;
  m.forward_axis = o.forward_axis;
  m.up_axis = o.up_axis;
  return m;
}

UpdateParams update_params(const FrontEndConfig& config) {
  const OdometryConfig& o = config.odometry;
  UpdateParams u;
  u.max_iterations = o.max_iterations;
  u.forced_searches = o.forced_searches;
  u.lidar_noise_m = o.lidar_noise_m;
  u.correspondence.neighbours = o.correspondence_neighbours;
  u.correspondence.max_distance_m = o.correspondence_gate_m;
  u.correspondence.max_plane_thickness_m = o.plane_thickness_m;
  u.correspondence.fit_uncertainty = o.fit_uncertainty;
  if (o.edge_residual == EdgeResidual::kAlongRay) {
    u.edge_viewpoint_body = config.extrinsics.lidar_to_imu_translation;
    if (o.post_edges) u.posts = PostParams{};
  }
  u.degeneracy_eigenvalue = o.degeneracy_eigenvalue;
  u.project_degenerate = o.degeneracy_projection;
  u.vertical_velocity_std = o.vertical_velocity_std_mps;
  u.vertical_axis = o.up_axis;
  return u;
}

ReinitializationConfig reinitialization_config(const OdometryConfig& o, const StateLimits& limits) {
  ReinitializationConfig r;
  r.registration_basin_m = o.correspondence_gate_m;
  r.limits = limits;
  return r;
}

KeyframeWindowConfig keyframe_window_config(const OdometryConfig& o, const UpdateParams& update) {
  KeyframeWindowConfig k;
  k.gating = o.keyframe_gating;
  k.keyframe_distance_m = o.keyframe_distance_m;
  k.keyframe_angle_deg = o.keyframe_angle_deg;
  k.hausdorff_threshold_m = o.hausdorff_threshold_m;
  k.hausdorff_voxel_m = o.hausdorff_voxel_m;
  k.window_keyframes = o.window_keyframes;
  k.map_voxel_m = o.map_voxel_m;
  k.map_points_per_voxel = o.map_points_per_voxel;
  k.map_min_point_spacing_m = o.map_min_point_spacing_m;
  k.map_min_observations = o.map_min_observations;
  if (update.posts) {
    k.post_viewpoint_body = update.edge_viewpoint_body;
    k.post_depth_m = update.posts->depth_m;
  }
  return k;
}

}  // namespace liod
