#include "liod/local_map.hpp"

#include <algorithm>
#include <cmath>

namespace liod {

LocalMap::LocalMap(double voxel_size, int max_points_per_voxel, double min_point_spacing)
    : inverse_voxel_size_(1.0 / voxel_size),
      max_points_per_voxel_(static_cast<std::uint32_t>(std::clamp(max_points_per_voxel, 1, kMaxPointsPerVoxel))),
      min_spacing_squared_(static_cast<float>(min_point_spacing * min_point_spacing)),
      slots_(1024, kEmpty) {}

std::int32_t LocalMap::find_index(const VoxelKey& key) const {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = slot_of(key);; i = (i + 1) & mask) {
    const std::int32_t v = slots_[i];
    if (v == kEmpty) return kEmpty;
    if (v >= 0 && voxels_[static_cast<std::size_t>(v)].key == key) return v;
  }
}

const LocalMap::Voxel* LocalMap::find(const VoxelKey& key) const {
  const std::int32_t v = find_index(key);
  return v < 0 ? nullptr : &voxels_[static_cast<std::size_t>(v)];
}

LocalMap::Voxel& LocalMap::find_or_insert(const VoxelKey& key) {
  if (2 * (used_slots_ + 1) > slots_.size()) {
    // Half full of live voxels and tombstones: grow if the live ones alone fill a quarter,
    // otherwise just sweep the tombstones out.
    const std::size_t live = voxels_.size() - free_voxels_.size();
    rehash(4 * live > slots_.size() ? 2 * slots_.size() : slots_.size());
  }
  const std::size_t mask = slots_.size() - 1;
  std::size_t reusable = slots_.size();
  for (std::size_t i = slot_of(key);; i = (i + 1) & mask) {
    const std::int32_t v = slots_[i];
    if (v == kDeleted && reusable == slots_.size()) reusable = i;
    if (v >= 0 && voxels_[static_cast<std::size_t>(v)].key == key) return voxels_[static_cast<std::size_t>(v)];
    if (v == kEmpty) {
      std::int32_t index;
      if (!free_voxels_.empty()) {
        index = free_voxels_.back();
        free_voxels_.pop_back();
      } else {
        index = static_cast<std::int32_t>(voxels_.size());
        voxels_.emplace_back();
      }
      Voxel& voxel = voxels_[static_cast<std::size_t>(index)];
      voxel.key = key;
      voxel.count = 0;
      if (reusable != slots_.size()) {
        slots_[reusable] = index;
      } else {
        slots_[i] = index;
        ++used_slots_;
      }
      return voxel;
    }
  }
}

void LocalMap::erase(const VoxelKey& key) {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = slot_of(key);; i = (i + 1) & mask) {
    const std::int32_t v = slots_[i];
    if (v == kEmpty) return;
    if (v >= 0 && voxels_[static_cast<std::size_t>(v)].key == key) {
      slots_[i] = kDeleted;  // a tombstone keeps later probes of other keys intact
      free_voxels_.push_back(v);
      return;
    }
  }
}

void LocalMap::rehash(std::size_t capacity) {
  std::vector<std::int32_t> old = std::move(slots_);
  slots_.assign(capacity, kEmpty);
  used_slots_ = 0;
  const std::size_t mask = capacity - 1;
  for (const std::int32_t v : old) {
    if (v < 0) continue;
    std::size_t i = slot_of(voxels_[static_cast<std::size_t>(v)].key);
    while (slots_[i] != kEmpty) i = (i + 1) & mask;
    slots_[i] = v;
    ++used_slots_;
  }
}

void LocalMap::add(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id) {
  const auto tag = static_cast<std::uint32_t>(keyframe_id);
  for (const auto& p : points) {
    Voxel& voxel = find_or_insert(voxel_of(p, inverse_voxel_size_));
    if (voxel.count >= max_points_per_voxel_) continue;
    const Eigen::Vector3f pf = p.cast<float>();
    bool crowded = false;
    for (std::uint32_t i = 0; i < voxel.count && !crowded; ++i) {
      crowded = (voxel.points[i] - pf).squaredNorm() < min_spacing_squared_;
    }
    if (crowded) continue;
    voxel.points[voxel.count] = pf;
    voxel.keyframes[voxel.count] = tag;
    ++voxel.count;
    ++point_count_;
  }
}

void LocalMap::remove_keyframe(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id) {
  const auto tag = static_cast<std::uint32_t>(keyframe_id);
  for (const auto& p : points) {
    const VoxelKey key = voxel_of(p, inverse_voxel_size_);
    const std::int32_t index = find_index(key);
    if (index < 0) continue;
    Voxel& voxel = voxels_[static_cast<std::size_t>(index)];
    std::uint32_t kept = 0;
    for (std::uint32_t i = 0; i < voxel.count; ++i) {
      if (voxel.keyframes[i] == tag) continue;
      voxel.points[kept] = voxel.points[i];
      voxel.keyframes[kept] = voxel.keyframes[i];
      ++kept;
    }
    point_count_ -= voxel.count - kept;
    voxel.count = kept;
    if (kept == 0) erase(key);
  }
}

int LocalMap::nearest(const Eigen::Vector3d& query, int k, double max_distance,
                      std::array<Eigen::Vector3d, kMaxNeighbours>& out) const {
  k = std::min(k, kMaxNeighbours);
  std::array<float, kMaxNeighbours> best_d2;
  std::array<Eigen::Vector3f, kMaxNeighbours> best;
  int found = 0;
  float worst = static_cast<float>(max_distance * max_distance);
  const Eigen::Vector3f q = query.cast<float>();
  // Only the voxels that overlap the query's gate box can hold a neighbour: 1 to 8 of them for a
  // gate up to half a voxel, at most 27 for a gate up to a whole one (the configuration's limit).
  // The query's own voxel goes first; once k neighbours are found, a voxel whose box lies farther
  // than the k-th of them is skipped before its hash lookup. Same neighbours, far fewer voxels
  // visited with a wide gate in a dense map.
  const VoxelKey own = voxel_of(query, inverse_voxel_size_);
  const VoxelKey lo = voxel_of(query - Eigen::Vector3d::Constant(max_distance), inverse_voxel_size_);
  const VoxelKey hi = voxel_of(query + Eigen::Vector3d::Constant(max_distance), inverse_voxel_size_);
  const float voxel_size = static_cast<float>(1.0 / inverse_voxel_size_);
  auto box_distance2 = [&](const VoxelKey& key) {
    // From the query to the voxel's box, per axis 0 inside it.
    const Eigen::Vector3f box_lo(static_cast<float>(key.x) * voxel_size, static_cast<float>(key.y) * voxel_size,
                                 static_cast<float>(key.z) * voxel_size);
    const Eigen::Vector3f below = (box_lo - q).cwiseMax(0.0F);
    const Eigen::Vector3f above = (q - box_lo - Eigen::Vector3f::Constant(voxel_size)).cwiseMax(0.0F);
    return (below + above).squaredNorm();
  };
  auto visit = [&](const VoxelKey& key) {
    const Voxel* voxel = find(key);
    if (voxel == nullptr) return;
    for (std::uint32_t j = 0; j < voxel->count; ++j) {
      const float d2 = (voxel->points[j] - q).squaredNorm();
      if (d2 >= worst) continue;
      int pos = found < k ? found : k - 1;
      while (pos > 0 && best_d2[static_cast<std::size_t>(pos - 1)] > d2) {
        best_d2[static_cast<std::size_t>(pos)] = best_d2[static_cast<std::size_t>(pos - 1)];
        best[static_cast<std::size_t>(pos)] = best[static_cast<std::size_t>(pos - 1)];
        --pos;
      }
      best_d2[static_cast<std::size_t>(pos)] = d2;
      best[static_cast<std::size_t>(pos)] = voxel->points[j];
      if (found < k) ++found;
      if (found == k) worst = best_d2[static_cast<std::size_t>(k - 1)];
    }
  };
  visit(own);
  for (int dx = lo.x; dx <= hi.x; ++dx) {
    for (int dy = lo.y; dy <= hi.y; ++dy) {
      for (int dz = lo.z; dz <= hi.z; ++dz) {
        const VoxelKey key{dx, dy, dz};
        if (key == own || box_distance2(key) >= worst) continue;
        visit(key);
      }
    }
  }
  for (int i = 0; i < found; ++i) out[static_cast<std::size_t>(i)] = best[static_cast<std::size_t>(i)].cast<double>();
  return found;
}

std::vector<Eigen::Vector3d> LocalMap::points() const {
  std::vector<Eigen::Vector3d> all;
  all.reserve(point_count_);
  for (const std::int32_t v : slots_) {
    if (v < 0) continue;
    const Voxel& voxel = voxels_[static_cast<std::size_t>(v)];
    for (std::uint32_t i = 0; i < voxel.count; ++i) all.push_back(voxel.points[i].cast<double>());
  }
  return all;
}

}  // namespace liod
