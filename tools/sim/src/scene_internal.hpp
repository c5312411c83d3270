#pragma once
// Helpers shared by the route-specific scene generators (not part of the public API).

#include <Eigen/Core>
#include <vector>

#include "liod/sim/rng.hpp"
#include "liod/sim/scene.hpp"
#include "liod/sim/scene_builder.hpp"

namespace liod::sim::detail {

/// Rolling terrain with grades of a few percent and optional hills/dips near given points.
Terrain make_terrain(Rng& rng, double slope_scale, const std::vector<Eigen::Vector2d>& hill_sites);

/// Bounding box of points, grown by the sensor's reach so no ray leaves the indexed area.
void bounds_with_margin(const std::vector<Eigen::Vector2d>& pts, double margin,
                        Eigen::Vector2d& min, Eigen::Vector2d& max);

/// Indices into `dense` of the points nearest to each of `nodes`, searched in order.
std::vector<std::size_t> locate_in_order(const std::vector<Eigen::Vector2d>& dense,
                                         const std::vector<Eigen::Vector2d>& nodes);

/// Repeats a closed corner loop (first == last not required) `laps` times from its first corner.
std::vector<Eigen::Vector2d> repeat_loop(const std::vector<Eigen::Vector2d>& loop, int laps);

/// Plain furniture along a straight road side between two distances (lamps, trees, signs).
struct SideFurniture {
  double lamp_spacing = 0.0;  // 0 = none
  double tree_spacing = 0.0;
  double lamp_offset = 1.0;   // beyond the road edge
  double tree_offset = 1.6;
  double sign_probability = 0.0;
};
void furnish_side(SceneBuilder& b, const Eigen::Vector2d& a, const Eigen::Vector2d& c,
                  double road_half_width, double side, const SideFurniture& f);

Scene make_city(const SceneRequest& req, Rng& rng, bool loop_route);
Scene make_figure8(const SceneRequest& req, Rng& rng);
Scene make_highway(const SceneRequest& req, Rng& rng);
Scene make_tunnel(const SceneRequest& req, Rng& rng);

}  // namespace liod::sim::detail
