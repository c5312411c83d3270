// Ray casting: a 2D DDA over the grid, exact ray/bilinear-patch ground intersection per cell and
// analytic ray/primitive tests, stopping at the first cell that cannot hide anything nearer.

#include <algorithm>
#include <cmath>
#include <limits>

#include "liod/sim/world.hpp"

namespace liod::sim {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// Leaves and twigs face every way: the incidence seen by the beam is random.
double random_foliage_cos(Rng& rng) { return rng.uniform(0.15, 1.0); }

bool in_window(const Box& b, const Eigen::Vector3d& local, int axis) {
  if (b.window_spacing <= 0.0F || axis == 2) {
    return false;
  }
  const int along = axis == 0 ? 1 : 0;
  const double u = local[along] + b.half[along];
  const double v = local.z() + b.half.z();
  const double sp = b.window_spacing;
  const double fh = b.floor_height;
  const double fu = u / sp - std::floor(u / sp);
  const double fv = v / fh - std::floor(v / fh);
  // The lowest storey and a margin at the building's edges are solid wall.
  if (v < fh * 1.2 || u < 0.6 || u > 2.0 * b.half[along] - 0.6) {
    return false;
  }
  return fu > 0.2 && fu < 0.8 && fv > 0.3 && fv < 0.85;
}
}  // namespace

bool World::hit_box(std::size_t i, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double best,
                    RayContext& ctx, RayHit& hit) const {
  if (wind_ && boxes[i].look.kind == SurfaceKind::Porous) {
    Box moved = boxes[i];
    moved.center.head<2>() += sway_at(static_cast<std::uint32_t>(i), ctx);
    return intersect_box(moved, o, d, best, ctx.rng(), hit);
  }
  return intersect_box(boxes[i], o, d, best, ctx.rng(), hit);
}

bool intersect_box(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double best,
                   Rng& rng, RayHit& hit) {
  const Eigen::Vector3d ol = b.rotation.transpose() * (o - b.center);
  const Eigen::Vector3d dl = b.rotation.transpose() * d;
  double tnear = -kInf;
  double tfar = kInf;
  int axis = 0;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(dl[k]) < 1e-12) {
      if (std::abs(ol[k]) > b.half[k]) {
        return false;
      }
      continue;
    }
    const double inv = 1.0 / dl[k];
    double t1 = (-b.half[k] - ol[k]) * inv;
    double t2 = (b.half[k] - ol[k]) * inv;
    if (t1 > t2) {
      std::swap(t1, t2);
    }
    if (t1 > tnear) {
      tnear = t1;
      axis = k;
    }
    tfar = std::min(tfar, t2);
  }
  if (tnear > tfar || tfar <= 0.0 || tnear >= best) {
    return false;
  }
  if (b.look.kind == SurfaceKind::Porous) {
    const double t = std::max(tnear, 0.0) + rng.exponential(1.0 / static_cast<double>(b.look.extinction));
    if (t >= tfar || t >= best) {
      return false;
    }
    hit.range = t;
    hit.cos_incidence = random_foliage_cos(rng);
    hit.reflectivity = b.look.reflectivity;
    hit.kind = SurfaceKind::Porous;
    return true;
  }
  if (tnear <= 0.0) {
    return false;  // origin inside a solid: cannot happen for a sensor outside all solids
  }
  hit.range = tnear;
  hit.cos_incidence = std::abs(dl[axis]);
  const Eigen::Vector3d local = ol + tnear * dl;
  if (in_window(b, local, axis)) {
    hit.kind = SurfaceKind::Glass;
    hit.reflectivity = 0.04F;
  } else {
    hit.kind = b.look.kind;
    hit.reflectivity = b.look.reflectivity;
  }
  return true;
}

bool World::hit_cylinder(std::size_t i, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                         double best, RayHit& hit) const {
  const Cylinder& c = cylinders[i];
  const double ox = o.x() - c.center.x();
  const double oy = o.y() - c.center.y();
  const double a = d.x() * d.x() + d.y() * d.y();
  double t_side = kInf;
  if (a > 1e-12) {
    const double bh = ox * d.x() + oy * d.y();
    const double cc = ox * ox + oy * oy - c.radius * c.radius;
    const double disc = bh * bh - a * cc;
    if (disc >= 0.0) {
      const double t = (-bh - std::sqrt(disc)) / a;
      const double z = o.z() + t * d.z();
      if (t > 0.0 && z >= c.z0 && z <= c.z1) {
        t_side = t;
      }
    }
  }
  double t_cap = kInf;
  if (d.z() < -1e-12) {
    const double t = (c.z1 - o.z()) / d.z();
    const double x = ox + t * d.x();
    const double y = oy + t * d.y();
    if (t > 0.0 && x * x + y * y <= c.radius * c.radius) {
      t_cap = t;
    }
  }
  const double t = std::min(t_side, t_cap);
  if (t >= best) {
    return false;
  }
  hit.range = t;
  if (t == t_side) {
    const double nx = (ox + t * d.x()) / c.radius;
    const double ny = (oy + t * d.y()) / c.radius;
    hit.cos_incidence = std::abs(nx * d.x() + ny * d.y());
  } else {
    hit.cos_incidence = std::abs(d.z());
  }
  hit.reflectivity = c.look.reflectivity;
  hit.kind = c.look.kind;
  return true;
}

bool World::hit_ellipsoid(std::size_t i, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                          double best, RayContext& ctx, RayHit& hit) const {
  const Ellipsoid& e = ellipsoids[i];
  Eigen::Vector3d center = e.center;
  if (wind_) {
    center.head<2>() += sway_at(static_cast<std::uint32_t>(boxes.size() + cylinders.size() + i), ctx);
  }
  const Eigen::Vector3d q = (o - center).cwiseQuotient(e.radii);
  const Eigen::Vector3d s = d.cwiseQuotient(e.radii);
  const double a = s.squaredNorm();
  const double bh = q.dot(s);
  const double cc = q.squaredNorm() - 1.0;
  const double disc = bh * bh - a * cc;
  if (disc < 0.0) {
    return false;
  }
  const double root = std::sqrt(disc);
  const double t0 = (-bh - root) / a;
  const double t1 = (-bh + root) / a;
  if (t1 <= 0.0 || t0 >= best) {
    return false;
  }
  const double t = std::max(t0, 0.0) + ctx.rng().exponential(1.0 / static_cast<double>(e.look.extinction));
  if (t >= t1 || t >= best) {
    return false;
  }
  hit.range = t;
  hit.cos_incidence = random_foliage_cos(ctx.rng());
  hit.reflectivity = e.look.reflectivity;
  hit.kind = SurfaceKind::Porous;
  return true;
}

bool World::hit_ground_cell(int ix, int iy, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                            double t0, double t1, RayHit& hit) const {
  const double h00 = vertex_height(ix, iy);
  const double h10 = vertex_height(ix + 1, iy);
  const double h01 = vertex_height(ix, iy + 1);
  const double h11 = vertex_height(ix + 1, iy + 1);
  const double zmin_ray = o.z() + d.z() * (d.z() > 0.0 ? t0 : t1);
  if (zmin_ray > std::max({h00, h10, h01, h11})) {
    return false;
  }
  // Along the ray, height above the bilinear patch is a quadratic in the ray parameter.
  const double cx = min_.x() + cell_ * ix;
  const double cy = min_.y() + cell_ * iy;
  const double u0 = (o.x() + d.x() * t0 - cx) / cell_;
  const double v0 = (o.y() + d.y() * t0 - cy) / cell_;
  const double z0 = o.z() + d.z() * t0;
  const double au = d.x() / cell_;
  const double av = d.y() / cell_;
  const double B = h10 - h00;
  const double C = h01 - h00;
  const double D = h00 - h10 - h01 + h11;
  const double f0 = z0 - (h00 + B * u0 + C * v0 + D * u0 * v0);
  const double f1 = d.z() - (B * au + C * av + D * (u0 * av + v0 * au));
  const double f2 = -D * au * av;
  const double len = t1 - t0;
  double tau = kInf;
  if (f0 <= 0.0) {
    tau = 0.0;  // grazing re-entry at a cell border after rounding
  } else if (std::abs(f2) < 1e-14) {
    if (f1 < 0.0) {
      tau = -f0 / f1;
    }
  } else {
    const double disc = f1 * f1 - 4.0 * f2 * f0;
    if (disc >= 0.0) {
      const double sq = std::sqrt(disc);
      const double q = -0.5 * (f1 + (f1 >= 0.0 ? sq : -sq));
      double r1 = q / f2;
      double r2 = q != 0.0 ? f0 / q : kInf;
      if (r1 > r2) {
        std::swap(r1, r2);
      }
      tau = r1 >= 0.0 ? r1 : (r2 >= 0.0 ? r2 : kInf);
    }
  }
  if (!(tau <= len)) {
    return false;
  }
  const double u = u0 + au * tau;
  const double v = v0 + av * tau;
  const double dhdx = (B + D * v) / cell_;
  const double dhdy = (C + D * u) / cell_;
  const Eigen::Vector3d n = Eigen::Vector3d(-dhdx, -dhdy, 1.0).normalized();
  hit.range = t0 + tau;
  hit.cos_incidence = std::abs(n.dot(d));
  hit.reflectivity = ground_reflect_[cell_index(ix, iy)];
  hit.kind = SurfaceKind::Diffuse;
  return true;
}

bool World::cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range,
                 RayContext& ctx, RayHit& hit) const {
  double fx = (origin.x() - min_.x()) / cell_;
  double fy = (origin.y() - min_.y()) / cell_;
  if (fx < 0.0 || fy < 0.0 || fx >= nx_ || fy >= ny_) {
    return false;
  }
  int ix = static_cast<int>(fx);
  int iy = static_cast<int>(fy);
  const int sx = dir.x() > 0.0 ? 1 : -1;
  const int sy = dir.y() > 0.0 ? 1 : -1;
  const double tdx = std::abs(dir.x()) > 1e-15 ? cell_ / std::abs(dir.x()) : kInf;
  const double tdy = std::abs(dir.y()) > 1e-15 ? cell_ / std::abs(dir.y()) : kInf;
  double tmx = std::abs(dir.x()) > 1e-15
                   ? ((dir.x() > 0.0 ? (ix + 1) - fx : fx - ix) * cell_) / std::abs(dir.x())
                   : kInf;
  double tmy = std::abs(dir.y()) > 1e-15
                   ? ((dir.y() > 0.0 ? (iy + 1) - fy : fy - iy) * cell_) / std::abs(dir.y())
                   : kInf;

  if (++ctx.ray_id_ == 0U) {
    std::fill(ctx.stamp_.begin(), ctx.stamp_.end(), 0U);
    ctx.ray_id_ = 1U;
  }
  const auto nb = static_cast<std::uint32_t>(boxes.size());
  const auto nc = static_cast<std::uint32_t>(cylinders.size());
  double best = max_range;
  bool found = false;
  double t_enter = 0.0;
  while (true) {
    const double t_exit = std::min({tmx, tmy, max_range});
    const double zlow = origin.z() + dir.z() * (dir.z() > 0.0 ? t_enter : t_exit);
    if (dir.z() > 0.0 && zlow > max_z_) {
      break;
    }
    const std::size_t c = cell_index(ix, iy);
    RayHit h;
    if (hit_ground_cell(ix, iy, origin, dir, t_enter, t_exit, h) && h.range < best) {
      best = h.range;
      hit = h;
      found = true;
    }
    if (zlow <= static_cast<double>(cell_top_[c])) {
      for (std::uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const std::uint32_t id = cell_items_[k];
        if (ctx.stamp_[id] == ctx.ray_id_) {
          continue;
        }
        ctx.stamp_[id] = ctx.ray_id_;
        bool ok = false;
        if (id < nb) {
          ok = hit_box(id, origin, dir, best, ctx, h);
        } else if (id < nb + nc) {
          ok = hit_cylinder(id - nb, origin, dir, best, h);
        } else {
          ok = hit_ellipsoid(id - nb - nc, origin, dir, best, ctx, h);
        }
        if (ok && h.range < best) {
          best = h.range;
          hit = h;
          found = true;
        }
      }
    }
    if (best <= t_exit || t_exit >= max_range) {
      break;
    }
    if (tmx < tmy) {
      ix += sx;
      tmx += tdx;
    } else {
      iy += sy;
      tmy += tdy;
    }
    if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) {
      break;
    }
    t_enter = t_exit;
  }
  return found;
}

}  // namespace liod::sim
