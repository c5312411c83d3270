#include "liod/voxel_grid.hpp"

#include <unordered_set>

namespace liod {

std::vector<Eigen::Vector3d> voxel_downsample(const std::vector<Eigen::Vector3d>& points, double voxel_size) {
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(points.size() / 4 + 1);
  std::unordered_set<VoxelKey, VoxelKeyHash> occupied;
  occupied.reserve(points.size());
  const double inverse = 1.0 / voxel_size;
  for (const auto& p : points) {
    if (occupied.insert(voxel_of(p, inverse)).second) kept.push_back(p);
  }
  return kept;
}

}  // namespace liod
