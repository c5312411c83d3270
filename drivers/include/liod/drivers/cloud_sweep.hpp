#pragma once
// The point-cloud input path, beside the RS-Helios packet path: a sweep given as a list of points
// (a dataset's clouds, a LiDAR whose packets liod does not decode), with or without per-point time
// and ring. make_scan turns it into the liod::Scan the front end reads and fills in what the format
// lacks: the ring from each point's elevation (the curvature features run along one beam's returns
// in firing order) and the time from its azimuth (the deskew moves each point with the body pose
// at its own time).

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "liod/types.hpp"

namespace liod::drivers {

/// One sweep as a cloud. Points are in the cloud's frame; their `time` (seconds after start_time)
/// and `ring` are read only where the flags say the format has them.
struct CloudSweep {
  double start_time = 0.0;  ///< s, sensor clock: the sweep's first point
  /// s: the sweep's last point; 0 = start_time + the latest point time (with times) or + the
  /// sweep period (without).
  double end_time = 0.0;
  bool has_time = false;
  bool has_ring = false;
  std::uint64_t sequence = 0;
  std::vector<LidarPoint> points;
};

struct CloudScanConfig {
  /// Beam elevations in degrees, any order (ring 0 = the lowest): the rings a cloud without them
  /// gets. Required when the cloud has no ring.
  std::vector<double> beam_elevations_deg;
  /// A return farther than this from every beam's elevation is dropped (counted): it belongs to no
  /// beam of the table.
  double max_elevation_error_deg = 1.0;
  /// The spinning head's frame in the cloud's frame (its z axis the rotation axis): elevations
  /// and azimuths are taken in it.
  Eigen::Isometry3d head_in_cloud = Eigen::Isometry3d::Identity();
  /// Beams leave the head this far out from its axis (Ouster's lidar_origin_to_beam_origin): the
  /// elevation is taken from there, not from the axis, which matters within a few metres.
  double beam_origin_offset_m = 0.0;
  /// Without per-point time: one revolution takes this long, beginning at start_azimuth_deg
  /// (counter-clockwise from the head's x axis) and turning clockwise seen from above (z up), as
  /// Velodyne and Ouster heads do; false: counter-clockwise.
  double sweep_period_s = 0.1;
  double start_azimuth_deg = 180.0;
  bool clockwise = true;
  /// Nearer returns are dropped: with no range there is no elevation or azimuth.
  double min_range_m = 0.05;
};

struct CloudScanStats {
  std::size_t points_in = 0;
  std::size_t no_beam = 0;       ///< dropped: elevation beyond max_elevation_error_deg of every beam
  std::size_t too_near = 0;      ///< dropped: nearer than min_range_m, or not finite
};

/// The sweep as a Scan: rings from elevation where the cloud has none, times from azimuth where it
/// has no per-point time, points in time order (each ring in firing order). Throws
/// std::invalid_argument when the cloud has no ring and the config no beam table, or the table
/// has more beams than a ring index holds.
Scan make_scan(const CloudSweep& sweep, const CloudScanConfig& config, CloudScanStats* stats = nullptr);

/// The beam of each elevation (rad), ring 0 the lowest, from a table of beam elevations: the
/// nearest, or -1 beyond max_error_deg. Exposed for tests.
class BeamTable {
 public:
  BeamTable(const std::vector<double>& elevations_deg, double max_error_deg);
  int ring_of(double elevation_rad) const;
  std::size_t beams() const { return sorted_rad_.size(); }

 private:
  std::vector<double> sorted_rad_;
  double max_error_rad_;
};

}  // namespace liod::drivers
