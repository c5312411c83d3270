// Long roads: `highway` (fast dual carriageway, sparse structure: rails, barriers, noise walls,
// gantries, overpasses) and `tunnel` (an oval whose one straight runs through a long box tunnel
// of constant cross-section).

#include <algorithm>
#include <cmath>
#include <numbers>

#include "liod/sim/trajectory.hpp"
#include "scene_internal.hpp"

namespace liod::sim::detail {

namespace {
/// Lateral offset of the driven lane along the road: mostly the slow lane, with lane changes.
std::vector<double> lane_offsets(const std::vector<double>& s, double slow, double fast, Rng& rng) {
  std::vector<double> off(s.size(), slow);
  double at = rng.uniform(300.0, 700.0);
  bool in_fast = false;
  while (at < s.back()) {
    const double ramp = rng.uniform(90.0, 150.0);
    const double from = in_fast ? fast : slow;
    const double to = in_fast ? slow : fast;
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (s[i] >= at && s[i] < at + ramp) {
        const double f = 0.5 - 0.5 * std::cos(std::numbers::pi * (s[i] - at) / ramp);
        off[i] = from + (to - from) * f;
      } else if (s[i] >= at + ramp) {
        off[i] = to;
      }
    }
    in_fast = !in_fast;
    at += ramp + (in_fast ? rng.uniform(200.0, 600.0) : rng.uniform(500.0, 1500.0));
  }
  return off;
}
}  // namespace

Scene make_highway(const SceneRequest& req, Rng& rng) {
  Scene scene;
  const double total = req.max_speed * req.duration * 1.05 + 500.0;
  std::vector<Eigen::Vector2d> corners{Eigen::Vector2d(-60.0, 0.0), Eigen::Vector2d(0.0, 0.0)};
  double heading = 0.0;
  double len = 60.0;
  while (len < total) {
    const double leg = rng.uniform(500.0, 900.0);
    corners.push_back(corners.back() + leg * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
    len += leg;
    heading = std::clamp(heading + rng.uniform(-0.3, 0.3) - 0.3 * heading, -0.45, 0.45);
  }
  corners.push_back(corners.back() + 300.0 * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
  const std::vector<Eigen::Vector2d> centre = rounded_polyline(corners, 700.0, 1.0);
  const std::vector<double> s_c = polyline_arclength(centre);
  const std::vector<double> off = lane_offsets(s_c, 7.6, 3.9, rng);
  scene.plan.points = offset_polyline(centre, off);
  scene.plan.road_centre = centre;
  scene.plan.road_half_width = 11.5;
  scene.plan.lanes_with = {3.9, 7.6};
  scene.plan.lanes_against = {3.9, 7.6};
  scene.plan.cruise_speed = req.max_speed;
  scene.plan.speed_cap.assign(scene.plan.points.size(), req.max_speed);

  Eigen::Vector2d wmin;
  Eigen::Vector2d wmax;
  bounds_with_margin(centre, 170.0, wmin, wmax);
  std::vector<Eigen::Vector2d> hills;
  for (double s = 400.0; s < s_c.back(); s += rng.uniform(900.0, 1600.0)) {
    hills.push_back(centre[static_cast<std::size_t>(s)] + Eigen::Vector2d(0, rng.uniform(-30, 30)));
  }
  scene.world.terrain = make_terrain(rng, 1.0, hills);
  SceneBuilder b(scene.world, rng);
  b.allocate(wmin, wmax, 2.0);

  const Appearance concrete{0.3F};
  const Appearance steel{0.45F};
  // Cross-section, in metres right of the median centre line: median barrier at 0, our lanes to
  // +11, the opposite carriageway to -11, rails just outside.
  const std::size_t step = 8;
  bool noise_left = false;
  bool noise_right = false;
  bool lamps = false;
  bool forest = false;
  double next_gantry = rng.uniform(300.0, 800.0);
  double next_bridge = rng.uniform(600.0, 1400.0);
  for (std::size_t i = step; i < centre.size(); i += step) {
    const Eigen::Vector2d a = centre[i - step];
    const Eigen::Vector2d c = centre[i];
    const Eigen::Vector2d d = (c - a).normalized();
    const Eigen::Vector2d r(d.y(), -d.x());
    const double s = s_c[i];
    if (i % 400 == 0) {
      noise_left = rng.bernoulli(0.25);
      noise_right = rng.bernoulli(0.3);
      lamps = rng.bernoulli(0.4);
      forest = rng.bernoulli(0.5);
    }
    b.add_road(a, c, 11.5);
    b.add_strip(a, c, 0.6, -0.2, 0.85, concrete);  // median barrier
    for (double side : {1.0, -1.0}) {
      b.add_strip(a + r * side * 11.8, c + r * side * 11.8, 0.1, 0.45, 0.8, steel);  // guard rail
      for (int p = 0; p < 2; ++p) {
        const Eigen::Vector2d q = a + d * (p * 4.0) + r * side * 11.95;
        b.add_block(q, std::atan2(d.y(), d.x()), 0.08, 0.08, -0.3, 0.75, steel);
      }
      if ((side > 0 ? noise_right : noise_left)) {
        b.add_strip(a + r * side * 16.0, c + r * side * 16.0, 0.25, -0.3, 4.5,
                    Appearance{static_cast<float>(rng.uniform(0.2, 0.45))});
      } else if (forest && rng.bernoulli(0.35)) {
        b.add_tree(a + d * rng.uniform(0, 8) + r * side * rng.uniform(20.0, 70.0), rng.uniform(0.9, 1.6));
      }
    }
    if (lamps && (i / step) % 6 == 0) {
      const double side = (i / step) % 12 == 0 ? 1.0 : -1.0;
      b.add_pole(a + r * side * 13.0, 10.0, 0.15, true, std::atan2(-r.y() * side, -r.x() * side));
    }
    if (s > next_gantry) {
      next_gantry += rng.uniform(900.0, 1500.0);
      const double yaw = std::atan2(r.y(), r.x());
      for (double side : {1.0, -1.0}) {
        b.add_pole(a + r * side * 13.5, 7.5, 0.3, false);
      }
      b.add_block(a, yaw, 13.5, 0.4, 6.6, 7.4, steel);
      for (double lat : {4.0, 8.0}) {
        Box panel;
        panel.rotation = rotation_from_euler(0.0, 0.0, std::atan2(-d.y(), -d.x()));
        const Eigen::Vector2d pc = a - d * 0.5 + r * lat;
        panel.center << pc.x(), pc.y(), scene.world.terrain.height(pc.x(), pc.y()) + 7.6;
        panel.half << 0.05, 1.8, 1.0;
        panel.look = Appearance{0.9F, SurfaceKind::Retroreflective, 0.0F};
        scene.world.boxes.push_back(panel);
      }
    }
    if (s > next_bridge) {
      next_bridge += rng.uniform(1200.0, 2200.0);
      const double yaw = std::atan2(r.y(), r.x());
      const double g = scene.world.terrain.height(a.x(), a.y());
      Box deck;
      deck.rotation = rotation_from_euler(0.0, 0.0, yaw);
      deck.center << a.x(), a.y(), g + 6.8;
      deck.half << 45.0, 6.0, 0.7;
      deck.look = concrete;
      scene.world.boxes.push_back(deck);
      for (double side : {1.0, -1.0}) {
        const Eigen::Vector2d pc = a + r * side * 15.0;
        b.add_block(pc, yaw, 0.6, 5.0, -0.5, 6.2, concrete);
      }
    }
    if ((i / step) % 12 == 0) {
      // Kilometre/marker posts with reflectors.
      const Eigen::Vector2d p = a + r * 12.6;
      b.add_block(p, 0.0, 0.06, 0.06, -0.2, 1.1, Appearance{0.85F, SurfaceKind::Retroreflective, 0.0F});
    }
    if (rng.bernoulli(0.004)) {
      b.add_car(a + r * 10.0, std::atan2(d.y(), d.x()), rng.bernoulli(0.5), true);  // broken down
    }
  }
  scene.road_roughness = 16e-6;
  scene.summary = "dual carriageway, gentle curves, lane changes, sparse roadside structure";
  return scene;
}

Scene make_tunnel(const SceneRequest& req, Rng& rng) {
  Scene scene;
  const double rc = std::clamp(req.max_speed * req.max_speed / 2.6, 45.0, 100.0);
  const double tunnel_len = rng.uniform(300.0, 400.0);
  const double xa = rng.uniform(130.0, 180.0);
  const double xb = xa + tunnel_len;
  const double ls = xb + rng.uniform(120.0, 180.0);
  const std::vector<Eigen::Vector2d> lap = {Eigen::Vector2d(0, 0), Eigen::Vector2d(ls + rc, 0),
                                            Eigen::Vector2d(ls + rc, 2 * rc),
                                            Eigen::Vector2d(-rc, 2 * rc), Eigen::Vector2d(-rc, 0)};
  const double lap_len = 2 * ls + 2 * std::numbers::pi * rc;
  const int laps = static_cast<int>(std::ceil((req.max_speed * req.duration + 300.0) / lap_len));
  const std::vector<Eigen::Vector2d> centre = rounded_polyline(repeat_loop(lap, laps), rc, 1.0);
  scene.plan.points = offset_polyline(centre, std::vector<double>(centre.size(), 1.9));
  scene.plan.road_centre = centre;
  scene.plan.road_half_width = 5.0;
  scene.plan.lanes_with = {1.9};
  scene.plan.lanes_against = {1.9};
  scene.plan.cruise_speed = req.max_speed;
  scene.plan.speed_cap.assign(scene.plan.points.size(), req.max_speed);

  Eigen::Vector2d wmin;
  Eigen::Vector2d wmax;
  bounds_with_margin(centre, 170.0, wmin, wmax);
  scene.world.terrain = make_terrain(rng, 1.0, {Eigen::Vector2d(0.5 * ls, 2 * rc + 60.0)});
  GradedCorridor cor;
  cor.a = Eigen::Vector2d(-30.0, 0.0);
  cor.b = Eigen::Vector2d(ls + 30.0, 0.0);
  cor.half_width = 14.0;
  cor.blend = 40.0;
  // The floor meets the natural terrain at both ends, so its grade is the terrain's own.
  cor.z_at_a = scene.world.terrain.natural_height(cor.a.x(), cor.a.y());
  cor.grade = (scene.world.terrain.natural_height(cor.b.x(), cor.b.y()) - cor.z_at_a) /
              (cor.b - cor.a).norm();
  scene.world.terrain.corridors.push_back(cor);
  SceneBuilder b(scene.world, rng);
  b.allocate(wmin, wmax, 2.0);

  // Road: one lap of 5 m pieces.
  const std::vector<Eigen::Vector2d> one = rounded_polyline(repeat_loop(lap, 1), rc, 5.0);
  for (std::size_t i = 1; i < one.size(); ++i) {
    b.add_road(one[i - 1], one[i], 5.0);
  }
  // The tunnel: the rock to either side and above is three boxes whose inner faces are the walls
  // and the ceiling, sloped with the corridor grade; a raised walkway runs along the right wall.
  const double pitch = -std::atan(cor.grade);
  const Eigen::Matrix3d rot = rotation_from_euler(0.0, pitch, 0.0);
  auto tunnel_box = [&](double y0, double y1, double z0, double z1, Appearance look) {
    Box box;
    box.rotation = rot;
    const double xm = 0.5 * (xa + xb);
    const double zm = Terrain::corridor_plane(cor, xm, 0.0);
    box.center << xm, 0.5 * (y0 + y1), zm + 0.5 * (z0 + z1);
    box.half << 0.5 * tunnel_len * std::sqrt(1.0 + cor.grade * cor.grade), 0.5 * (y1 - y0),
        0.5 * (z1 - z0);
    box.look = look;
    scene.world.boxes.push_back(box);
    b.reserve(Eigen::Vector2d(xm, 0.5 * (y0 + y1)), 0.0, 0.5 * tunnel_len, 0.5 * (y1 - y0));
  };
  const Appearance lining{0.35F};
  tunnel_box(5.5, 40.0, -1.0, 16.0, lining);
  tunnel_box(-40.0, -5.5, -1.0, 16.0, lining);
  tunnel_box(-5.5, 5.5, 5.8, 16.0, lining);
  tunnel_box(-5.5, -4.3, -0.5, 0.25, Appearance{0.3F});

  // Around the rest of the oval: lamps, trees, some houses, rails on the bends.
  SideFurniture f;
  f.lamp_spacing = 40.0;
  f.tree_spacing = 14.0;
  f.tree_offset = 4.0;
  f.sign_probability = 0.5;
  furnish_side(b, Eigen::Vector2d(10.0, 0.0), Eigen::Vector2d(xa - 10.0, 0.0), 5.0, 1.0, f);
  furnish_side(b, Eigen::Vector2d(10.0, 0.0), Eigen::Vector2d(xa - 10.0, 0.0), 5.0, -1.0, f);
  furnish_side(b, Eigen::Vector2d(xb + 10.0, 0.0), Eigen::Vector2d(ls, 0.0), 5.0, 1.0, f);
  furnish_side(b, Eigen::Vector2d(xb + 10.0, 0.0), Eigen::Vector2d(ls, 0.0), 5.0, -1.0, f);
  furnish_side(b, Eigen::Vector2d(ls, 2 * rc), Eigen::Vector2d(0.0, 2 * rc), 5.0, 1.0, f);
  furnish_side(b, Eigen::Vector2d(ls, 2 * rc), Eigen::Vector2d(0.0, 2 * rc), 5.0, -1.0, f);
  for (double x = 20.0; x < ls - 20.0; x += rng.uniform(14.0, 30.0)) {
    const double side = rng.sign();
    const Eigen::Vector2d front(x, 2 * rc + side * rng.uniform(12.0, 18.0));
    b.add_building(front, Eigen::Vector2d(0.0, -side), rng.uniform(9.0, 16.0), rng.uniform(8.0, 12.0),
                   rng.uniform(5.0, 9.0), BuildingStyle::House);
  }
  for (std::size_t i = 1; i < one.size(); ++i) {
    const Eigen::Vector2d d = (one[i] - one[i - 1]).normalized();
    const Eigen::Vector2d r(d.y(), -d.x());
    const bool bend = one[i].x() < -5.0 || one[i].x() > ls + 5.0;
    if (bend) {
      // Outer side of a left-hand bend is the right side.
      b.add_strip(one[i - 1] + r * 6.0, one[i] + r * 6.0, 0.1, 0.45, 0.8, Appearance{0.45F});
    }
  }
  for (int k = 0; k < 250; ++k) {
    const Eigen::Vector2d p(rng.uniform(wmin.x(), wmax.x()), rng.uniform(wmin.y(), wmax.y()));
    b.add_tree(p, rng.uniform(0.8, 1.5));
  }
  scene.road_roughness = 25e-6;
  scene.summary = "oval with a " + std::to_string(static_cast<int>(tunnel_len)) +
                  " m straight box tunnel (constant cross-section, 11 m x 5.8 m)";
  return scene;
}

}  // namespace liod::sim::detail
