#pragma once
// Scan Context (Kim and Kim, "Scan Context: Egocentric Spatial Descriptor for Place Recognition
// within 3D Point Cloud Map", IROS 2018): a keyframe's surroundings as a polar grid of rings x
// sectors around the sensor, each bin holding the highest point in it. Two places are compared
// column by column (cosine distance of the sectors' height profiles) under a circular shift of
// the sectors, which makes the match independent of the heading and gives the relative yaw. The
// relocalisation (relocalization.hpp) retrieves a saved keyframe with it before registration
// confirms the place.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace liod {

struct ScanContextConfig {
  int rings = 20;           // radial bins (the paper's N_r)
  int sectors = 60;         // angular bins (N_s): 6 degrees each
  double max_range_m = 60.0;  // the descriptor's radius: the street a car sees, not the far field
  // Heights are measured from this far below the sensor, so that the road (about 1-2 m below an
  // IMU on a car) fills a bin with a small positive value and an empty bin stays 0.
  double height_offset_m = 3.0;
};

struct ScanContext {
  int rings = 0;
  int sectors = 0;
  Eigen::MatrixXf bins;      // rings x sectors: highest point above -height_offset_m, 0 = empty
  Eigen::VectorXf sector_key;  // per sector: the mean of its bins (Scan Context++): aligns headings cheaply
};

/// The descriptor of points given in a level frame centred at the sensor (x forward, z up:
/// the body frame with roll and pitch removed).
ScanContext make_scan_context(const std::vector<Eigen::Vector3f>& level_points, const ScanContextConfig& config);

/// The rotation that levels a body frame: R_level_body = Rz(-yaw) R_world_body, for a body whose
/// world attitude is `world_from_body` (world z up, along gravity).
Eigen::Matrix3d level_from_body(const Eigen::Matrix3d& world_from_body);

struct ScanContextMatch {
  double distance = 1.0;  // mean cosine distance of the compared columns, in [0, 1]; 1 = no overlap
  int shift = 0;          // sectors: column c of the query matches column c + shift of the candidate
  double yaw_rad = 0.0;   // the query's heading relative to the candidate's: shift * 2 pi / sectors
};

/// The best circular shift between two descriptors of the same size. The sector keys' circular
/// difference picks a few shifts (Scan Context++'s fast alignment); the full distance is taken at
/// those and their neighbours. Columns empty in either are not compared; a shift comparing fewer
/// than half of the sectors scores 1.
ScanContextMatch match_scan_contexts(const ScanContext& query, const ScanContext& candidate);

}  // namespace liod
