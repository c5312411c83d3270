// `figure8`: an open industrial yard crossed by a lemniscate road that the vehicle drives lap after
// lap, crossing its own path at the centre twice a lap.

#include <algorithm>
#include <cmath>
#include <numbers>

#include "scene_internal.hpp"

namespace liod::sim::detail {

Scene make_figure8(const SceneRequest& req, Rng& rng) {
  Scene scene;
  // Lemniscate of Bernoulli: tightest radius a/3, so a >= v^2 keeps lateral acceleration <= 3.
  const double a = std::clamp(req.max_speed * req.max_speed, 80.0, 170.0);
  const double lap_len = 5.244 * a;
  const int laps = static_cast<int>(std::ceil((req.max_speed * req.duration + 300.0) / lap_len));
  std::vector<Eigen::Vector2d> fine;
  const double t0 = std::numbers::pi / 2.0;
  const double t1 = t0 + 2.0 * std::numbers::pi * laps;
  for (double t = t0; t <= t1; t += 0.0005) {
    const double s2 = std::sin(t) * std::sin(t);
    fine.emplace_back(a * std::cos(t) / (1.0 + s2), a * std::sin(t) * std::cos(t) / (1.0 + s2));
  }
  scene.plan.points = resample_polyline(fine, 1.0);
  scene.plan.cruise_speed = req.max_speed;
  scene.plan.speed_cap.assign(scene.plan.points.size(), req.max_speed);

  Eigen::Vector2d wmin;
  Eigen::Vector2d wmax;
  bounds_with_margin(scene.plan.points, 170.0, wmin, wmax);
  scene.world.terrain = make_terrain(rng, 0.8, {Eigen::Vector2d(a * rng.uniform(-0.6, 0.6), rng.uniform(-60, 60))});
  SceneBuilder b(scene.world, rng);
  b.allocate(wmin, wmax);

  // One lap of road, in 5 m pieces.
  std::vector<Eigen::Vector2d> lap;
  for (double t = t0; t <= t0 + 2.0 * std::numbers::pi + 0.01; t += 0.01) {
    const double s2 = std::sin(t) * std::sin(t);
    lap.emplace_back(a * std::cos(t) / (1.0 + s2), a * std::sin(t) * std::cos(t) / (1.0 + s2));
  }
  lap = resample_polyline(lap, 5.0);
  for (std::size_t i = 1; i < lap.size(); ++i) {
    b.add_road(lap[i - 1], lap[i], 4.5);
  }
  // Lamps along the road on both sides.
  for (std::size_t i = 1; i < lap.size(); i += 7) {
    const Eigen::Vector2d d = (lap[i] - lap[i - 1]).normalized();
    const Eigen::Vector2d n(d.y(), -d.x());
    const double side = (i / 7) % 2 == 0 ? 1.0 : -1.0;
    b.add_pole(lap[i] + n * side * 6.0, rng.uniform(7.0, 10.0), 0.14, true,
               std::atan2(-n.y() * side, -n.x() * side));
  }
  // Warehouses, denser on the -x half: the +x lobe stays an open stretch.
  const int n_wh = 14;
  for (int k = 0, placed = 0; k < 400 && placed < n_wh; ++k) {
    const Eigen::Vector2d p(rng.uniform(-a - 60, a * 0.3), rng.uniform(-a * 0.6 - 60, a * 0.6 + 60));
    const double yaw = rng.uniform(0.0, std::numbers::pi);
    const double w = rng.uniform(15.0, 60.0);
    const double d = rng.uniform(10.0, 35.0);
    const Eigen::Vector2d dir(std::cos(yaw), std::sin(yaw));
    if (b.is_free(p - dir * (d / 2), yaw, d / 2, w / 2, 4.0) &&
        b.add_building(p, dir, w, d, rng.uniform(6.0, 14.0), BuildingStyle::Warehouse)) {
      ++placed;
    }
  }
  // Container stacks.
  for (int cl = 0; cl < 5; ++cl) {
    const Eigen::Vector2d base(rng.uniform(-a, a), rng.uniform(-a * 0.6 - 50, a * 0.6 + 50));
    const double yaw = rng.uniform(0.0, std::numbers::pi);
    const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw));
    const Eigen::Vector2d ay(-ax.y(), ax.x());
    const Appearance looks[] = {Appearance{0.15F}, Appearance{0.35F}, Appearance{0.55F}, Appearance{0.08F}};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 5; ++c) {
        const Eigen::Vector2d p = base + ax * (c * 6.4) + ay * (r * 2.8);
        if (!b.is_free(p, yaw, 3.05, 1.22, 0.1)) {
          continue;
        }
        const int stack = rng.uniform_int(1, 3);
        b.add_block(p, yaw, 3.05, 1.22, -0.2, 2.59 * stack, looks[rng.uniform_int(0, 3)]);
      }
    }
  }
  // Trucks, cars, hedges, trees, a fence.
  for (int k = 0; k < 40; ++k) {
    const Eigen::Vector2d p(rng.uniform(-a - 40, a + 40), rng.uniform(-a * 0.6 - 40, a * 0.6 + 40));
    b.add_car(p, rng.uniform(0, 6.28), rng.bernoulli(0.4));
  }
  for (int k = 0; k < 160; ++k) {
    const Eigen::Vector2d p(rng.uniform(wmin.x(), wmax.x()), rng.uniform(wmin.y(), wmax.y()));
    if (rng.bernoulli(0.6)) {
      b.add_tree(p, rng.uniform(0.7, 1.4));
    } else {
      b.add_bush(p);
    }
  }
  {
    const double fy = a * 0.6 + 70.0;
    for (double x = -a - 50; x < a + 50; x += 10.0) {
      b.add_strip({x, fy}, {x + 10.0, fy}, 0.05, 0.0, 2.0,
                  Appearance{0.3F, SurfaceKind::Porous, 7.0F});  // chain-link fence
    }
  }
  scene.road_roughness = 40e-6;
  scene.summary = "industrial yard, lemniscate road (a = " + std::to_string(static_cast<int>(a)) +
                  " m) crossing itself at the centre";
  return scene;
}

}  // namespace liod::sim::detail
