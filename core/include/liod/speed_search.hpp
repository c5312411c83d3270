#pragma once
// A rolling start's speed by exhaustive search: every speed hypothesis along the vehicle's
// forward axis deskews and places two scans, and the one under which their vertical structure,
// seen from above, overlaps best wins (correlative scan matching, Olson 2009, reduced to the one
// unknown a road vehicle's IMU leaves at start: attitude comes from gravity, the turn from the
// gyro, and a car moves along its own axis).
//
// Why not a local registration: on sparse roads most returns are ground rings, which move with
// the sensor, so a standstill fits them best and a gradient method started from a wrong speed
// stays near zero. A flat ground says nothing about a horizontal motion anyway: only posts,
// poles, trees and wall ends do, and their footprints from above do not depend on which ring
// hit them, so they are compared in 2-D.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <vector>

#include "liod/local_map.hpp"

namespace liod {

struct VerticalStructureParams {
  double cell_m = 0.5;               // bird's-eye cells in which the height spread is measured
  double min_height_spread_m = 0.3;  // less than this in a cell is ground (a ring or two), or nothing
  double ground_clearance_m = 0.2;   // points this close above a cell's lowest one are its ground
};

/// Indices of the points (gravity-aligned frame, z up) on vertical structure: in bird's-eye cells
/// whose points span at least min_height_spread_m in height, and above the cell's ground.
std::vector<std::size_t> vertical_structure(const std::vector<Eigen::Vector3d>& points,
                                            const VerticalStructureParams& params);

struct AlongTrackLineParams {
  double radius_m = 0.5;          // footprint neighbourhood in which a point's line is measured
  double min_length_std_m = 0.08;  // a post (8 cm) is a dot, a 0.3 m stretch of rail a line
  double max_width_ratio = 0.1;    // variance across over along: a tree trunk's arc is ~0.2
  double max_angle_deg = 30.0;     // from the direction of travel
};

/// Indices of the points (gravity-aligned frame, z up) that do not lie on a line along
/// `direction` (x, y) in the footprint: rails and barriers beside the road. A ring crosses a
/// barrier's height band over a stretch fixed in the sensor's frame, so the barrier's footprint
/// moves with the sensor and scores a standstill as well as the true speed, while telling nothing
/// about the motion along it.
std::vector<std::size_t> off_along_track_lines(const std::vector<Eigen::Vector3d>& points,
                                               const Eigen::Vector2d& direction, const AlongTrackLineParams& params);

/// How well a cloud's footprint (x, y of a gravity-aligned frame) lands on a reference footprint:
/// the sum over the query points of 1 - (d / radius)^2 for the horizontal distance d to the
/// nearest reference point within radius (a truncated quadratic, so that the score is smooth in
/// the motion near the optimum and blind to outliers).
class FootprintOverlap {
 public:
  FootprintOverlap(const std::vector<Eigen::Vector3d>& reference, double radius);
  double score(const std::vector<Eigen::Vector3d>& query) const;

 private:
  double radius_;
  LocalMap footprint_;
};

struct GridSearchResult {
  double value = 0.0;
  double score = 0.0;
};

struct GridSearchParams {
  double min = 0.0;
  double max = 0.0;
  double coarse_step = 1.0;
  double fine_step = 0.1;  // around the best coarse hypothesis
};

/// The coarse grid's hypotheses: min, min + coarse_step, ... up to max.
std::vector<double> coarse_grid(const GridSearchParams& params);

/// The best of centre and the fine grid within one coarse step either side of it.
GridSearchResult refine_around(const std::function<double(double)>& score, double centre, const GridSearchParams& params);

/// The index of the highest local maximum of scores (over the coarse grid `hypotheses`, both
/// neighbours lower or equal) among the hypotheses at least min_abs from zero, if it reaches
/// min_share of the highest score of all. A standstill's score falls off on either side of zero,
/// so what peaks again away from it is something that lands on itself at that speed.
std::optional<std::size_t> separate_peak(const std::vector<double>& hypotheses, const std::vector<double>& scores,
                                         double min_abs, double min_share);

/// Whether the score at index `best` (the highest) stands clear of its aliases: inside the grid,
/// not at either end (a score still rising there peaks beyond it), and at least min_ratio times
/// every other local maximum of scores at least min_separation from it. Guard-rail posts at a
/// regular spacing land on their neighbours' places k scans before at the true speed minus
/// spacing / (k scan periods), and for a scan or two such an alias can lead by a few per cent.
bool stands_clear_of_aliases(const std::vector<double>& hypotheses, const std::vector<double>& scores, std::size_t best,
                             double min_separation, double min_ratio);

/// Maximises score(x) over the coarse grid on [min, max], then over the fine grid around the
/// best coarse hypothesis. Exhaustive, so that a score with several local maxima (periodic posts)
/// is safe.
GridSearchResult grid_search(const std::function<double(double)>& score, const GridSearchParams& params);

}  // namespace liod
