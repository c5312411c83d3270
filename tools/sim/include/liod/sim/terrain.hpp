#pragma once
// The smooth ground shape: rolling terrain with real road grades, hills that make ramps, and
// straight graded corridors (a tunnel floor) that the terrain blends into.

#include <Eigen/Core>
#include <vector>

namespace liod::sim {

struct TerrainWave {
  Eigen::Vector2d wave_vector = Eigen::Vector2d::Zero();  // rad/m
  double phase = 0.0;
  double amplitude = 0.0;  // m
};

struct TerrainHill {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double sigma = 50.0;  // m
  double height = 0.0;  // m, negative for a dip
};

/// Forces a planar, constantly graded strip (e.g. a tunnel floor) along a segment a->b.
struct GradedCorridor {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  double half_width = 10.0;  // fully planar within this lateral distance
  double blend = 40.0;       // distance over which the terrain takes over again
  double z_at_a = 0.0;
  double grade = 0.0;        // dz per metre along a->b
};

class Terrain {
 public:
  std::vector<TerrainWave> waves;
  std::vector<TerrainHill> hills;
  std::vector<GradedCorridor> corridors;

  double height(double x, double y) const;
  /// The height the terrain would have without any corridor.
  double natural_height(double x, double y) const;
  /// Height of a corridor's plane at (x, y) (valid anywhere, meaningful inside it).
  static double corridor_plane(const GradedCorridor& c, double x, double y);
};

}  // namespace liod::sim
