#pragma once
// Online calibration of each beam against the map (docs/design.md, "Beam calibration").
//
// Elevation. A unit's true beam angles differ from its published table (RS-Helios: rounded to
// 0.01 deg, so by up to 0.005 deg even after a perfect factory calibration). A beam whose elevation
// is off by e moves its ground ring by about range * e: 2.6 mm at 30 m. On the highway those
// millimetres, different from beam to beam and, the sensor being tilted, from the front of a ring to
// its back, tilt every scan against a map made by other beams: the map's pitch drifts 0.2-0.3 deg
// per km. So each beam's elevation offset is estimated from its ground points' residuals against
// the map, by Gauss-Newton on exponentially forgotten sums, with a prior that the offset is small.
// One pattern is not observable: offsets proportional to the elevation (e = b * elevation) raise
// every ground ring by the same height (range * elevation is the sensor's height), which the pose
// absorbs. It is removed from the estimate (the gauge); a common offset of all beams is not, as it
// bends the ground into a cone that the map, seen from other ranges before, does show.
//
// Range (optional). Each channel also measures its ranges a few millimetres long or short. On the
// near ground and on walls that moves its points across the surface; uncorrected, the elevation
// calibration, which has no other parameter, answers the near rings' range offsets with a common
// tilt of the far beams (a few thousandths of a degree that the unit does not have). A
// beam's range offset is learned the same way from its residuals off the far ground, less the
// beams' mean: a common offset is seen only where a surface is seen from both sides, and is the one
// the sensor's own calibration gets best.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace liod {

struct BeamCalibrationParams {
  double forgetting = 0.999;       // per scan: a scan's residuals weigh half after 70 s at 10 Hz
  double step = 0.2;               // fraction of the estimated correction applied each scan: damps the loop
                                   // through the map, which the corrected beams go on to build
  double prior_std_deg = 0.004;    // a beam's offset before any data (weighed against every 4th ground point)
  double max_offset_deg = 0.02;    // no beam's offset grows beyond this (4x the table's rounding)
  double min_information = 1e6;    // a beam's sum of j^2 / variance below this is not corrected (1/rad^2;
                                   // one ground point 10 m away adds ~1e5)
  bool learn_ranges = false;       // also each beam's range offset
  double range_prior_std_m = 0.01;
  double max_range_offset_m = 0.05;
  double min_range_information = 1e5;  // 1/m^2: ~100 points on surfaces met face-on
};

class BeamCalibration {
 public:
  explicit BeamCalibration(std::size_t beams = 0, const BeamCalibrationParams& params = {});

  /// The LiDAR-frame point of `ring` moved along its ray by that beam's range offset, then turned
  /// by its elevation offset.
  Eigen::Vector3d correct(const Eigen::Vector3d& point, std::uint16_t ring) const;

  /// How a point moves per radian of its beam's elevation (zero straight up or down).
  static Eigen::Vector3d elevation_derivative(const Eigen::Vector3d& point);

  /// One residual r (m) of a `ring` point at `elevation` (rad, LiDAR frame), its derivative
  /// j = dr/d(elevation offset) (m/rad) and its variance (m^2), measured with the current offsets.
  void add_elevation(std::uint16_t ring, double elevation, double jacobian, double residual, double variance);

  /// One residual r (m) of a `ring` point, j = dr/d(range offset) (the surface normal along the
  /// ray) and its variance (m^2). Ignored unless the params learn ranges.
  void add_range(std::uint16_t ring, double jacobian, double residual, double variance);

  /// Folds the scan's residuals into every beam's estimates and moves the offsets towards them.
  void finish_scan();

  double offset_rad(std::uint16_t ring) const { return ring < beams_.size() ? beams_[ring].elevation.offset : 0.0; }
  double range_offset_m(std::uint16_t ring) const { return ring < beams_.size() ? beams_[ring].range.offset : 0.0; }
  bool learns_ranges() const { return params_.learn_ranges; }
  std::size_t beams() const { return beams_.size(); }

 private:
  // One offset's forgotten Gauss-Newton sums.
  struct Estimate {
    double offset = 0.0;           // applied to the points
    double information = 0.0;      // forgotten sum of j^2 / variance
    double gradient = 0.0;         // forgotten sum of j r / variance, at the current offset
    double scan_information = 0.0;
    double scan_gradient = 0.0;
    void add(double jacobian, double residual, double variance);
    /// Folds the scan in; the Gauss-Newton target with a prior at zero.
    double fold(double forgetting, double prior_information);
    /// Moves the offset a `step` of the way to `target`, within +-limit.
    void move_towards(double target, double step, double limit);
  };
  struct Beam {
    Estimate elevation;
    double elevation_sum = 0.0;  // forgotten like the sums: the beam's mean elevation
    double weight = 0.0;
    double scan_elevation_sum = 0.0;
    double scan_weight = 0.0;
    Estimate range;
  };
  void finish_elevations();
  void finish_ranges();

  BeamCalibrationParams params_;
  double prior_information_;
  double range_prior_information_;
  std::vector<Beam> beams_;
};

}  // namespace liod
