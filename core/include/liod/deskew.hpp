#pragma once
// IMU deskew (the seed paper's module 1; LIO-SAM's imageProjection): every feature point is moved
// into the body frame at the scan's end with the body pose at the instant it was measured. A car
// at 15 m/s moves 1.5 m during one 0.1 s sweep; without this a scan's start and end disagree by
// that much (the ablation without deskew: docs/design.md).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "liod/beam_calibration.hpp"
#include "liod/curvature_features.hpp"
#include "liod/imu_trajectory.hpp"
#include "liod/types.hpp"

namespace liod {

enum class DeskewMode { kImu, kConstantVelocity, kNone };

/// A map plane point's beam and where that beam saw it (LiDAR frame), for the beam calibration.
struct RingPoint {
  std::uint16_t ring;
  Eigen::Vector3d lidar;
};

/// A scan's features in the body frame at its end.
struct DeskewedFeatures {
  std::vector<Eigen::Vector3d> planes;         // registration queries (sparse)
  std::vector<Eigen::Vector3d> edges;
  std::vector<Eigen::Vector3d> map_planes;     // what a keyframe adds to the map (denser)
  std::vector<RingPoint> map_plane_sources;    // each map plane point's beam and LiDAR-frame point
};

struct DeskewParams {
  double map_min_point_spacing_m = 0.2;  // the map's point spacing: planes are first thinned to it
  double plane_voxel_m = 0.6;            // the registration's plane queries: one per voxel
  double edge_voxel_m = 0.3;
};

/// The body pose, relative to the pose at t_end, at each time of the sweep [t_start, t_end] (IMU
/// clock). kImu integrates the IMU intervals from `start` (end: the predicted end state);
/// kConstantVelocity takes the end state's velocity and `angular_rate` (body frame) through the
/// sweep (LOAM's assumption); kNone leaves the points where they were measured.
PoseTable deskew_trajectory(DeskewMode mode, double t_start, double t_end, const NavState& start, const NavState& end,
                            const std::vector<ImuInterval>& intervals, const Eigen::Vector3d& angular_rate);

/// The scan's features (indices into scan.points) corrected by the beam calibration and deskewed
/// with `relative` (deskew_trajectory; t0 is the scan's start on the IMU clock). With
/// flattest_queries each plane query is its voxel's flattest candidate, else its first.
DeskewedFeatures deskew_features(const Scan& scan, const ScanFeatures& indices, const PoseTable& relative, double t0,
                                 const Pose& lidar_to_imu, const BeamCalibration& beams, const DeskewParams& params,
                                 bool flattest_queries);

}  // namespace liod
