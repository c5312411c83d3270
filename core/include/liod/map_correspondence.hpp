#pragma once
// Point-to-plane and point-to-line correspondences against the local map. Both give a linear
// residual r = n . q + d in the world point q, so the solver treats them alike: for a line, n is
// the unit vector from the line to the point (LOAM's point-to-line distance).

#include <Eigen/Core>
#include <optional>

#include "liod/local_map.hpp"
#include "liod/post_model.hpp"

namespace liod {

struct LinearResidual {
  Eigen::Vector3d normal;
  double offset = 0.0;
  /// The residual's variance in units of the point noise: the query's own noise plus the fitted
  /// plane's (line's) uncertainty where the query lies (see map_correspondence.cpp).
  double variance_scale = 1.0;
  double evaluate(const Eigen::Vector3d& q) const { return normal.dot(q) + offset; }
};

struct CorrespondenceParams {
  int neighbours = 5;
  double max_distance_m = 1.5;
  double max_plane_thickness_m = 0.1;  // every neighbour within this of the fitted plane
  double min_plane_spread_ratio = 0.2; // second / largest spread (std) of the neighbours, against collinear ones
  double min_line_ratio = 3.0;         // largest / second eigenvalue for a line
  bool fit_uncertainty = true;         // false: a residual's variance is the point noise alone
  /// Non-zero (a unit vector, world frame): a wall's normal (a plane whose normal is within
  /// wall_max_up_cosine of horizontal), and with blind_ground any plane's, loses its component
  /// along it, so that the plane locates the query across that direction only; a plane nearly
  /// facing it (less than half of its normal left) gives no residual.
  Eigen::Vector3d blind_along = Eigen::Vector3d::Zero();
  bool blind_ground = false;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // the world's up, for telling walls from ground
  double wall_max_up_cosine = 0.7;
};

std::optional<LinearResidual> plane_correspondence(LocalMap::NeighbourSearch& map, const Eigen::Vector3d& query,
                                                   const CorrespondenceParams& params);

/// A roadside post, a pole's foot, a wall's corner: an edge whose map points stand one above the
/// other. The map keeps a post 16 cm wide and 0.4 m tall (a guard rail's, below the rail) as two or
/// three points, too few for a fitted line, yet on a highway such posts are the only structure
/// along the track.
struct PostParams {
  int neighbours = 2;             // nearest map post axes that must stand on one vertical line
  double radius_m = 0.4;          // ...within this of the query's axis
  double max_width_m = 0.2;       // their horizontal spread (largest distance between them, across up)
  double min_height_m = 0.1;      // their vertical extent at least (a horizontal edge has none)
  double depth_m = kPostAxisDepthM;  // 0: the edge points themselves
};

/// Where the axes of the posts that the edge points (world frame) may lie on are: each point
/// moved depth_m along the horizontal part of the ray from the viewpoint that saw it (the LiDAR's
/// origin). A post's edge point is where a ring met its near side, which the viewpoint picks: seen
/// from 20 m ahead, a face across the road; passed, the face behind. Matched point to point
/// those move with the viewpoint by up to the post's depth, each the same way along the track,
/// and at the true poses of the clean highway drives (no sensor error) pulled every scan back by
/// 2-8 mm; the axes do not move.
std::vector<Eigen::Vector3d> post_axes(const std::vector<Eigen::Vector3d>& edges, const Eigen::Vector3d& viewpoint,
                                       const Eigen::Vector3d& up, double depth_m);

/// The vertical line through the nearest map post axes (post_axes, from the keyframes' edges) of
/// the query's own axis estimate, if they form a post (PostParams); its residual is the query's
/// axis estimate's distance to that line along the horizontal part of the ray from the viewpoint
/// (the LiDAR's origin, world frame): the range to the post, which does not depend on where
/// across the post the beam grazed it. up: the world's up direction (against gravity).
std::optional<LinearResidual> post_correspondence(LocalMap::NeighbourSearch& axes, const Eigen::Vector3d& query,
                                                  const Eigen::Vector3d& up, const Eigen::Vector3d& viewpoint,
                                                  const PostParams& params);

/// With a viewpoint (the LiDAR's origin, world frame) the distance to the line is measured along
/// the ray from it, else the shortest way (LOAM).
std::optional<LinearResidual> line_correspondence(LocalMap::NeighbourSearch& map, const Eigen::Vector3d& query,
                                                  const CorrespondenceParams& params,
                                                  const Eigen::Vector3d* viewpoint = nullptr);

}  // namespace liod
