#include "liod/sim/scene_builder.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "liod/sim/trajectory.hpp"

namespace liod::sim {

namespace {
Eigen::Matrix3d yaw_rotation(double yaw) { return rotation_from_euler(0.0, 0.0, yaw); }

Appearance diffuse(double r) { return Appearance{static_cast<float>(r), SurfaceKind::Diffuse, 0.0F}; }
}  // namespace

double facade_reflectivity(Rng& rng) {
  // Plaster and concrete are bright, brick and dark cladding are not.
  const double u = rng.uniform();
  if (u < 0.15) {
    return rng.uniform(0.06, 0.12);
  }
  if (u < 0.45) {
    return rng.uniform(0.15, 0.3);
  }
  return rng.uniform(0.3, 0.7);
}

void SceneBuilder::allocate(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double cell) {
  world_.allocate(min, max, cell);
  min_ = min;
  nx_ = static_cast<int>(std::ceil(max.x() - min.x()));
  ny_ = static_cast<int>(std::ceil(max.y() - min.y()));
  occ_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_), 0);
}

void SceneBuilder::paint(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half_width,
                         GroundType t) {
  world_.paint_ground(a, b, half_width, t, false);
}

void SceneBuilder::add_road(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half_width,
                            GroundType type) {
  world_.paint_ground(a, b, half_width, type);
  const Eigen::Vector2d ab = b - a;
  const double len = ab.norm();
  reserve(0.5 * (a + b), std::atan2(ab.y(), ab.x()), 0.5 * len + half_width, half_width);
}

bool SceneBuilder::is_free(const Eigen::Vector2d& center, double yaw, double half_len,
                           double half_wid, double margin) const {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  const double hl = half_len + margin;
  const double hw = half_wid + margin;
  for (double u = -hl; u <= hl + 1e-9; u += std::min(0.5, hl)) {
    for (double v = -hw; v <= hw + 1e-9; v += std::min(0.5, hw)) {
      const Eigen::Vector2d p = center + u * ax + v * ay - min_;
      const int ix = static_cast<int>(std::floor(p.x()));
      const int iy = static_cast<int>(std::floor(p.y()));
      if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) {
        return false;
      }
      if (occ_[static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx_) +
               static_cast<std::size_t>(ix)] != 0) {
        return false;
      }
    }
  }
  return true;
}

void SceneBuilder::reserve(const Eigen::Vector2d& center, double yaw, double half_len,
                           double half_wid) {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  for (double u = -half_len; u <= half_len + 1e-9; u += 0.4) {
    for (double v = -half_wid; v <= half_wid + 1e-9; v += 0.4) {
      const Eigen::Vector2d p = center + u * ax + v * ay - min_;
      const int ix = static_cast<int>(std::floor(p.x()));
      const int iy = static_cast<int>(std::floor(p.y()));
      if (ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_) {
        occ_[static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx_) +
             static_cast<std::size_t>(ix)] = 2;
      }
    }
  }
}

double SceneBuilder::terrain_min(const Eigen::Vector2d& c, double yaw, double hl, double hw) const {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  double m = 1e9;
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) {
      const Eigen::Vector2d p = c + ax * (hl * i / 2.0) + ay * (hw * j / 2.0);
      m = std::min(m, world_.terrain.height(p.x(), p.y()));
    }
  }
  return m;
}

double SceneBuilder::terrain_max(const Eigen::Vector2d& c, double yaw, double hl, double hw) const {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  double m = -1e9;
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) {
      const Eigen::Vector2d p = c + ax * (hl * i / 2.0) + ay * (hw * j / 2.0);
      m = std::max(m, world_.terrain.height(p.x(), p.y()));
    }
  }
  return m;
}

bool SceneBuilder::add_building(const Eigen::Vector2d& front_mid, const Eigen::Vector2d& front_dir,
                                double width, double depth, double height, BuildingStyle style) {
  const double yaw = std::atan2(front_dir.y(), front_dir.x());
  const Eigen::Vector2d center = front_mid - front_dir * (depth / 2.0);
  if (!is_free(center, yaw, depth / 2.0, width / 2.0, 0.3)) {
    return false;
  }
  reserve(center, yaw, depth / 2.0, width / 2.0);
  const double z0 = terrain_min(center, yaw, depth / 2.0, width / 2.0) - 1.0;
  const double base = terrain_max(center, yaw, depth / 2.0, width / 2.0);
  const Eigen::Matrix3d R = yaw_rotation(yaw);
  const Eigen::Vector2d along(-front_dir.y(), front_dir.x());
  Box main;
  main.rotation = R;
  main.look = diffuse(facade_reflectivity(rng_));
  switch (style) {
    case BuildingStyle::Tower:
    case BuildingStyle::Block:
      main.window_spacing = static_cast<float>(rng_.uniform(2.4, 4.0));
      main.floor_height = static_cast<float>(rng_.uniform(3.0, 3.8));
      break;
    case BuildingStyle::House:
      main.window_spacing = static_cast<float>(rng_.uniform(2.8, 4.5));
      main.floor_height = 2.9F;
      break;
    case BuildingStyle::Warehouse:
      main.look = diffuse(rng_.uniform(0.35, 0.6));
      break;
  }
  const double top = base + height;
  // Upper storeys set back from a wider podium (towers), or a shop front that juts out (blocks).
  double body_depth = depth;
  double body_front_shift = 0.0;
  if (style == BuildingStyle::Tower && height > 18.0 && rng_.bernoulli(0.5)) {
    const double podium_h = rng_.uniform(4.0, 8.0);
    Box podium = main;
    podium.center << center.x(), center.y(), 0.5 * (z0 + base + podium_h);
    podium.half << depth / 2.0, width / 2.0, 0.5 * (base + podium_h - z0);
    world_.boxes.push_back(podium);
    body_front_shift = rng_.uniform(2.0, 5.0);
    body_depth = std::max(6.0, depth - body_front_shift);
  }
  const Eigen::Vector2d body_c = front_mid - front_dir * (body_front_shift + body_depth / 2.0);
  main.center << body_c.x(), body_c.y(), 0.5 * (z0 + top);
  main.half << body_depth / 2.0, width / 2.0, 0.5 * (top - z0);
  world_.boxes.push_back(main);

  if (style == BuildingStyle::Block && rng_.bernoulli(0.35)) {
    const double shop_h = rng_.uniform(3.5, 5.0);
    const double jut = rng_.uniform(1.0, 2.5);
    const double w = width * rng_.uniform(0.5, 0.95);
    Box shop;
    shop.rotation = R;
    shop.look = diffuse(facade_reflectivity(rng_));
    const Eigen::Vector2d c = front_mid + front_dir * (jut / 2.0 - 0.05);
    shop.center << c.x(), c.y(), 0.5 * (z0 + base + shop_h);
    shop.half << jut / 2.0, w / 2.0, 0.5 * (base + shop_h - z0);
    if (is_free(c, yaw, jut / 2.0, w / 2.0, 0.5)) {
      world_.boxes.push_back(shop);
      reserve(c, yaw, jut / 2.0, w / 2.0);
    }
  } else if ((style == BuildingStyle::Block || style == BuildingStyle::Tower) &&
             rng_.bernoulli(0.4) && height > 9.0) {
    // Balconies: slabs on every storey over a few bays of the front façade.
    const double fh = main.floor_height;
    const double bw = rng_.uniform(2.5, 4.0);
    const int bays = std::max(1, static_cast<int>(width / (bw + 2.0)) - 1);
    const double jut = rng_.uniform(1.0, 1.6);
    for (int b = 0; b < bays; ++b) {
      const double off = -width / 2.0 + (b + 0.5) * width / bays;
      for (double z = base + 1.5 * fh; z + 1.0 < top; z += fh) {
        Box slab;
        slab.rotation = R;
        slab.look = diffuse(rng_.uniform(0.2, 0.5));
        const Eigen::Vector2d c = front_mid + front_dir * (jut / 2.0) + along * off;
        slab.center << c.x(), c.y(), z;
        slab.half << jut / 2.0, bw / 2.0, 0.12;
        world_.boxes.push_back(slab);
        Box rail = slab;
        const Eigen::Vector2d rc = front_mid + front_dir * (jut - 0.03) + along * off;
        rail.center << rc.x(), rc.y(), z + 0.55;
        rail.half << 0.03, bw / 2.0, 0.45;
        world_.boxes.push_back(rail);
      }
    }
  }
  if (style == BuildingStyle::House && rng_.bernoulli(0.6)) {
    Box chimney;
    chimney.rotation = R;
    chimney.look = diffuse(rng_.uniform(0.1, 0.3));
    const Eigen::Vector2d c = center + along * rng_.uniform(-width / 3, width / 3);
    chimney.center << c.x(), c.y(), top + 0.6;
    chimney.half << 0.35, 0.35, 0.6;
    world_.boxes.push_back(chimney);
  }
  return true;
}

bool SceneBuilder::add_tree(const Eigen::Vector2d& p, double scale) {
  if (!is_free(p, 0.0, 0.4, 0.4)) {
    return false;
  }
  reserve(p, 0.0, 0.4, 0.4);
  const double g = world_.terrain.height(p.x(), p.y());
  Cylinder trunk;
  trunk.center = p;
  trunk.radius = rng_.uniform(0.12, 0.3) * scale;
  trunk.z0 = g - 0.5;
  const double trunk_h = rng_.uniform(1.8, 3.5) * scale;
  trunk.z1 = g + trunk_h;
  trunk.look = diffuse(rng_.uniform(0.15, 0.3));
  world_.cylinders.push_back(trunk);
  Ellipsoid crown;
  const double rh = rng_.uniform(1.5, 3.5) * scale;
  const double rv = rng_.uniform(1.5, 3.0) * scale;
  crown.center << p.x() + rng_.uniform(-0.3, 0.3), p.y() + rng_.uniform(-0.3, 0.3),
      g + trunk_h + 0.7 * rv;
  crown.radii << rh * rng_.uniform(0.85, 1.15), rh * rng_.uniform(0.85, 1.15), rv;
  crown.look = Appearance{static_cast<float>(rng_.uniform(0.35, 0.6)), SurfaceKind::Porous,
                          static_cast<float>(rng_.uniform(0.5, 1.6))};
  world_.ellipsoids.push_back(crown);
  return true;
}

bool SceneBuilder::add_bush(const Eigen::Vector2d& p) {
  if (!is_free(p, 0.0, 0.6, 0.6)) {
    return false;
  }
  reserve(p, 0.0, 0.6, 0.6);
  Ellipsoid e;
  const double g = world_.terrain.height(p.x(), p.y());
  e.radii << rng_.uniform(0.7, 1.6), rng_.uniform(0.7, 1.6), rng_.uniform(0.5, 1.1);
  e.center << p.x(), p.y(), g + 0.6 * e.radii.z();
  e.look = Appearance{static_cast<float>(rng_.uniform(0.35, 0.55)), SurfaceKind::Porous,
                      static_cast<float>(rng_.uniform(1.0, 2.5))};
  world_.ellipsoids.push_back(e);
  return true;
}

bool SceneBuilder::add_pole(const Eigen::Vector2d& p, double height, double radius, bool lamp,
                            double lamp_yaw) {
  if (!is_free(p, 0.0, 0.3, 0.3)) {
    return false;
  }
  reserve(p, 0.0, 0.3, 0.3);
  const double g = world_.terrain.height(p.x(), p.y());
  Cylinder c;
  c.center = p;
  c.radius = radius;
  c.z0 = g - 0.5;
  c.z1 = g + height;
  c.look = diffuse(rng_.uniform(0.2, 0.5));
  world_.cylinders.push_back(c);
  if (lamp) {
    Box arm;
    arm.rotation = yaw_rotation(lamp_yaw);
    const Eigen::Vector2d d(std::cos(lamp_yaw), std::sin(lamp_yaw));
    const Eigen::Vector2d ac = p + d * 0.9;
    arm.center << ac.x(), ac.y(), g + height - 0.15;
    arm.half << 0.9, 0.12, 0.1;
    arm.look = diffuse(0.4);
    world_.boxes.push_back(arm);
  }
  return true;
}

void vehicle_boxes(const Terrain& terrain, const Eigen::Vector2d& p, double yaw, double half_len,
                   double half_wid, double top, const Appearance& paint, std::vector<Box>& out) {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw));
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  auto h = [&](const Eigen::Vector2d& q) { return terrain.height(q.x(), q.y()); };
  const double pitch = -std::atan2(h(p + ax * half_len) - h(p - ax * half_len), 2 * half_len);
  const double roll = std::atan2(h(p + ay * half_wid) - h(p - ay * half_wid), 2 * half_wid);
  const Eigen::Matrix3d R = rotation_from_euler(roll, pitch, yaw);
  const double g = h(p);
  Box body;
  body.rotation = R;
  body.look = paint;
  if (top > 0.0) {
    body.center << p.x(), p.y(), g + 0.5 * (0.45 + top);
    body.half << half_len, half_wid, 0.5 * (top - 0.45);
    out.push_back(body);
    return;
  }
  body.center << p.x(), p.y(), g + 0.65;
  body.half << half_len, half_wid, 0.35;
  out.push_back(body);
  Box cabin;
  cabin.rotation = R;
  cabin.look = Appearance{0.05F, SurfaceKind::Glass, 0.0F};
  const Eigen::Vector2d cc = p - ax * 0.25;
  cabin.center << cc.x(), cc.y(), g + 1.0 + 0.24;
  cabin.half << half_len * 0.55, half_wid * 0.9, 0.24;
  out.push_back(cabin);
}

Appearance vehicle_paint(Rng& rng) {
  // Black and dark grey cars return little, white ones a lot.
  const double paints[] = {0.04, 0.07, 0.12, 0.25, 0.45, 0.65};
  return diffuse(paints[rng.uniform_int(0, 5)]);
}

bool SceneBuilder::add_car(const Eigen::Vector2d& p, double yaw, bool large, bool on_road) {
  const double hl = large ? rng_.uniform(3.0, 4.5) : rng_.uniform(2.0, 2.45);
  const double hw = large ? 1.2 : rng_.uniform(0.85, 0.95);
  if (!on_road && !is_free(p, yaw, hl, hw, 0.2)) {
    return false;
  }
  reserve(p, yaw, hl, hw);
  const Appearance paint = vehicle_paint(rng_);
  const double top = large ? rng_.uniform(2.4, 3.4) : 0.0;
  vehicle_boxes(world_.terrain, p, yaw, hl, hw, top, paint, world_.boxes);
  return true;
}

bool SceneBuilder::add_sign(const Eigen::Vector2d& p, double facing_yaw) {
  if (!add_pole(p, rng_.uniform(2.2, 2.8), 0.04, false)) {
    return false;
  }
  Box panel;
  panel.rotation = yaw_rotation(facing_yaw);
  const Eigen::Vector2d d(std::cos(facing_yaw), std::sin(facing_yaw));
  const Eigen::Vector2d c = p + d * 0.06;
  const double s = rng_.uniform(0.3, 0.45);
  panel.center << c.x(), c.y(), world_.cylinders.back().z1 + s - 0.1;
  panel.half << 0.02, s, s;
  panel.look = Appearance{0.9F, SurfaceKind::Retroreflective, 0.0F};
  world_.boxes.push_back(panel);
  return true;
}

void SceneBuilder::add_strip(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double thickness,
                             double z_bottom, double z_top, Appearance look) {
  const Eigen::Vector2d ab = b - a;
  const double len = ab.norm();
  if (len < 1e-6) {
    return;
  }
  const double yaw = std::atan2(ab.y(), ab.x());
  const double ha = world_.terrain.height(a.x(), a.y());
  const double hb = world_.terrain.height(b.x(), b.y());
  const double pitch = -std::atan2(hb - ha, len);
  Box box;
  box.rotation = rotation_from_euler(0.0, pitch, yaw);
  const Eigen::Vector2d m = 0.5 * (a + b);
  box.center << m.x(), m.y(), 0.5 * (ha + hb) + 0.5 * (z_bottom + z_top);
  box.half << 0.5 * std::hypot(len, hb - ha), thickness / 2.0, 0.5 * (z_top - z_bottom);
  box.look = look;
  world_.boxes.push_back(box);
}

void SceneBuilder::add_block(const Eigen::Vector2d& center, double yaw, double half_len,
                             double half_wid, double z_bottom, double height, Appearance look) {
  const double g0 = terrain_min(center, yaw, half_len, half_wid) + z_bottom;
  const double g1 = terrain_max(center, yaw, half_len, half_wid) + height;
  Box b;
  b.rotation = yaw_rotation(yaw);
  b.center << center.x(), center.y(), 0.5 * (g0 + g1);
  b.half << half_len, half_wid, 0.5 * (g1 - g0);
  b.look = look;
  world_.boxes.push_back(b);
  reserve(center, yaw, half_len, half_wid);
}

}  // namespace liod::sim
