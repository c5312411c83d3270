#pragma once
// The simulated world: a ground surface sampled on a grid plus simple analytic solids, indexed by
// a 2D uniform grid so a ray only meets what lies under its footprint.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "liod/sim/rng.hpp"
#include "liod/sim/terrain.hpp"

namespace liod::sim {

enum class SurfaceKind : std::uint8_t {
  Diffuse,
  Retroreflective,  // traffic signs, plates: very bright, detected far
  Glass,            // specular: returns only near normal incidence
  Porous,           // foliage, hedges: the beam stops somewhere inside the volume
};

struct Appearance {
  float reflectivity = 0.3F;  // diffuse NIR reflectivity 0..1
  SurfaceKind kind = SurfaceKind::Diffuse;
  float extinction = 0.0F;    // 1/m, Porous only: mean free path = 1 / extinction
};

/// Oriented box; `rotation` maps box-local to world coordinates.
struct Box {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d half = Eigen::Vector3d::Ones();
  Appearance look;
  /// Façade windows on the vertical faces (glass), 0 = none.
  float window_spacing = 0.0F;
  float floor_height = 3.2F;
};

/// Vertical capped cylinder (poles, trunks, posts).
struct Cylinder {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double radius = 0.1;
  double z0 = 0.0;
  double z1 = 1.0;
  Appearance look;
};

/// Axis-aligned ellipsoid, always porous (tree crowns, bushes).
struct Ellipsoid {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d radii = Eigen::Vector3d::Ones();
  Appearance look{0.45F, SurfaceKind::Porous, 1.0F};
};

enum class GroundType : std::uint8_t { Soil = 0, Grass, Asphalt, Concrete, Gravel };

struct RayHit {
  double range = 0.0;           // along the unit direction
  double cos_incidence = 1.0;   // |n . d|
  float reflectivity = 0.0F;
  SurfaceKind kind = SurfaceKind::Diffuse;
};

class World;

/// Per-thread scratch for ray casting: the mailbox that tests each primitive once per ray, the
/// random stream for porous media, and the time of the ray (where swaying foliage is).
class RayContext {
 public:
  RayContext(const World& world, std::uint64_t seed);
  Rng& rng() { return rng_; }
  /// The draws of the drive's added conditions (rain, random dropouts): a stream of its own, so
  /// that switching them on leaves every other draw of the revolution as it was.
  Rng& aux() { return aux_; }
  /// IMU-clock time of the ray about to be cast.
  void set_time(double t) { time_ = t; }
  double time() const { return time_; }

 private:
  friend class World;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t ray_id_ = 0;
  Rng rng_;
  Rng aux_;
  double time_ = 0.0;
  // Wind: each porous primitive's displacement, recomputed when the time moves on.
  std::vector<double> sway_time_;
  std::vector<Eigen::Vector2d> sway_;
};

/// Ray against one box within (0, best): a porous box stops the beam at an exponentially
/// distributed depth drawn from `rng`; façade windows are glass.
bool intersect_box(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double best,
                   Rng& rng, RayHit& hit);

/// How porous vegetation moves in the wind (liod-sim --wind): every crown, bush and hedge leans
/// with the gusts in the wind's direction and sways about that lean in a few random modes.
struct SwayMode {
  float frequency = 0.0F;  // Hz
  float phase_x = 0.0F;
  float phase_y = 0.0F;
};
struct Sway {
  float amplitude = 0.0F;  // m, 0 = does not move
  std::array<SwayMode, 3> modes{};
};

class World {
 public:
  Terrain terrain;
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::vector<Ellipsoid> ellipsoids;

  /// Sets the indexed area and cell size; ground outside it does not exist.
  void allocate(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double cell_size);
  /// Paints the ground type of all cells whose centre lies within `half_width` of segment a-b
  /// (a capsule with `round_ends`, else the rectangle along the segment).
  void paint_ground(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half_width,
                    GroundType type, bool round_ends = true);
  GroundType ground_type_at(double x, double y) const;
  /// Samples the terrain on the grid and builds the primitive index. Call after adding primitives.
  void finalize(std::uint64_t seed);
  /// finalize() again with the same seed, after primitives were added, removed or set swaying.
  void rebuild() { finalize(seed_); }
  /// Sets porous vegetation swaying in the wind (drawn from `seed`); takes effect at rebuild().
  void enable_wind(std::uint64_t seed);
  bool windy() const { return !sway_.empty(); }
  /// Horizontal displacement at time t of primitive `id` (boxes, cylinders, ellipsoids in turn).
  Eigen::Vector2d sway(std::uint32_t id, double t) const;

  /// Nearest surface along the ray within [0, max_range]; false when nothing is hit.
  bool cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range,
            RayContext& ctx, RayHit& hit) const;
  /// Distance from p to the nearest simulated surface (0 inside porous volumes), capped at ~2 cells.
  double distance_to_world(const Eigen::Vector3d& p) const;
  /// The ground height as the LiDAR sees it (bilinear between grid samples).
  double ground_height(double x, double y) const;
  bool contains(double x, double y) const;

  std::size_t primitive_count() const { return boxes.size() + cylinders.size() + ellipsoids.size(); }
  Eigen::Vector2d min_corner() const { return min_; }
  Eigen::Vector2d max_corner() const { return max_; }
  double cell_size() const { return cell_; }

 private:
  bool hit_box(std::size_t i, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double best,
               RayContext& ctx, RayHit& hit) const;
  bool hit_cylinder(std::size_t i, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double best,
                    RayHit& hit) const;
  bool hit_ellipsoid(std::size_t i, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double best, RayContext& ctx, RayHit& hit) const;
  bool hit_ground_cell(int ix, int iy, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                       double t0, double t1, RayHit& hit) const;
  double vertex_height(int ix, int iy) const {
    return heights_[static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx_ + 1) +
                    static_cast<std::size_t>(ix)];
  }
  std::size_t cell_index(int ix, int iy) const {
    return static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(ix);
  }
  void index_primitive(std::uint32_t id, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                       double top, std::vector<std::vector<std::uint32_t>>& lists);

  Eigen::Vector2d min_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d max_ = Eigen::Vector2d::Zero();
  double cell_ = 2.0;
  int nx_ = 0;
  int ny_ = 0;
  std::vector<float> heights_;          // (nx+1) x (ny+1) vertices
  std::vector<float> cell_top_;         // highest point of anything in the cell
  std::vector<float> ground_reflect_;   // per cell, material plus patchiness
  std::vector<GroundType> ground_type_;
  std::vector<std::uint32_t> cell_start_;
  std::vector<std::uint32_t> cell_items_;
  double max_z_ = 0.0;
  std::uint64_t seed_ = 0;
  std::uint64_t wind_seed_ = 0;
  bool wind_ = false;
  std::vector<Sway> sway_;              // per primitive id when windy, else empty
  Eigen::Vector2d wind_dir_ = Eigen::Vector2d::UnitX();
  double gust_frequency_ = 0.0;
  double gust_phase_ = 0.0;
  const Eigen::Vector2d& sway_at(std::uint32_t id, RayContext& ctx) const;
  void build_sway();
  // The farthest a primitive sways, in units of its amplitude: a full lean plus three modes.
  static constexpr double kSwayReach = 2.8;
};

}  // namespace liod::sim
