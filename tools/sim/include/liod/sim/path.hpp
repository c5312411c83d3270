#pragma once
// The driven path on the ground plane: a dense lane polyline with speed caps and stops, and the
// curvature-continuous curve (a smoothed cubic B-spline, arc-length parameterised) that a
// steered vehicle can actually follow.

#include <Eigen/Core>
#include <vector>

namespace liod::sim {

struct Stop {
  double s = 0.0;         // arc length of the stop line
  double duration = 0.0;  // seconds standing still
};

struct DrivePlan {
  std::vector<Eigen::Vector2d> points;  // ~1 m apart
  std::vector<double> speed_cap;        // m/s at each point
  std::vector<Stop> stops;              // sorted by s
  double static_start_s = 0.0;          // seconds at rest before moving off (0 = rolling start)
  double cruise_speed = 10.0;           // m/s wanted on a free road
  // The road under the lane, for other traffic: its centre line at each point (empty: a road
  // without lanes, e.g. the yard of figure8), the half width, and the centres of its lanes, in
  // metres right of the centre line, in the drive's direction and in the opposite one (right of
  // that direction).
  std::vector<Eigen::Vector2d> road_centre;
  double road_half_width = 0.0;
  std::vector<double> lanes_with;
  std::vector<double> lanes_against;
};

/// Dense polyline through `corners` with every interior corner replaced by a circular arc of the
/// given radius (shrunk where the legs are short). Points are `spacing` apart.
std::vector<Eigen::Vector2d> rounded_polyline(const std::vector<Eigen::Vector2d>& corners,
                                              double radius, double spacing);

/// Shifts each point sideways by offset[i] (positive = to the right of the driving direction).
std::vector<Eigen::Vector2d> offset_polyline(const std::vector<Eigen::Vector2d>& pts,
                                             const std::vector<double>& offset);

/// Points `spacing` apart along a polyline (its last point is dropped unless it falls on one).
std::vector<Eigen::Vector2d> resample_polyline(const std::vector<Eigen::Vector2d>& pts, double spacing);

/// Cumulative length along a polyline.
std::vector<double> polyline_arclength(const std::vector<Eigen::Vector2d>& pts);

class PathCurve {
 public:
  /// Smooths the polyline with a Gaussian of `sigma` metres and fits a cubic B-spline through it.
  PathCurve(const std::vector<Eigen::Vector2d>& pts, double sigma);

  double length() const { return s_table_.back(); }
  Eigen::Vector2d position(double s) const;
  double heading(double s) const;
  /// Signed curvature, positive turning left.
  double curvature(double s) const;

 private:
  double param_at(double s) const;
  void eval(double u, Eigen::Vector2d* p, Eigen::Vector2d* d1, Eigen::Vector2d* d2) const;

  std::vector<Eigen::Vector2d> ctrl_;
  std::vector<double> u_table_;
  std::vector<double> s_table_;
};

}  // namespace liod::sim
