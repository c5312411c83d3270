#include "liod/hausdorff.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "liod/voxel_grid.hpp"

namespace liod {

double directed_hausdorff(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double cap) {
  if (a.empty() || b.empty()) return cap;
  // Cells of size cap: any neighbour closer than cap lies in the 27 surrounding cells.
  const double inverse = 1.0 / cap;
  std::unordered_map<VoxelKey, std::vector<Eigen::Vector3d>, VoxelKeyHash> grid;
  grid.reserve(b.size());
  for (const auto& p : b) grid[voxel_of(p, inverse)].push_back(p);
  double worst_squared = 0.0;
  const double cap_squared = cap * cap;
  for (const auto& p : a) {
    const VoxelKey c = voxel_of(p, inverse);
    double best = cap_squared;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid.end()) continue;
          for (const auto& q : it->second) best = std::min(best, (q - p).squaredNorm());
        }
      }
    }
    worst_squared = std::max(worst_squared, best);
    if (worst_squared >= cap_squared) return cap;
  }
  return std::sqrt(worst_squared);
}

double hausdorff_distance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double cap) {
  const double forward = directed_hausdorff(a, b, cap);
  if (forward >= cap) return cap;
  return std::max(forward, directed_hausdorff(b, a, cap));
}

}  // namespace liod
