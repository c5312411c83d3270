#include "liod/local_map.hpp"

#include <algorithm>
#include <cmath>

namespace liod {

LocalMap::LocalMap(double voxel_size, int max_points_per_voxel, double min_point_spacing)
    : voxel_size_(voxel_size),
      inverse_voxel_size_(1.0 / voxel_size),
      max_points_per_voxel_(static_cast<std::size_t>(max_points_per_voxel)),
      min_spacing_squared_(min_point_spacing * min_point_spacing) {}

void LocalMap::add(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id) {
  for (const auto& p : points) {
    Voxel& voxel = voxels_[voxel_of(p, inverse_voxel_size_)];
    if (voxel.size() >= max_points_per_voxel_) continue;
    const bool crowded = std::any_of(voxel.begin(), voxel.end(), [&](const Entry& e) {
      return (e.point - p).squaredNorm() < min_spacing_squared_;
    });
    if (crowded) continue;
    if (voxel.empty()) voxel.reserve(max_points_per_voxel_);
    voxel.push_back({p, keyframe_id});
    ++point_count_;
  }
}

void LocalMap::remove_keyframe(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id) {
  for (const auto& p : points) {
    const auto it = voxels_.find(voxel_of(p, inverse_voxel_size_));
    if (it == voxels_.end()) continue;
    Voxel& voxel = it->second;
    const auto old_size = voxel.size();
    voxel.erase(std::remove_if(voxel.begin(), voxel.end(), [&](const Entry& e) { return e.keyframe == keyframe_id; }),
                voxel.end());
    point_count_ -= old_size - voxel.size();
    if (voxel.empty()) voxels_.erase(it);
  }
}

int LocalMap::nearest(const Eigen::Vector3d& query, int k, double max_distance,
                      std::array<Eigen::Vector3d, kMaxNeighbours>& out) const {
  k = std::min(k, kMaxNeighbours);
  std::array<double, kMaxNeighbours> best_d2;
  int found = 0;
  double worst = max_distance * max_distance;
  const VoxelKey centre = voxel_of(query, inverse_voxel_size_);
  // One ring of voxels is exact for max_distance <= voxel size (the configuration enforces it):
  // 27 hash look-ups, where a wider gate would cost 125.
  constexpr int reach = 1;
  for (int dx = -reach; dx <= reach; ++dx) {
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dz = -reach; dz <= reach; ++dz) {
        const auto it = voxels_.find({centre.x + dx, centre.y + dy, centre.z + dz});
        if (it == voxels_.end()) continue;
        for (const Entry& e : it->second) {
          const double d2 = (e.point - query).squaredNorm();
          if (d2 >= worst) continue;
          // Insertion into the sorted best list.
          int pos = found < k ? found : k - 1;
          while (pos > 0 && best_d2[pos - 1] > d2) {
            best_d2[pos] = best_d2[pos - 1];
            out[pos] = out[pos - 1];
            --pos;
          }
          best_d2[pos] = d2;
          out[pos] = e.point;
          if (found < k) ++found;
          if (found == k) worst = best_d2[k - 1];
        }
      }
    }
  }
  return found;
}

std::vector<Eigen::Vector3d> LocalMap::points() const {
  std::vector<Eigen::Vector3d> all;
  all.reserve(point_count_);
  for (const auto& [key, voxel] : voxels_) {
    for (const Entry& e : voxel) all.push_back(e.point);
  }
  return all;
}

}  // namespace liod
