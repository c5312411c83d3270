#pragma once
// The algorithm's configuration (core/): the IMU's noise model, the LiDAR-IMU extrinsics, the
// front end's and the backend's settings. Each unit takes its own small config struct, filled
// from these by its owner (lidar_inertial_odometry.cpp, backend.cpp); config/ loads them from
// YAML. A default here is what a user gets without the key: keys a user sets are explained in
// config/liod.yaml, the advanced ones in config/examples/advanced.yaml, and the reasoning behind
// every value in docs/design.md ("Tuning constants").

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "liod/backend/backend_config.hpp"
#include "liod/deskew.hpp"           // DeskewMode
#include "liod/keyframe_window.hpp"  // KeyframeGating

namespace liod {

enum class CurvatureMode { kAdaptive, kFixed };
/// How an edge point's distance to its map line is measured: along the LiDAR ray (its range, which
/// the silhouette of a post or a corner does not shift with the viewpoint) or the shortest way (LOAM).
enum class EdgeResidual { kAlongRay, kPointToLine };

struct ImuConfig {
  double rate_hz = 200.0;               // nominal rate; used to detect gaps
  double gyro_noise_density = 5.0e-4;   // rad/s/sqrt(Hz)
  double accel_noise_density = 5.0e-3;  // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 5.0e-5;   // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 1.0e-2;  // m/s^3/sqrt(Hz): also absorbs scale and misalignment (config/liod.yaml)
  double gravity_m_s2 = 9.80665;
  double max_gap_s = 0.05;              // a longer gap marks the IMU as lost
  /// The IMU's measurement ranges (datasheet): a sample beyond either is no measurement (a
  /// corrupted but finite value passes an 8-bit checksum) and is dropped; one at the range is the
  /// sensor clipping and is flagged saturated. Defaults: the Xsens MTi-630's 2000 deg/s and 10 g.
  double gyro_range_rad_s = 34.91;
  double accel_range_m_s2 = 98.07;
};

struct ExtrinsicsConfig {
  /// p_imu = rotation * p_lidar + translation
  Eigen::Vector3d lidar_to_imu_translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond lidar_to_imu_rotation = Eigen::Quaterniond::Identity();
  /// t_imu = t_lidar + lidar_time_offset_s
  double lidar_time_offset_s = 0.0;
};

/// The front end's settings. What is not here is a tuning constant of the unit that uses it
/// (bias_holds.hpp, move_off.hpp, start_up.hpp, curvature_features.hpp), fixed by physics or by a
/// measurement that docs/design.md gives.
struct OdometryConfig {
  DeskewMode deskew = DeskewMode::kImu;
  CurvatureMode curvature = CurvatureMode::kAdaptive;
  KeyframeGating keyframe_gating = KeyframeGating::kHausdorff;
  double min_range_m = 2.0;          // returns closer than this are not used
  /// Self-crop: returns inside this box of the body (IMU) frame hit the vehicle itself.
  /// Disabled while min is not below max on every axis.
  Eigen::Vector3d crop_box_min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d crop_box_max_m = Eigen::Vector3d::Zero();
  double max_range_m = 120.0;
  /// The vehicle's forward direction in the body (IMU) frame, a unit vector: a rolling start
  /// searches its speed along it (a road vehicle does not slide sideways).
  Eigen::Vector3d forward_axis = Eigen::Vector3d::UnitX();
  /// The vehicle's up direction in the body (IMU) frame, a unit vector orthogonal to forward_axis.
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
  /// Std of the velocity along up_axis (a wheeled vehicle does not move along it; suspension and
  /// bumps do a little). Ties the pitch to the direction of travel. 0: constraint off.
  double vertical_velocity_std_mps = 0.05;
  /// Seconds of scan poses after which the daemon checks the configured extrinsics against an
  /// estimate from them, once (daemon/extrinsics_check.hpp); 0: no check.
  double extrinsics_check_s = 60.0;
  double occlusion_jump_m = 0.5;     // neighbour range jump that marks an occlusion edge (scaled by range)
  double edge_curvature = 0.1;       // c above this: edge candidate
  double plane_curvature = 0.05;     // c below this: planar candidate
  int sectors_per_ring = 8;
  int max_edges_per_sector = 6;
  double plane_voxel_m = 0.6;        // downsampling of the planar features of a scan
  double edge_voxel_m = 0.3;
  double map_voxel_m = 1.0;          // local map hash cell size
  int map_points_per_voxel = 20;
  double map_min_point_spacing_m = 0.2;
  int map_min_observations = 2;      // keyframes that must have seen a map voxel before it is matched (local_map.hpp)
  int max_iterations = 5;
  int forced_searches = 1;  // iterations that search the map afresh; later ones only if the pose moved
  double lidar_noise_m = 0.03;       // std of a point-to-plane/line residual
  double max_correspondence_m = 0.5; // loop registration (backend)
  int correspondence_neighbours = 8;     // map neighbours of a plane / line correspondence (front end)
  double correspondence_gate_m = 1.0;    // front end: farther map neighbours are not used
  double plane_thickness_m = 0.03;       // every neighbour within this of its fitted plane
  bool fit_uncertainty = true;           // a residual's variance includes its fitted plane's / line's uncertainty
  EdgeResidual edge_residual = EdgeResidual::kAlongRay;
  bool beam_calibration = true;  // learn each beam's elevation offset from its ground residuals (beam_calibration.hpp)
  bool beam_range_calibration = true;  // with beam_calibration: each beam's range offset too (beam_calibration.hpp)
  bool post_edges = true;  // along_ray only: edges on posts (map points one above the other) match the post's axis
  double crossing_edge_tolerance_m = 0.1;  // an edge where the ring runs off a surface across a horizontal border that the next ring carries on: dropped (0: kept)
  double post_max_width_m = 0.4;  // post_edges: an edge ending a ring's run this narrow is placed by the run's axis (0: never)
  bool move_off_planes_across = true;  // after a standstill start: walls (and once rolling, the ground) locate across the track only (move_off.hpp)
  double keyframe_distance_m = 1.0;
  double keyframe_angle_deg = 10.0;
  double hausdorff_threshold_m = 0.6; // h1
  double hausdorff_voxel_m = 1.0;     // clouds are downsampled to this before the Hausdorff test
  int window_keyframes = 200;
  double degeneracy_eigenvalue = 30.0;  // LiDAR information (weighted residual count) below which a direction is degenerate
  /// After a degenerate scan the forward accelerometer bias and gravity tilt are held, except while
  /// the vehicle turns faster than this (deg/s, IMU yaw rate): the turn separates the two. 0: always held.
  double hold_release_yaw_rate_deg_s = 5.0;
  bool degeneracy_projection = false;   // true: degenerate directions get no LiDAR update (else flagged only)
  double init_gyro_bias_std = 0.01;      // rad/s
  double init_accel_bias_std = 0.2;      // m/s^2
  double init_velocity_std = 20.0;       // m/s: unknown speed at a rolling start
  double init_tilt_std_deg = 5.0;
};

/// What the front end (LidarInertialOdometry) needs.
struct FrontEndConfig {
  ImuConfig imu;
  ExtrinsicsConfig extrinsics;
  OdometryConfig odometry;
};

/// The front end's and the backend's configuration together.
struct AlgorithmConfig : FrontEndConfig {
  BackendConfig backend;
};

}  // namespace liod
