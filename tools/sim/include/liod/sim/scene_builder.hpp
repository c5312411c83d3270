#pragma once
// Placing things in the world: a footprint raster that keeps objects off roads and out of each
// other, and the furniture of a street (buildings with façades, trees, poles, parked cars, signs,
// rails), each standing on the terrain.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "liod/sim/rng.hpp"
#include "liod/sim/world.hpp"

namespace liod::sim {

enum class BuildingStyle { Tower, Block, House, Warehouse };

class SceneBuilder {
 public:
  SceneBuilder(World& world, Rng& rng) : world_(world), rng_(rng) {}

  /// Sets up the world grid and the 1 m footprint raster over the same area.
  void allocate(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double cell = 2.0);
  /// A road strip: painted on the ground and kept free of objects.
  void add_road(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half_width,
                GroundType type = GroundType::Asphalt);
  /// Paints a rectangle of ground along a-b without reserving it.
  void paint(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half_width, GroundType t);
  /// Is an oriented rectangle (plus margin) free of roads and objects?
  bool is_free(const Eigen::Vector2d& center, double yaw, double half_len, double half_wid,
               double margin = 0.0) const;
  void reserve(const Eigen::Vector2d& center, double yaw, double half_len, double half_wid);

  /// Building whose front façade faces direction yaw + 90 deg (i.e. `front` points to the street).
  bool add_building(const Eigen::Vector2d& front_mid, const Eigen::Vector2d& front_dir,
                    double width, double depth, double height, BuildingStyle style);
  bool add_tree(const Eigen::Vector2d& p, double scale = 1.0);
  bool add_bush(const Eigen::Vector2d& p);
  bool add_pole(const Eigen::Vector2d& p, double height, double radius = 0.12, bool lamp = true,
                double lamp_yaw = 0.0);
  /// A parked car or van; `on_road` skips the footprint check (parking lanes are part of roads).
  bool add_car(const Eigen::Vector2d& p, double yaw, bool large = false, bool on_road = false);
  bool add_sign(const Eigen::Vector2d& p, double facing_yaw);
  /// A box that follows the terrain along its length (rails, walls, barriers, kerbs).
  void add_strip(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double thickness,
                 double z_bottom, double z_top, Appearance look);
  /// A freestanding box sitting on the terrain with a yaw.
  void add_block(const Eigen::Vector2d& center, double yaw, double half_len, double half_wid,
                 double z_bottom, double height, Appearance look);

  double terrain_min(const Eigen::Vector2d& center, double yaw, double hl, double hw) const;
  double terrain_max(const Eigen::Vector2d& center, double yaw, double hl, double hw) const;
  Rng& rng() { return rng_; }
  World& world() { return world_; }

 private:
  World& world_;
  Rng& rng_;
  Eigen::Vector2d min_ = Eigen::Vector2d::Zero();
  int nx_ = 0;
  int ny_ = 0;
  std::vector<std::uint8_t> occ_;  // 1 m cells: 0 free, 1 road, 2 object
};

double facade_reflectivity(Rng& rng);

/// The boxes of a road vehicle standing on the terrain at p, facing yaw: a car (top = 0) is a
/// painted body with a glass cabin on it, a van or truck one painted box from 0.45 m up to `top`.
void vehicle_boxes(const Terrain& terrain, const Eigen::Vector2d& p, double yaw, double half_len,
                   double half_wid, double top, const Appearance& paint, std::vector<Box>& out);
/// A vehicle's paint, from black to white.
Appearance vehicle_paint(Rng& rng);

}  // namespace liod::sim
