#pragma once
// The backend's configuration: loop closure, the pose graph and the state it keeps
// (docs/backend.md).

#include "liod/backend/scan_context.hpp"

namespace liod {

enum class LoopDistance { k2D, k3D };
/// How the odometry factors between consecutive keyframes are weighted: by the front end's pose
/// covariance (odometry_factor.hpp), or by the fixed sigmas below (LIO-SAM).
enum class OdometryWeights { kCovariance, kFixed };
/// map: build the map, continuing a saved one once relocalised in it; localise: track in the saved
/// map without adding to it (no keyframes persisted, no loops of its own, the map matched instead).
enum class BackendMode { kMap, kLocalize };

/// Relocalisation in a saved map (relocalization.hpp).
struct RelocalizationConfig {
  ScanContextConfig scan_context;
  // Each saved keyframe is also described as if seen this far to its left and right (Scan
  // Context++'s augmentation, Kim et al. 2021): the descriptor changes fast with a sideways
  // offset, and a second drive is often a lane or the opposite carriageway away.
  double lateral_offset_m = 3.5;
  int verified_candidates = 3;      // the best places registered per attempt
  // Scan Context distance beyond which a place is not verified: columns that disagree more than
  // they agree (a mean angle between height profiles beyond 60 degrees).
  double max_descriptor_distance = 0.5;
  double interval_s = 0.5;          // keyframe time between attempts (bounds the backend's load)
  int submap_keyframes = 15;        // saved keyframes nearest the place form its sub-map
  // The similarity test's threshold here: another drive sees a place from another lane or
  // direction, so a true pair's partial Hausdorff distance is larger than a loop's (the same lane
  // again); registration fit and the two-placement gate carry the rejection of wrong places.
  double similarity_threshold_m = 2.0;
  // Without a prior to fall back on, the fit must be a match's, not a look-alike street's: the
  // residual within about 1.5 LiDAR noise sigmas (the loop's 0.1 m is for a revisit the odometry
  // already puts nearby). The inlier fraction stays the loop's: a street driven the other way
  // sees the other faces of what stands in it, and half its plane points find no plane.
  double max_rms_m = 0.05;
  double min_inlier_fraction = 0.5;
  // A placement is accepted when a second one, from a later keyframe at least min_travel_m on,
  // agrees with it: one registration can fit a repetitive street wrongly, two far apart rarely do.
  double min_travel_m = 3.0;
  double agreement_m = 0.3;
  double agreement_deg = 1.0;
  double match_interval_s = 1.0;    // localise mode: keyframe time between matches on the map
};

/// The backend (issue 5): keyframe pose graph, loop closure, maps. See docs/backend.md.
struct BackendConfig {
  bool enabled = false;
  double loop_radius_m = 10.0;          // candidates within this distance of the current keyframe...
  double loop_time_gap_s = 20.0;        // ...and at least this much older
  LoopDistance loop_distance = LoopDistance::k2D;  // 2d: x-y distance (the paper) | 3d (ablation)
  int loop_candidates = 2;              // candidates verified per keyframe (nearest first, distinct passes)
  int loop_cooldown_keyframes = 3;      // keyframes without loop search after an accepted loop
  int submap_keyframes = 10;            // the candidate's sub-map: candidate +- this many keyframes
  bool similarity_check = true;         // the Hausdorff similarity test before registration (ablation)
  double similarity_threshold_m = 1.0;  // partial Hausdorff distance above which a pair is dissimilar
  double similarity_quantile = 0.8;     // quantile of the nearest distances (1 = classic Hausdorff)
  double similarity_search_m = 3.0;     // coarse alignment search, +- in x and y
  double similarity_search_yaw_deg = 3.0;  // and in yaw
  double loop_max_rms_m = 0.1;          // registration accepted below this point-to-plane rms...
  double loop_min_inlier_fraction = 0.5;  // ...with at least this fraction of the points within 2 rms
  double max_vertical_m = 1.5;          // registered height minus graph height beyond this: false loop
  double max_tilt_deg = 2.0;            // registered vs graph tilt (roll/pitch) beyond this: false loop
  double robust_loss_scale = 3.0;       // Cauchy scale of the loop factors, in sigmas
  OdometryWeights odometry_weights = OdometryWeights::kCovariance;
  double odometry_translation_sigma_m = 0.05;  // odometry factor between consecutive keyframes (fixed weights)
  double odometry_rotation_sigma_deg = 0.1;
  double loop_translation_sigma_m = 0.03;      // loop factor: ~2x the registration error measured on the sim drives
  double loop_rotation_sigma_deg = 0.1;
  double tilt_sigma_deg = 0.5;          // gravity (roll/pitch) factor per keyframe; 0 = none
  bool imu_factors = false;             // IMU preintegration factors, velocity and bias states (LIO-SAM's graph)
  int max_solver_iterations = 50;
  int solve_window_keyframes = 1000;    // a loop's solve frees at most this many newest keyframes; 0 = all
  double keyframe_voxel_m = 0.3;        // keyframe points kept by the backend (body frame)
  double map_voxel_m = 0.3;             // downsampling of the global map PCD
  bool persist = false;                 // write keyframes + graph to output.state_dir (atomically)
  int memory_keyframes = 200;           // keyframe clouds kept in memory (LRU); others on disk; 0 = all in memory
  BackendMode mode = BackendMode::kMap;
  RelocalizationConfig relocalization;
};

}  // namespace liod
