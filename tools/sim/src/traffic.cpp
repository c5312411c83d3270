#include "liod/sim/traffic.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "liod/sim/scene_builder.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kTrafficStream = 0x74726166ULL;
constexpr double kEgoHalfLength = 2.35;  // EgoBody::passenger_car
constexpr double kEgoHalfWidth = 0.92;
constexpr double kLateralAccel = 2.5;    // m/s^2 other drivers take bends at
constexpr double kBrake = 1.5;           // m/s^2 planned deceleration
constexpr double kStandingGap = 2.0;     // m bumper to bumper in a queue

struct Motion {
  double cruise = 10.0;
  std::vector<Stop> stops;  // sorted, metres along the lane
};

/// Speed limit along a lane (one value per metre): bends taken at kLateralAccel, braking for
/// them planned at kBrake.
std::vector<double> bend_limits(const std::vector<Eigen::Vector2d>& pts) {
  const std::size_t n = pts.size();
  std::vector<double> cap(n, 1e9);
  for (std::size_t i = 3; i + 3 < n; ++i) {
    const Eigen::Vector2d a = (pts[i] - pts[i - 3]).normalized();
    const Eigen::Vector2d b = (pts[i + 3] - pts[i]).normalized();
    const double turn = std::abs(std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)));
    const double kappa = turn / 3.0;
    if (kappa > 1e-4) {
      cap[i] = std::sqrt(kLateralAccel / kappa);
    }
  }
  for (std::size_t i = n - 1; i-- > 0;) {
    cap[i] = std::min(cap[i], std::sqrt(cap[i + 1] * cap[i + 1] + 2.0 * kBrake));
  }
  return cap;
}

/// A driver alone on the lane: cruise, slow for bends, stop at its stop lines.
std::vector<float> drive_alone(double s0, const Motion& m, const std::vector<double>& cap,
                               std::size_t steps) {
  std::vector<float> out(steps);
  const double dt = kTrafficStep;
  const double end = static_cast<double>(cap.size() - 1);
  auto cap_at = [&](double s) { return cap[static_cast<std::size_t>(std::clamp(s, 0.0, end))]; };
  double s = s0;
  double v = std::min(m.cruise, cap_at(s));
  double dwell_until = -1.0;
  std::size_t next = 0;
  while (next < m.stops.size() && m.stops[next].s < s0 + 5.0) {
    ++next;
  }
  for (std::size_t k = 0; k < steps; ++k) {
    out[k] = static_cast<float>(s);
    const double t = static_cast<double>(k) * dt;
    if (t < dwell_until) {
      continue;
    }
    double v_ref = std::min(m.cruise, cap_at(s + v));
    if (next < m.stops.size()) {
      const double gap = m.stops[next].s - s;
      v_ref = std::min(v_ref, std::sqrt(2.0 * kBrake * std::max(0.0, gap - 0.5)));
      if (gap < 1.0 && v < 0.5) {
        dwell_until = t + m.stops[next].duration;
        ++next;
        v = 0.0;
        continue;
      }
    }
    v = std::max(0.0, v + std::clamp(v_ref - v, -3.0 * dt, 1.5 * dt));
    s += v * dt;
  }
  return out;
}

/// Keeps `s` at least a time gap and a standing gap behind (ahead = true: in front of) `other`.
void keep_gap(std::vector<float>& s, const std::vector<float>& other, double gap, double tau, bool ahead) {
  const auto lag = static_cast<std::ptrdiff_t>(std::lround(tau / kTrafficStep));
  const auto n = static_cast<std::ptrdiff_t>(s.size());
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    const std::ptrdiff_t j = std::clamp(ahead ? k + lag : k - lag, std::ptrdiff_t{0}, n - 1);
    const auto bound = static_cast<float>(static_cast<double>(other[static_cast<std::size_t>(j)]) + (ahead ? gap : -gap));
    float& v = s[static_cast<std::size_t>(k)];
    v = ahead ? std::max(v, bound) : std::min(v, bound);
  }
}

/// Do two rectangles (centre, unit heading, half length, half width) overlap?
bool rectangles_overlap(const Eigen::Vector2d& c1, const Eigen::Vector2d& h1, double l1, double w1,
                        const Eigen::Vector2d& c2, const Eigen::Vector2d& h2, double l2, double w2) {
  const Eigen::Vector2d axes[4] = {h1, Eigen::Vector2d(-h1.y(), h1.x()), h2, Eigen::Vector2d(-h2.y(), h2.x())};
  const Eigen::Vector2d d = c2 - c1;
  for (const auto& a : axes) {
    const double r1 = l1 * std::abs(h1.dot(a)) + w1 * std::abs(h1.x() * a.y() - h1.y() * a.x());
    const double r2 = l2 * std::abs(h2.dot(a)) + w2 * std::abs(h2.x() * a.y() - h2.y() * a.x());
    if (std::abs(d.dot(a)) > r1 + r2) {
      return false;
    }
  }
  return true;
}

TrafficVehicle draw_vehicle(Rng& rng, std::uint32_t lane, double truck_share) {
  TrafficVehicle v;
  v.lane = lane;
  const double u = rng.uniform();
  if (u < truck_share) {
    v.half_length = rng.uniform(4.0, 6.0);
    v.half_width = 1.25;
    v.top = rng.uniform(3.0, 3.8);
  } else if (u < truck_share + 0.15) {
    v.half_length = rng.uniform(2.5, 3.0);
    v.half_width = 1.0;
    v.top = rng.uniform(2.0, 2.6);
  } else {
    v.half_length = rng.uniform(2.0, 2.45);
    v.half_width = rng.uniform(0.85, 0.95);
  }
  v.paint = vehicle_paint(rng);
  return v;
}

/// Metres along `lane` (1 m points) of the car at each traffic step: a forward local search.
std::vector<float> ego_along(const std::vector<Eigen::Vector2d>& lane, const Trajectory& ego, std::size_t steps) {
  std::vector<float> s(steps);
  std::size_t at = 0;
  double best = 1e18;
  const Eigen::Vector2d p0 = ego.pose(0.0).translation.head<2>();
  for (std::size_t i = 0; i < std::min<std::size_t>(lane.size(), 80); ++i) {
    if ((lane[i] - p0).squaredNorm() < best) {
      best = (lane[i] - p0).squaredNorm();
      at = i;
    }
  }
  for (std::size_t k = 0; k < steps; ++k) {
    const Eigen::Vector2d p = ego.pose(static_cast<double>(k) * kTrafficStep).translation.head<2>();
    const std::size_t lo = at > 3 ? at - 3 : 0;
    const std::size_t hi = std::min(lane.size(), at + 40);
    best = 1e18;
    for (std::size_t i = lo; i < hi; ++i) {
      if ((lane[i] - p).squaredNorm() < best) {
        best = (lane[i] - p).squaredNorm();
        at = i;
      }
    }
    s[k] = static_cast<float>(at);
  }
  return s;
}
}  // namespace

Traffic::Traffic(const DrivePlan& plan, const Trajectory& ego, const Terrain& terrain, double duration,
                 std::uint64_t seed)
    : terrain_(terrain) {
  if (plan.road_centre.size() != plan.points.size() || plan.lanes_with.empty()) {
    throw std::invalid_argument("--traffic needs a route with lanes (urban, loop, highway, tunnel)");
  }
  Rng rng(derive_seed(seed, kTrafficStream));
  const std::size_t first_against = build_lanes(plan);
  const auto steps = static_cast<std::size_t>(std::ceil((duration + 1.0) / kTrafficStep)) + 1;
  const std::vector<float> ego_s = ego_along(lanes_[0].points, ego, steps);
  for (std::uint32_t li = 0; li < lanes_.size(); ++li) {
    populate(li, li >= first_against, plan, ego_s, rng);
  }
  leave_out_touching(ego, duration);
}

std::size_t Traffic::build_lanes(const DrivePlan& plan) {
  // Lane 0 is the car's own; then, on a dual carriageway, the other lane of its carriageway (the
  // one the car is not in); then the opposite lanes, each listed in its own driving direction.
  const std::vector<Eigen::Vector2d>& centre = plan.road_centre;
  lanes_.push_back(Lane{resample_polyline(plan.points, 1.0)});
  if (plan.lanes_with.size() == 2) {
    std::vector<double> other(centre.size());
    for (std::size_t i = 0; i < centre.size(); ++i) {
      other[i] = plan.lanes_with[0] + plan.lanes_with[1] - (plan.points[i] - centre[i]).norm();
    }
    lanes_.push_back(Lane{resample_polyline(offset_polyline(centre, other), 1.0)});
  }
  const std::size_t first_against = lanes_.size();
  for (double o : plan.lanes_against) {
    std::vector<Eigen::Vector2d> pts = offset_polyline(centre, std::vector<double>(centre.size(), -o));
    std::reverse(pts.begin(), pts.end());
    lanes_.push_back(Lane{resample_polyline(pts, 1.0)});
  }
  return first_against;
}

void Traffic::populate(std::uint32_t li, bool against, const DrivePlan& plan, const std::vector<float>& ego_s,
                       Rng& rng) {
  const bool dual = plan.lanes_with.size() == 2;
  const bool own = li == 0;
  const std::vector<Eigen::Vector2d>& pts = lanes_[li].points;
  const std::vector<double> cap = bend_limits(pts);
  const double length = static_cast<double>(pts.size() - 1);
  // Junction stops: the car's own stop lines, mirrored onto the opposite lanes (one road width
  // back, so that they stop before the junction in their direction).
  std::vector<Stop> junctions;
  if (!dual) {
    for (const Stop& st : plan.stops) {
      junctions.push_back(Stop{against ? length - st.s - 20.0 : st.s, 0.0});
    }
    std::sort(junctions.begin(), junctions.end(), [](const Stop& a, const Stop& b) { return a.s < b.s; });
  }
  // Spawn positions at t = 0: ahead of the car in its own lane (plus a follower or two behind),
  // along the whole lane elsewhere.
  const double mean_gap = own ? 180.0 : (against ? (dual ? 90.0 : 60.0) : 90.0);
  const auto ego0 = static_cast<double>(ego_s[0]);
  std::vector<double> starts;
  const double from = own ? ego0 + rng.uniform(15.0, 40.0) : (against ? 0.0 : std::max(0.0, ego0 - 300.0));
  for (double s = from; s < length - 10.0; s += rng.exponential(mean_gap) + 15.0) {
    starts.push_back(s);
  }
  std::vector<double> behind;
  if (own) {
    for (int k = rng.uniform_int(0, 2), b = 1; b <= k; ++b) {
      behind.push_back(ego0 - 12.0 * b - rng.uniform(0.0, 10.0));
    }
  }
  auto make = [&](double s0, double speed_lo, double speed_hi) {
    TrafficVehicle v = draw_vehicle(rng, li, dual ? 0.25 : 0.1);
    Motion m;
    m.cruise = rng.uniform(speed_lo, speed_hi) * plan.cruise_speed;
    for (const Stop& st : junctions) {
      if (rng.bernoulli(0.5)) {
        m.stops.push_back(Stop{st.s, rng.uniform(2.0, 8.0)});
      }
    }
    v.s = drive_alone(s0, m, cap, ego_s.size());
    return v;
  };
  // Each vehicle is kept behind the one in front of it; in the car's own lane the car itself is
  // the reference: the vehicles ahead are kept ahead of it, the followers behind.
  auto chain = [&](const std::vector<double>& at, double lo, double hi, double tau_lo, bool ahead, bool from_ego) {
    const std::size_t first = vehicles_.size();
    for (double s0 : at) {
      TrafficVehicle v = make(s0, lo, hi);
      const bool has_prev = vehicles_.size() > first;
      if (has_prev || from_ego) {
        const std::vector<float>& prev = has_prev ? vehicles_.back().s : ego_s;
        const double half = has_prev ? vehicles_.back().half_length : kEgoHalfLength;
        keep_gap(v.s, prev, half + v.half_length + kStandingGap, rng.uniform(tau_lo, 2.0), ahead);
      }
      vehicles_.push_back(std::move(v));
    }
  };
  if (own) {
    // Ahead of the car, nearest first, at least as fast as it would like to go: a slower one
    // would end up pinned to its bumper, moving with it, which the gap rule only allows at stops.
    chain(starts, 1.0, 1.2, 1.0, true, true);
    chain(behind, 1.0, 1.2, 1.2, false, true);
  } else {
    std::reverse(starts.begin(), starts.end());  // front first
    chain(starts, against ? 0.65 : 0.8, against ? 1.05 : 1.3, 1.0, false, false);
  }
}

void Traffic::leave_out_touching(const Trajectory& ego, double duration) {
  // Leave out every vehicle that would ever touch the car (lane changes, a route that drives a
  // street again the other way, crossings): a stand-in for the traffic rules.
  std::vector<TrafficVehicle> kept;
  for (std::size_t i = 0; i < vehicles_.size(); ++i) {
    bool touches = false;
    for (double t = 0.0; t <= duration && !touches; t += 0.1) {
      Eigen::Vector2d c;
      Eigen::Vector2d h;
      double v = 0.0;
      if (!place(i, t, c, h, v)) {
        continue;
      }
      const Pose e = ego.pose(t);
      const Eigen::Vector2d eh = e.rotation.col(0).head<2>().normalized();
      touches = rectangles_overlap(e.translation.head<2>(), eh, kEgoHalfLength + 0.5, kEgoHalfWidth + 0.3, c, h,
                                   vehicles_[i].half_length, vehicles_[i].half_width);
    }
    if (!touches) {
      kept.push_back(vehicles_[i]);
    }
  }
  vehicles_ = std::move(kept);
}

Eigen::Vector2d Traffic::lane_point(const Lane& lane, double s) const {
  const double end = static_cast<double>(lane.points.size() - 1);
  const double x = std::clamp(s, 0.0, end - 1e-9);
  const auto i = static_cast<std::size_t>(x);
  const double f = x - static_cast<double>(i);
  return (1.0 - f) * lane.points[i] + f * lane.points[std::min(i + 1, lane.points.size() - 1)];
}

bool Traffic::place(std::size_t i, double t, Eigen::Vector2d& position, Eigen::Vector2d& heading,
                    double& speed) const {
  const TrafficVehicle& v = vehicles_[i];
  const Lane& lane = lanes_[v.lane];
  const double x = std::clamp(t / kTrafficStep, 0.0, static_cast<double>(v.s.size() - 2));
  const auto k = static_cast<std::size_t>(x);
  const double f = x - static_cast<double>(k);
  const double s = (1.0 - f) * static_cast<double>(v.s[k]) + f * static_cast<double>(v.s[k + 1]);
  if (s < 3.0 || s > static_cast<double>(lane.points.size()) - 4.0) {
    return false;
  }
  position = lane_point(lane, s);
  heading = (lane_point(lane, s + 2.0) - lane_point(lane, s - 2.0)).normalized();
  speed = (static_cast<double>(v.s[k + 1]) - static_cast<double>(v.s[k])) / kTrafficStep;
  return true;
}

void Traffic::near(double t0, double t1, const Eigen::Vector2d& p, double radius,
                   std::vector<std::uint32_t>& ids) const {
  ids.clear();
  for (std::size_t i = 0; i < vehicles_.size(); ++i) {
    Eigen::Vector2d c;
    Eigen::Vector2d h;
    double v = 0.0;
    if ((place(i, t0, c, h, v) && (c - p).norm() < radius) || (place(i, t1, c, h, v) && (c - p).norm() < radius)) {
      ids.push_back(static_cast<std::uint32_t>(i));
    }
  }
}

void Traffic::boxes(std::size_t i, double t, std::vector<MovingBox>& out) const {
  Eigen::Vector2d c;
  Eigen::Vector2d h;
  double speed = 0.0;
  if (!place(i, t, c, h, speed)) {
    return;
  }
  const TrafficVehicle& v = vehicles_[i];
  std::vector<Box> parts;
  vehicle_boxes(terrain_, c, std::atan2(h.y(), h.x()), v.half_length, v.half_width, v.top, v.paint, parts);
  for (const Box& b : parts) {
    out.push_back(MovingBox{b, Eigen::Vector3d(h.x() * speed, h.y() * speed, 0.0)});
  }
}

void Traffic::boxes_toward(const std::vector<std::uint32_t>& ids, double t, const Eigen::Vector2d& origin,
                           const Eigen::Vector2d& dir, std::vector<MovingBox>& out) const {
  out.clear();
  // The 32 beams of a firing leave within 5.3 deg of its azimuth (the Helios' horizontal offsets).
  const double spread = std::tan(6.5 * 3.14159265358979 / 180.0);
  for (std::uint32_t i : ids) {
    Eigen::Vector2d c;
    Eigen::Vector2d h;
    double speed = 0.0;
    if (!place(i, t, c, h, speed)) {
      continue;
    }
    const Eigen::Vector2d rel = c - origin;
    const double along = rel.dot(dir);
    const double r = std::hypot(vehicles_[i].half_length, vehicles_[i].half_width) + 0.5;
    if (along < -r || std::abs(rel.x() * dir.y() - rel.y() * dir.x()) > r + std::max(along, 0.0) * spread) {
      continue;
    }
    boxes(i, t, out);
  }
}

bool intersect_moving(const std::vector<MovingBox>& boxes, double dt, const Eigen::Vector3d& o,
                      const Eigen::Vector3d& d, double best, Rng& rng, RayHit& hit) {
  bool found = false;
  for (const MovingBox& m : boxes) {
    // Moving the box on by v dt is moving the ray back by it.
    RayHit h;
    if (intersect_box(m.box, o - m.velocity * dt, d, best, rng, h)) {
      best = h.range;
      hit = h;
      found = true;
    }
  }
  return found;
}

}  // namespace liod::sim
