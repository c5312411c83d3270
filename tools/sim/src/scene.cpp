#include <algorithm>
#include <cmath>
#include <numbers>

#include "liod/sim/scene.hpp"
#include "scene_internal.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kSceneStream = 0x7363656E65ULL;
}

std::optional<RouteKind> parse_route(std::string_view name) {
  if (name == "urban") return RouteKind::Urban;
  if (name == "loop") return RouteKind::Loop;
  if (name == "figure8") return RouteKind::Figure8;
  if (name == "highway") return RouteKind::Highway;
  if (name == "tunnel") return RouteKind::Tunnel;
  return std::nullopt;
}

const char* route_name(RouteKind kind) {
  switch (kind) {
    case RouteKind::Urban: return "urban";
    case RouteKind::Loop: return "loop";
    case RouteKind::Figure8: return "figure8";
    case RouteKind::Highway: return "highway";
    case RouteKind::Tunnel: return "tunnel";
  }
  return "?";
}

Scene generate_scene(const SceneRequest& req) {
  Rng rng(derive_seed(req.seed, kSceneStream));
  Scene scene;
  switch (req.route) {
    case RouteKind::Urban: scene = detail::make_city(req, rng, false); break;
    case RouteKind::Loop: scene = detail::make_city(req, rng, true); break;
    case RouteKind::Figure8: scene = detail::make_figure8(req, rng); break;
    case RouteKind::Highway: scene = detail::make_highway(req, rng); break;
    case RouteKind::Tunnel: scene = detail::make_tunnel(req, rng); break;
  }
  const bool rolling_default = req.route == RouteKind::Urban || req.route == RouteKind::Highway;
  const bool rolling = req.start == StartMode::Rolling ||
                       (req.start == StartMode::Default && rolling_default);
  scene.plan.static_start_s = rolling ? 0.0 : req.static_seconds;
  scene.world.finalize(derive_seed(req.seed, kSceneStream, 1));
  return scene;
}

namespace detail {

Terrain make_terrain(Rng& rng, double slope_scale, const std::vector<Eigen::Vector2d>& hill_sites) {
  Terrain t;
  for (int i = 0; i < 4; ++i) {
    const double wavelength = rng.uniform(150.0, 520.0);
    const double k = 2.0 * std::numbers::pi / wavelength;
    const double dir = rng.uniform(0.0, 2.0 * std::numbers::pi);
    TerrainWave w;
    w.wave_vector << k * std::cos(dir), k * std::sin(dir);
    w.phase = rng.uniform(0.0, 2.0 * std::numbers::pi);
    w.amplitude = slope_scale * rng.uniform(0.006, 0.014) / k;  // slope amplitude ~1 %
    t.waves.push_back(w);
  }
  for (const auto& site : hill_sites) {
    TerrainHill h;
    h.center = site;
    h.sigma = rng.uniform(50.0, 90.0);
    // Peak grade of a Gaussian hill is 0.61 height / sigma: 3 to 6 %.
    h.height = rng.sign() * slope_scale * h.sigma * rng.uniform(0.05, 0.09);
    t.hills.push_back(h);
  }
  return t;
}

void bounds_with_margin(const std::vector<Eigen::Vector2d>& pts, double margin,
                        Eigen::Vector2d& min, Eigen::Vector2d& max) {
  min = Eigen::Vector2d::Constant(1e18);
  max = Eigen::Vector2d::Constant(-1e18);
  for (const auto& p : pts) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  min.array() -= margin;
  max.array() += margin;
  min = min.array().floor();
  max = max.array().ceil();
}

std::vector<std::size_t> locate_in_order(const std::vector<Eigen::Vector2d>& dense,
                                         const std::vector<Eigen::Vector2d>& nodes) {
  std::vector<std::size_t> idx;
  std::size_t from = 0;
  for (const auto& n : nodes) {
    std::size_t best = from;
    double best_d = 1e18;
    // Nodes are visited in order, so search a bounded window ahead of the previous match.
    for (std::size_t i = from; i < dense.size() && i < from + 600; ++i) {
      const double d = (dense[i] - n).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    idx.push_back(best);
    from = best + 1;
  }
  return idx;
}

std::vector<Eigen::Vector2d> repeat_loop(const std::vector<Eigen::Vector2d>& loop, int laps) {
  std::vector<Eigen::Vector2d> out;
  for (int l = 0; l < laps; ++l) {
    out.insert(out.end(), loop.begin(), loop.end());
  }
  out.push_back(loop.front());
  return out;
}

void furnish_side(SceneBuilder& b, const Eigen::Vector2d& a, const Eigen::Vector2d& c,
                  double road_half_width, double side, const SideFurniture& f) {
  const Eigen::Vector2d dir = (c - a).normalized();
  const Eigen::Vector2d out = Eigen::Vector2d(dir.y(), -dir.x()) * side;  // away from the road
  const double len = (c - a).norm();
  Rng& rng = b.rng();
  const double into_road = std::atan2(-out.y(), -out.x());
  if (f.lamp_spacing > 0.0) {
    for (double s = rng.uniform(0.0, f.lamp_spacing); s < len; s += f.lamp_spacing * rng.uniform(0.9, 1.1)) {
      b.add_pole(a + dir * s + out * (road_half_width + f.lamp_offset), rng.uniform(6.5, 9.0),
                 rng.uniform(0.09, 0.15), true, into_road);
    }
  }
  if (f.tree_spacing > 0.0) {
    for (double s = rng.uniform(0.0, f.tree_spacing); s < len; s += f.tree_spacing * rng.uniform(0.8, 1.2)) {
      if (rng.bernoulli(0.85)) {
        b.add_tree(a + dir * s + out * (road_half_width + f.tree_offset), rng.uniform(0.8, 1.2));
      }
    }
  }
  if (f.sign_probability > 0.0 && rng.bernoulli(f.sign_probability)) {
    const double s = rng.uniform(0.1, 0.9) * len;
    b.add_sign(a + dir * s + out * (road_half_width + 0.5), std::atan2(-dir.y() * side, -dir.x() * side));
  }
}

}  // namespace detail
}  // namespace liod::sim
