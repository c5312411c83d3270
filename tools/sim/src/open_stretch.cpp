// An open stretch (liod-sim --open-stretch): a hundred metres of route through open country,
// nothing but the ground and a hedge along one side, where a LiDAR odometry has little to hold on
// to along the track.

#include <algorithm>
#include <cmath>

#include "liod/sim/conditions.hpp"
#include "liod/sim/scene_builder.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kOpenStream = 0x6F70656EULL;

double distance_to_path(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& path) {
  double best = 1e18;
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Eigen::Vector2d ab = path[i] - path[i - 1];
    const double f = std::clamp((p - path[i - 1]).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
    best = std::min(best, (path[i - 1] + f * ab - p).norm());
  }
  return best;
}

template <class T, class Reach>
std::size_t remove_near(std::vector<T>& items, const std::vector<Eigen::Vector2d>& path, Reach reach) {
  const std::size_t before = items.size();
  items.erase(std::remove_if(items.begin(), items.end(),
                             [&](const T& x) {
                               Eigen::Vector2d c;
                               const double r = reach(x, c);
                               return distance_to_path(c, path) - r < kOpenClearance;
                             }),
              items.end());
  return before - items.size();
}

std::size_t nearest_index(const std::vector<Eigen::Vector2d>& pts, const Eigen::Vector2d& p) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    if ((pts[i] - p).squaredNorm() < (pts[best] - p).squaredNorm()) {
      best = i;
    }
  }
  return best;
}
}  // namespace

OpenStretch clear_open_stretch(Scene& scene, const Trajectory& ego, double duration, std::uint64_t seed) {
  Rng rng(derive_seed(seed, kOpenStream));
  const DrivePlan& plan = scene.plan;
  OpenStretch out;
  out.t_begin = rng.uniform(0.3, 0.55) * duration;
  // The route may pass a place more than once: search the plan near where the car has got to.
  const std::vector<double> s = polyline_arclength(plan.points);
  std::size_t i0 = 0;
  {
    double driven = 0.0;
    Eigen::Vector3d prev = ego.pose(0.0).translation;
    for (double t = 0.1; t <= out.t_begin; t += 0.1) {
      const Eigen::Vector3d p = ego.pose(t).translation;
      driven += (p - prev).head<2>().norm();
      prev = p;
    }
    const Eigen::Vector2d here = prev.head<2>();
    const std::size_t lo = std::min(plan.points.size() - 1, static_cast<std::size_t>(std::max(0.0, driven - 40.0)));
    const std::size_t hi = std::min(plan.points.size(), static_cast<std::size_t>(driven + 60.0));
    const std::vector<Eigen::Vector2d> window(plan.points.begin() + static_cast<std::ptrdiff_t>(lo),
                                              plan.points.begin() + static_cast<std::ptrdiff_t>(std::max(hi, lo + 1)));
    i0 = lo + nearest_index(window, here);
  }
  std::size_t i1 = i0;
  while (i1 + 1 < plan.points.size() && s[i1] - s[i0] < kOpenLength) {
    ++i1;
  }
  out.path.assign(plan.points.begin() + static_cast<std::ptrdiff_t>(i0),
                  plan.points.begin() + static_cast<std::ptrdiff_t>(i1) + 1);
  for (double t = out.t_begin; t <= duration + 1.0; t += 0.05) {
    out.t_end = t;
    if ((ego.pose(t).translation.head<2>() - out.path.back()).norm() < 1.5) {
      break;
    }
  }

  World& w = scene.world;
  out.removed += remove_near(w.boxes, out.path, [](const Box& b, Eigen::Vector2d& c) {
    c = b.center.head<2>();
    return (b.rotation.cwiseAbs() * b.half).head<2>().norm();
  });
  out.removed += remove_near(w.cylinders, out.path, [](const Cylinder& cy, Eigen::Vector2d& c) {
    c = cy.center;
    return cy.radius;
  });
  out.removed += remove_near(w.ellipsoids, out.path, [](const Ellipsoid& e, Eigen::Vector2d& c) {
    c = e.center.head<2>();
    return e.radii.head<2>().maxCoeff();
  });

  // The hedge: right of the road, from a little before the stretch to a little after it, in 4 m
  // pieces, leaving a gap wherever the route passes at another time (a street crossing it).
  SceneBuilder b(w, rng);
  const std::size_t h0 = i0 > 30 ? i0 - 30 : 0;
  const std::size_t h1 = std::min(plan.points.size() - 1, i1 + 30);
  std::vector<Eigen::Vector2d> elsewhere;
  for (std::size_t i = 0; i < plan.points.size(); ++i) {
    if (i + 40 < h0 || i > h1 + 40) {
      elsewhere.push_back(plan.points[i]);
    }
  }
  const double height = rng.uniform(1.3, 1.8);
  const double extinction = rng.uniform(2.0, 3.5);
  for (std::size_t i = h0; i + 4 <= h1; i += 4) {
    auto side = [&](std::size_t k) {
      const Eigen::Vector2d t = (plan.points[std::min(k + 1, plan.points.size() - 1)] - plan.points[k > 0 ? k - 1 : 0]).normalized();
      const bool road = plan.road_centre.size() == plan.points.size();
      const double reach = (road ? plan.road_half_width : 2.5) + 1.6;
      const Eigen::Vector2d base = road ? plan.road_centre[k] : plan.points[k];
      return Eigen::Vector2d(base.x() + reach * t.y(), base.y() - reach * t.x());
    };
    const Eigen::Vector2d a = side(i);
    const Eigen::Vector2d c = side(i + 4);
    const Eigen::Vector2d m = 0.5 * (a + c);
    bool crossing = false;
    for (const auto& p : elsewhere) {
      crossing = crossing || (p - m).squaredNorm() < 36.0;
    }
    if (!crossing && (c - a).norm() > 0.5) {
      b.add_strip(a, c, 1.2, -0.2, height, Appearance{0.42F, SurfaceKind::Porous, static_cast<float>(extinction)});
      ++out.hedge;
    }
  }
  return out;
}

}  // namespace liod::sim
