// City grids: `urban` (dense blocks, a random walk through the junctions that keeps coming back to
// its start) and `loop` (suburban blocks, the same loop around blocks driven lap after lap).

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <map>
#include <numbers>

#include "scene_internal.hpp"

namespace liod::sim::detail {

namespace {

// The stream of a second route through a world (SceneRequest::route_seed).
constexpr std::uint64_t kRouteStream = 0x726F757465ULL;

struct Grid {
  std::vector<double> xs;  // road lines 0..N+1, plus one virtual line beyond each side
  std::vector<double> ys;
  int n = 0;               // junction lines 1..n are drivable by the route
  double hw = 6.5;         // road half width
  double sidewalk = 3.0;
  bool dense = true;
};

struct NodeState {
  int i = 0;
  int j = 0;
  int dir = 0;  // arrival heading: 0 +x, 1 +y, 2 -x, 3 -y
};

constexpr std::array<int, 4> kDi = {1, 0, -1, 0};
constexpr std::array<int, 4> kDj = {0, 1, 0, -1};

Eigen::Vector2d node_pos(const Grid& g, int i, int j) {
  return {g.xs[static_cast<std::size_t>(i + 1)], g.ys[static_cast<std::size_t>(j + 1)]};
}

/// Shortest no-U-turn path over the inner junctions, random among equals.
std::vector<NodeState> plan_path(const Grid& g, const NodeState& from, int ti, int tj, Rng& rng) {
  const int dirs = 4;
  auto key = [&](const NodeState& s) { return ((s.i * (g.n + 2)) + s.j) * dirs + s.dir; };
  std::map<int, NodeState> parent;
  std::deque<NodeState> q{from};
  parent[key(from)] = from;
  while (!q.empty()) {
    const NodeState s = q.front();
    q.pop_front();
    if (s.i == ti && s.j == tj && key(s) != key(from)) {
      std::vector<NodeState> out{s};
      NodeState c = s;
      while (key(c) != key(from)) {
        c = parent[key(c)];
        out.push_back(c);
      }
      std::reverse(out.begin(), out.end());
      return out;
    }
    std::array<int, 3> turns = {0, 1, 3};
    for (int k = 2; k > 0; --k) {
      std::swap(turns[static_cast<std::size_t>(k)],
                turns[static_cast<std::size_t>(rng.uniform_int(0, k))]);
    }
    for (int t : turns) {
      const int d = (s.dir + t) % 4;
      const NodeState nx{s.i + kDi[static_cast<std::size_t>(d)], s.j + kDj[static_cast<std::size_t>(d)], d};
      if (nx.i < 1 || nx.j < 1 || nx.i > g.n || nx.j > g.n || parent.count(key(nx)) != 0) {
        continue;
      }
      parent[key(nx)] = s;
      q.push_back(nx);
    }
  }
  return {from};
}

void build_block(SceneBuilder& b, const Grid& g, double x0, double x1, double y0, double y1,
                 const std::array<bool, 4>& street, bool loop_style) {
  Rng& rng = b.rng();
  const double w = x1 - x0;
  const double h = y1 - y0;
  if (w < 8.0 || h < 8.0) {
    return;
  }
  const Eigen::Vector2d c(0.5 * (x0 + x1), 0.5 * (y0 + y1));
  const double u = rng.uniform();
  enum class Kind { Buildings, Park, Parking, Plaza, Field } kind = Kind::Buildings;
  if (g.dense) {
    kind = u < 0.72 ? Kind::Buildings : u < 0.82 ? Kind::Park : u < 0.92 ? Kind::Parking : Kind::Plaza;
  } else {
    kind = u < 0.5 ? Kind::Buildings : u < 0.68 ? Kind::Park : u < 0.82 ? Kind::Field
                                      : u < 0.92 ? Kind::Parking : Kind::Buildings;
  }
  (void)loop_style;
  switch (kind) {
    case Kind::Park:
    case Kind::Field: {
      b.paint(Eigen::Vector2d(x0, c.y()), Eigen::Vector2d(x1, c.y()), 0.5 * h, GroundType::Grass);
      const double density = kind == Kind::Park ? 1.0 / 110.0 : 1.0 / 900.0;
      const int n = static_cast<int>(w * h * density);
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector2d p(rng.uniform(x0 + 2, x1 - 2), rng.uniform(y0 + 2, y1 - 2));
        if (rng.bernoulli(0.7)) {
          b.add_tree(p, rng.uniform(0.7, 1.4));
        } else {
          b.add_bush(p);
        }
      }
      if (kind == Kind::Park) {
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector2d p(rng.uniform(x0 + 3, x1 - 3), rng.uniform(y0 + 3, y1 - 3));
          if (b.is_free(p, 0.0, 1.0, 0.4)) {
            b.add_block(p, rng.uniform(0, 3.14), 1.0, 0.35, -0.2, 0.5, Appearance{0.3F});
          }
        }
      }
      return;
    }
    case Kind::Parking: {
      b.paint(Eigen::Vector2d(x0, c.y()), Eigen::Vector2d(x1, c.y()), 0.5 * h, GroundType::Asphalt);
      for (double y = y0 + 4.0; y + 2.5 < y1 - 2.0; y += 16.0) {
        for (double x = x0 + 3.0; x + 1.3 < x1 - 2.0; x += 2.7) {
          if (rng.bernoulli(0.6)) {
            b.add_car(Eigen::Vector2d(x, y + 2.5), std::numbers::pi / 2 + (rng.bernoulli(0.5) ? 0 : std::numbers::pi),
                      rng.bernoulli(0.08));
          }
          if (y + 11.0 < y1 - 2.0 && rng.bernoulli(0.6)) {
            b.add_car(Eigen::Vector2d(x, y + 10.0), std::numbers::pi / 2, rng.bernoulli(0.08));
          }
        }
      }
      b.add_pole(Eigen::Vector2d(x0 + 1.0, y0 + 1.0), 9.0, 0.15, true, 0.8);
      b.add_pole(Eigen::Vector2d(x1 - 1.0, y1 - 1.0), 9.0, 0.15, true, -2.3);
      return;
    }
    case Kind::Plaza: {
      b.paint(Eigen::Vector2d(x0, c.y()), Eigen::Vector2d(x1, c.y()), 0.5 * h, GroundType::Concrete);
      for (int k = 0; k < 6; ++k) {
        const Eigen::Vector2d p(rng.uniform(x0 + 4, x1 - 4), rng.uniform(y0 + 4, y1 - 4));
        if (rng.bernoulli(0.5)) {
          b.add_tree(p, 0.9);
        } else {
          b.add_pole(p, rng.uniform(3.5, 6.0), 0.1, rng.bernoulli(0.5), rng.uniform(0, 6.28));
        }
      }
      if (rng.bernoulli(0.6)) {
        b.add_block(c, rng.uniform(0, 3.14), rng.uniform(2, 4), rng.uniform(2, 3), -0.3,
                    rng.uniform(2.5, 4), Appearance{static_cast<float>(facade_reflectivity(rng))});
      }
      return;
    }
    case Kind::Buildings:
      break;
  }
  if (g.dense) {
    b.paint(Eigen::Vector2d(x0, c.y()), Eigen::Vector2d(x1, c.y()), 0.5 * h, GroundType::Concrete);
  }
  // Walk each side facing a street and line it with buildings.
  const std::array<Eigen::Vector2d, 4> starts = {Eigen::Vector2d(x0, y0), Eigen::Vector2d(x1, y0),
                                                 Eigen::Vector2d(x1, y1), Eigen::Vector2d(x0, y1)};
  const std::array<Eigen::Vector2d, 4> dirs = {Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1),
                                               Eigen::Vector2d(-1, 0), Eigen::Vector2d(0, -1)};
  for (std::size_t side = 0; side < 4; ++side) {
    if (!street[side]) {
      continue;
    }
    const Eigen::Vector2d dir = dirs[side];
    const Eigen::Vector2d inward(-dir.y(), dir.x());
    const double len = (side % 2 == 0) ? w : h;
    const double block_depth = (side % 2 == 0) ? h : w;
    double s = g.dense ? 0.0 : rng.uniform(2.0, 8.0);
    while (s < len - 6.0) {
      double width = g.dense ? rng.uniform(10.0, 28.0) : rng.uniform(9.0, 15.0);
      width = std::min(width, len - s);
      double depth = g.dense ? rng.uniform(10.0, 22.0) : rng.uniform(8.0, 12.0);
      depth = std::min(depth, 0.5 * block_depth - 1.0);
      const double setback = g.dense ? (rng.bernoulli(0.7) ? 0.0 : rng.uniform(1.0, 4.0))
                                     : rng.uniform(4.0, 9.0);
      BuildingStyle style = BuildingStyle::House;
      double height = rng.uniform(5.0, 8.5);
      if (g.dense) {
        const bool tower = rng.bernoulli(0.3);
        style = tower ? BuildingStyle::Tower : BuildingStyle::Block;
        height = tower ? rng.uniform(20.0, 45.0) : rng.uniform(8.0, 22.0);
      } else if (rng.bernoulli(0.15)) {
        style = BuildingStyle::Warehouse;
        height = rng.uniform(5.0, 9.0);
      }
      if (depth > 5.0 && width > 5.0) {
        const Eigen::Vector2d front = starts[side] + dir * (s + width / 2.0) + inward * setback;
        b.add_building(front, -inward, width, depth, height, style);
        if (!g.dense && rng.bernoulli(0.5)) {
          b.add_tree(front - inward * (depth + rng.uniform(2, 5)) + dir * rng.uniform(-3, 3));
        }
      }
      const double gap = g.dense ? (rng.bernoulli(0.75) ? 0.3 : rng.uniform(3.0, 10.0))
                                 : rng.uniform(4.0, 12.0);
      s += width + gap;
    }
  }
}

// The corners of the urban random walk. `any_start`: the walk starts on a random street in a random
// direction (a second drive through the same world); else on the first street of a random row,
// heading +x. The first excursion goes round one block, so even a short drive revisits its start.
std::vector<Eigen::Vector2d> walk_corners(const Grid& g, const SceneRequest& req, Rng& rng, bool any_start) {
  const int sj = rng.uniform_int(1, g.n);
  NodeState cur{2, sj, 0};
  if (any_start) {
    do {
      cur = NodeState{rng.uniform_int(1, g.n), rng.uniform_int(1, g.n), rng.uniform_int(0, 3)};
    } while (cur.i - kDi[static_cast<std::size_t>(cur.dir)] < 1 || cur.i - kDi[static_cast<std::size_t>(cur.dir)] > g.n ||
             cur.j - kDj[static_cast<std::size_t>(cur.dir)] < 1 || cur.j - kDj[static_cast<std::size_t>(cur.dir)] > g.n);
  }
  const NodeState home = cur;
  const Eigen::Vector2d before =
      node_pos(g, cur.i - kDi[static_cast<std::size_t>(cur.dir)], cur.j - kDj[static_cast<std::size_t>(cur.dir)]);
  std::vector<Eigen::Vector2d> corners = {0.5 * (before + node_pos(g, cur.i, cur.j)), node_pos(g, cur.i, cur.j)};
  const double needed = req.max_speed * req.duration + 300.0;
  double length = (corners[1] - corners[0]).norm();
  bool first = true;
  while (length < needed) {
    int ti = 0;
    int tj = 0;
    if (first) {
      ti = cur.i + 1 <= g.n ? cur.i + 1 : cur.i - 1;
      tj = cur.j + 1 <= g.n ? cur.j + 1 : cur.j - 1;
      first = false;
    } else {
      do {
        ti = rng.uniform_int(1, g.n);
        tj = rng.uniform_int(1, g.n);
      } while (std::abs(ti - cur.i) + std::abs(tj - cur.j) < 2);
    }
    for (int leg = 0; leg < 2; ++leg) {
      const int gi = leg == 0 ? ti : home.i;
      const int gj = leg == 0 ? tj : home.j;
      const auto path = plan_path(g, cur, gi, gj, rng);
      for (std::size_t k = 1; k < path.size(); ++k) {
        const Eigen::Vector2d p = node_pos(g, path[k].i, path[k].j);
        length += (p - corners.back()).norm();
        corners.push_back(p);
      }
      cur = path.back();
    }
  }
  // End half-way down the next street so the last junction is a real one.
  corners.push_back(corners.back() + 0.5 * Eigen::Vector2d(kDi[static_cast<std::size_t>(cur.dir)],
                                                             kDj[static_cast<std::size_t>(cur.dir)]) *
                                         70.0);
  return corners;
}

// The suburban loop: one loop around blocks, its perimeter fitted to the drive, driven lap after lap.
std::vector<Eigen::Vector2d> loop_corners(const Grid& g, const SceneRequest& req, Rng& rng) {
  const double expected = 0.6 * req.max_speed * req.duration;
  const double target = std::clamp(expected / 1.6, 300.0, 1600.0);
  int best_a = 1;
  int best_b = 1;
  double best_err = 1e18;
  for (int a = 1; a <= 3; ++a) {
    for (int b = 1; b <= 3; ++b) {
      const double per = 2.0 * ((node_pos(g, 1 + a, 1) - node_pos(g, 1, 1)).norm() +
                                (node_pos(g, 1, 1 + b) - node_pos(g, 1, 1)).norm());
      if (std::abs(per - target) < best_err) {
        best_err = std::abs(per - target);
        best_a = a;
        best_b = b;
      }
    }
  }
  const int i0 = 1 + rng.uniform_int(0, g.n - best_a - 1);
  const int j0 = 1 + rng.uniform_int(0, g.n - best_b - 1);
  const std::vector<Eigen::Vector2d> lap = {
      0.5 * (node_pos(g, i0, j0) + node_pos(g, i0 + best_a, j0)), node_pos(g, i0 + best_a, j0),
      node_pos(g, i0 + best_a, j0 + best_b), node_pos(g, i0, j0 + best_b), node_pos(g, i0, j0)};
  const double per = 2.0 * ((node_pos(g, i0 + best_a, j0) - node_pos(g, i0, j0)).norm() +
                            (node_pos(g, i0, j0 + best_b) - node_pos(g, i0, j0)).norm());
  const int laps = static_cast<int>(std::ceil((req.max_speed * req.duration + 300.0) / per));
  return repeat_loop(lap, laps);
}

// The lane along the corners and its speed profile.
DrivePlan plan_drive(const std::vector<Eigen::Vector2d>& corners, double cruise, bool loop_route, Rng& rng) {
  // Dense lane path: right-hand traffic, lane centre 2 m right of the road centre line.
  const std::vector<Eigen::Vector2d> centre = rounded_polyline(corners, 9.0, 1.0);
  const std::vector<Eigen::Vector2d> lane =
      offset_polyline(centre, std::vector<double>(centre.size(), 2.0));
  DrivePlan plan;
  plan.points = lane;
  plan.road_centre = centre;
  plan.lanes_with = {2.0};
  plan.lanes_against = {2.0};
  plan.cruise_speed = cruise;
  plan.speed_cap.assign(lane.size(), cruise);
  const std::vector<double> s_lane = polyline_arclength(lane);
  // Traffic: every street has its own pace; straight through a junction a driver slows a bit;
  // some junctions have a red light or a stop sign.
  const std::vector<std::size_t> at = locate_in_order(lane, std::vector<Eigen::Vector2d>(
                                                                corners.begin() + 1, corners.end() - 1));
  double last_stop = 0.0;
  std::size_t prev = 0;
  for (std::size_t k = 0; k < at.size(); ++k) {
    const double pace = rng.uniform(0.75, 1.0) * cruise;
    for (std::size_t i = prev; i < at[k] && i < lane.size(); ++i) {
      plan.speed_cap[i] = pace;
    }
    prev = at[k];
    if (at[k] >= lane.size()) continue;  // a corner the lane never passes near (read past the end before)
    const double sj = s_lane[at[k]];
    for (std::size_t i = 0; i < lane.size(); ++i) {
      if (std::abs(s_lane[i] - sj) < 12.0) {
        plan.speed_cap[i] = std::min(plan.speed_cap[i], 0.75 * cruise);
      }
    }
    const double p_stop = loop_route ? 0.12 : 0.25;
    if (sj - 10.0 > last_stop + 40.0 && sj > 60.0 && rng.bernoulli(p_stop)) {
      plan.stops.push_back(Stop{sj - 10.0, rng.uniform(2.0, 8.0)});
      last_stop = sj;
    }
  }
  return plan;
}

}  // namespace

Scene make_city(const SceneRequest& req, Rng& rng, bool loop_route) {
  Grid g;
  g.dense = !loop_route;
  g.n = loop_route ? 4 : std::clamp(4 + static_cast<int>(req.duration / 150.0), 4, 7);
  g.hw = g.dense ? 6.5 : 6.0;
  g.sidewalk = g.dense ? 3.0 : 2.0;
  const double lo = g.dense ? 75.0 : 90.0;
  const double hi = g.dense ? 110.0 : 135.0;
  auto make_lines = [&](std::vector<double>& v) {
    v.push_back(-45.0);
    v.push_back(0.0);
    for (int k = 1; k <= g.n + 1; ++k) {
      v.push_back(v.back() + rng.uniform(lo, hi));
    }
    v.push_back(v.back() + 45.0);
  };
  make_lines(g.xs);
  make_lines(g.ys);

  // The route. The world is drawn after it from the same stream, so a second route through the
  // same world (`route_seed`) is drawn from a stream of its own after the first one.
  Scene scene;
  scene.plan = plan_drive(loop_route ? loop_corners(g, req, rng) : walk_corners(g, req, rng, false), req.max_speed,
                          loop_route, rng);
  const std::vector<Eigen::Vector2d> lane = scene.plan.points;
  if (req.route_seed) {
    Rng route(derive_seed(*req.route_seed, kRouteStream));
    scene.plan = plan_drive(loop_route ? loop_corners(g, req, route) : walk_corners(g, req, route, true),
                            req.max_speed, loop_route, route);
  }
  scene.plan.road_half_width = g.hw;

  // World extents and terrain.
  std::vector<Eigen::Vector2d> extent = {Eigen::Vector2d(g.xs.front(), g.ys.front()),
                                         Eigen::Vector2d(g.xs.back(), g.ys.back())};
  extent.insert(extent.end(), lane.begin(), lane.end());
  Eigen::Vector2d wmin;
  Eigen::Vector2d wmax;
  bounds_with_margin(extent, 170.0, wmin, wmax);
  const std::vector<Eigen::Vector2d> hills = {
      node_pos(g, rng.uniform_int(1, g.n), rng.uniform_int(1, g.n)) +
      Eigen::Vector2d(rng.uniform(-30, 30), rng.uniform(-30, 30))};
  scene.world.terrain = make_terrain(rng, 1.0, hills);
  SceneBuilder b(scene.world, rng);
  b.allocate(wmin, wmax);

  // Roads: every grid line except the virtual outer ones.
  const double x_lo = g.xs.front();
  const double x_hi = g.xs.back();
  const double y_lo = g.ys.front();
  const double y_hi = g.ys.back();
  for (std::size_t k = 1; k + 1 < g.xs.size(); ++k) {
    b.paint({g.xs[k], y_lo}, {g.xs[k], y_hi}, g.hw + g.sidewalk, GroundType::Concrete);
  }
  for (std::size_t k = 1; k + 1 < g.ys.size(); ++k) {
    b.paint({x_lo, g.ys[k]}, {x_hi, g.ys[k]}, g.hw + g.sidewalk, GroundType::Concrete);
  }
  for (std::size_t k = 1; k + 1 < g.xs.size(); ++k) {
    b.add_road({g.xs[k], y_lo}, {g.xs[k], y_hi}, g.hw);
  }
  for (std::size_t k = 1; k + 1 < g.ys.size(); ++k) {
    b.add_road({x_lo, g.ys[k]}, {x_hi, g.ys[k]}, g.hw);
  }

  // Street furniture and parked cars, street segment by street segment.
  const double clear = g.hw + 7.0;  // keep junction mouths open
  auto furnish_street = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& c) {
    const Eigen::Vector2d dir = (c - a).normalized();
    const Eigen::Vector2d a2 = a + dir * clear;
    const Eigen::Vector2d c2 = c - dir * clear;
    if ((c2 - a2).dot(dir) < 10.0) {
      return;
    }
    SideFurniture f;
    f.lamp_spacing = rng.uniform(24.0, 36.0);
    f.tree_spacing = rng.bernoulli(g.dense ? 0.5 : 0.8) ? rng.uniform(8.0, 14.0) : 0.0;
    f.tree_offset = g.dense ? 1.6 : g.sidewalk + 1.5;
    f.sign_probability = 0.4;
    for (double side : {1.0, -1.0}) {
      furnish_side(b, a2, c2, g.hw, side, f);
      const Eigen::Vector2d out = Eigen::Vector2d(dir.y(), -dir.x()) * side;
      if (rng.bernoulli(g.dense ? 0.75 : 0.3)) {
        const double len = (c2 - a2).norm();
        for (double s = 3.0; s < len - 3.0; s += 6.0) {
          if (rng.bernoulli(0.55)) {
            const double yaw = std::atan2(dir.y() * side, dir.x() * side);
            b.add_car(a2 + dir * s + out * (g.hw - 1.15), yaw, rng.bernoulli(0.1), true);
          }
        }
      }
      if (rng.bernoulli(0.5)) {
        // Bins and bollards: small things a feature extractor should not trust.
        const double s = rng.uniform(0.0, (c2 - a2).norm());
        const Eigen::Vector2d p = a2 + dir * s + out * (g.hw + rng.uniform(0.4, 1.2));
        if (b.is_free(p, 0.0, 0.4, 0.4)) {
          b.add_pole(p, rng.uniform(0.8, 1.1), rng.uniform(0.1, 0.3), false);
        }
      }
    }
  };
  for (std::size_t k = 1; k + 1 < g.xs.size(); ++k) {
    for (std::size_t m = 1; m + 2 < g.ys.size(); ++m) {
      furnish_street({g.xs[k], g.ys[m]}, {g.xs[k], g.ys[m + 1]});
    }
    furnish_street({g.xs[k], g.ys[0]}, {g.xs[k], g.ys[1]});
    furnish_street({g.xs[k], g.ys[g.ys.size() - 2]}, {g.xs[k], g.ys.back()});
  }
  for (std::size_t m = 1; m + 1 < g.ys.size(); ++m) {
    for (std::size_t k = 1; k + 2 < g.xs.size(); ++k) {
      furnish_street({g.xs[k], g.ys[m]}, {g.xs[k + 1], g.ys[m]});
    }
    furnish_street({g.xs[0], g.ys[m]}, {g.xs[1], g.ys[m]});
    furnish_street({g.xs[g.xs.size() - 2], g.ys[m]}, {g.xs.back(), g.ys[m]});
  }

  // Blocks between the lines (the outermost ones face only their one street).
  const double off = g.hw + g.sidewalk;
  for (std::size_t i = 0; i + 1 < g.xs.size(); ++i) {
    for (std::size_t j = 0; j + 1 < g.ys.size(); ++j) {
      const bool west_road = i >= 1;
      const bool east_road = i + 2 < g.xs.size();
      const bool south_road = j >= 1;
      const bool north_road = j + 2 < g.ys.size();
      const double x0 = g.xs[i] + (west_road ? off : 0.0);
      const double x1 = g.xs[i + 1] - (east_road ? off : 0.0);
      const double y0 = g.ys[j] + (south_road ? off : 0.0);
      const double y1 = g.ys[j + 1] - (north_road ? off : 0.0);
      // Sides in order: south (walk +x), east (+y), north (-x), west (-y).
      build_block(b, g, x0, x1, y0, y1, {south_road, east_road, north_road, west_road}, loop_route);
    }
  }
  // Beyond the city: open country with scattered trees, so far returns are not all walls.
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector2d p(rng.uniform(wmin.x(), wmax.x()), rng.uniform(wmin.y(), wmax.y()));
    if (p.x() < x_lo || p.x() > x_hi || p.y() < y_lo || p.y() > y_hi) {
      b.add_tree(p, rng.uniform(0.8, 1.5));
    }
  }
  scene.road_roughness = g.dense ? 40e-6 : 25e-6;
  scene.summary = std::string(loop_route ? "suburban grid, one loop around blocks driven lap after lap"
                                         : "dense city grid, random walk returning to its start") +
                  ", " + std::to_string(g.n) + "x" + std::to_string(g.n) + " junctions";
  return scene;
}

}  // namespace liod::sim::detail
