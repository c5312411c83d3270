#include "liod/voxel_grid.hpp"

namespace liod {

VoxelSet::VoxelSet(std::size_t points) {
  std::size_t capacity = 16;
  while (capacity < points) capacity *= 2;  // half of the points at most half full
  allocate(capacity);
}

void VoxelSet::allocate(std::size_t capacity) {
  slots_.assign(capacity, Slot{});
  size_ = 0;
}

VoxelSet::Insertion VoxelSet::insert_numbered(const VoxelKey& key) {
  if (2 * (size_ + 1) > slots_.size()) grow();
  return place(key, static_cast<std::uint32_t>(size_));
}

VoxelSet::Insertion VoxelSet::place(const VoxelKey& key, std::uint32_t index_if_new) {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = VoxelKeyHash{}(key) & mask;; i = (i + 1) & mask) {
    Slot& slot = slots_[i];
    if (slot.number == kFree) {
      slot.key = key;
      slot.number = index_if_new;
      ++size_;
      return {true, index_if_new};
    }
    if (slot.key == key) return {false, slot.number};
  }
}

void VoxelSet::grow() {
  const std::vector<Slot> old = std::move(slots_);
  allocate(2 * old.size());
  for (const Slot& slot : old) {
    if (slot.number != kFree) place(slot.key, slot.number);
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
