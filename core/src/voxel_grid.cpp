#include "liod/voxel_grid.hpp"

namespace liod {

VoxelSet::VoxelSet(std::size_t expected) {
  std::size_t capacity = 16;
  while (capacity < 2 * expected) capacity *= 2;  // at most half full: short probes
  keys_.resize(capacity);
  used_.assign(capacity, 0);
}

bool VoxelSet::insert(const VoxelKey& key) {
  if (2 * (size_ + 1) > keys_.size()) grow();
  const std::size_t mask = keys_.size() - 1;
  for (std::size_t i = VoxelKeyHash{}(key) & mask;; i = (i + 1) & mask) {
    if (!used_[i]) {
      keys_[i] = key;
      used_[i] = 1;
      ++size_;
      return true;
    }
    if (keys_[i] == key) return false;
  }
}

void VoxelSet::grow() {
  const std::vector<VoxelKey> keys = std::move(keys_);
  const std::vector<std::uint8_t> used = std::move(used_);
  keys_.assign(2 * keys.size(), VoxelKey{});
  used_.assign(2 * keys.size(), 0);
  size_ = 0;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (used[i]) insert(keys[i]);
  }
}

std::vector<Eigen::Vector3d> voxel_downsample(const std::vector<Eigen::Vector3d>& points, double voxel_size) {
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(points.size() / 4 + 1);
  VoxelSet occupied(points.size());
  const double inverse = 1.0 / voxel_size;
  for (const auto& p : points) {
    if (occupied.insert(voxel_of(p, inverse))) kept.push_back(p);
  }
  return kept;
}

}  // namespace liod
