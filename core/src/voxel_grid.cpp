#include "liod/voxel_grid.hpp"

namespace liod {

VoxelSet::VoxelSet(std::size_t expected) {
  std::size_t capacity = 16;
  while (capacity < 2 * expected) capacity *= 2;  // at most half full: short probes
  keys_.resize(capacity);
  numbers_.resize(capacity);
  used_.assign(capacity, 0);
}

VoxelSet::Insertion VoxelSet::insert_numbered(const VoxelKey& key) {
  if (2 * (size_ + 1) > keys_.size()) grow();
  return place(key, static_cast<std::uint32_t>(size_));
}

VoxelSet::Insertion VoxelSet::place(const VoxelKey& key, std::uint32_t index_if_new) {
  const std::size_t mask = keys_.size() - 1;
  for (std::size_t i = VoxelKeyHash{}(key) & mask;; i = (i + 1) & mask) {
    if (!used_[i]) {
      keys_[i] = key;
      numbers_[i] = index_if_new;
      used_[i] = 1;
      ++size_;
      return {true, index_if_new};
    }
    if (keys_[i] == key) return {false, numbers_[i]};
  }
}

void VoxelSet::grow() {
  const std::vector<VoxelKey> keys = std::move(keys_);
  const std::vector<std::uint32_t> numbers = std::move(numbers_);
  const std::vector<std::uint8_t> used = std::move(used_);
  keys_.assign(2 * keys.size(), VoxelKey{});
  numbers_.assign(2 * keys.size(), 0);
  used_.assign(2 * keys.size(), 0);
  size_ = 0;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (used[i]) place(keys[i], numbers[i]);
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

std::vector<Eigen::Vector3d> voxel_downsample_lowest(const std::vector<Eigen::Vector3d>& points,
                                                     const std::vector<float>& scores, double voxel_size) {
  std::vector<std::uint32_t> lowest;  // per voxel, by its number
  lowest.reserve(points.size() / 4 + 1);
  VoxelSet voxels(points.size());
  const double inverse = 1.0 / voxel_size;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    const auto [inserted, number] = voxels.insert_numbered(voxel_of(points[i], inverse));
    if (inserted) {
      lowest.push_back(i);
    } else if (scores[i] < scores[lowest[number]]) {
      lowest[number] = i;
    }
  }
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(lowest.size());
  for (const std::uint32_t i : lowest) kept.push_back(points[i]);
  return kept;
}

}  // namespace liod
