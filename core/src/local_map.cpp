#include "liod/local_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace liod {
namespace {

// A hint only (no effect on results); compilers without the builtin skip it.
inline void prefetch(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(address);
#else
  (void)address;
#endif
}

// |(a, b, c)|^2 summed in the order of Eigen's squaredNorm.
inline float squared_norm(float a, float b, float c) { return a * a + (b * b + c * c); }

}  // namespace

LocalMap::LocalMap(double voxel_size, int max_points_per_voxel, double min_point_spacing, int min_observations)
    : inverse_voxel_size_(1.0 / voxel_size),
      max_points_per_voxel_(static_cast<std::uint32_t>(std::clamp(max_points_per_voxel, 1, kMaxPointsPerVoxel))),
      min_spacing_squared_(static_cast<float>(min_point_spacing * min_point_spacing)),
      min_observations_(static_cast<std::uint32_t>(std::max(min_observations, 1))),
      slots_(1024) {}

std::int32_t LocalMap::find_index(const VoxelKey& key) const {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = slot_of(key);; i = (i + 1) & mask) {
    const Slot& slot = slots_[i];
    if (slot.voxel == kEmpty) return kEmpty;
    if (slot.voxel >= 0 && slot.key == key) return slot.voxel;
  }
}

const LocalMap::Voxel* LocalMap::find(const VoxelKey& key) const {
  const std::int32_t v = find_index(key);
  return v < 0 ? nullptr : &voxels_[static_cast<std::size_t>(v)];
}

const LocalMap::Voxel* LocalMap::find_observed(const VoxelKey& key) const {
  const Voxel* voxel = find(key);
  const std::uint32_t needed = keyframes_added_ > 1 ? min_observations_ : 1U;
  return voxel != nullptr && voxel->observations >= needed ? voxel : nullptr;
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
    const std::int32_t v = slots_[i].voxel;
    if (v == kDeleted && reusable == slots_.size()) reusable = i;
    if (v >= 0 && slots_[i].key == key) return voxels_[static_cast<std::size_t>(v)];
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
      voxel.count = 0;
      voxel.observations = 0;
      if (reusable != slots_.size()) {
        slots_[reusable] = {key, index};
      } else {
        slots_[i] = {key, index};
        ++used_slots_;
      }
      return voxel;
    }
  }
}

void LocalMap::erase(const VoxelKey& key) {
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = slot_of(key);; i = (i + 1) & mask) {
    Slot& slot = slots_[i];
    if (slot.voxel == kEmpty) return;
    if (slot.voxel >= 0 && slot.key == key) {
      free_voxels_.push_back(slot.voxel);
      slot.voxel = kDeleted;  // a tombstone keeps later probes of other keys intact
      return;
    }
  }
}

void LocalMap::rehash(std::size_t capacity) {
  std::vector<Slot> old = std::move(slots_);
  slots_.assign(capacity, Slot{});
  used_slots_ = 0;
  const std::size_t mask = capacity - 1;
  for (const Slot& slot : old) {
    if (slot.voxel < 0) continue;
    std::size_t i = slot_of(slot.key);
    while (slots_[i].voxel != kEmpty) i = (i + 1) & mask;
    slots_[i] = slot;
    ++used_slots_;
  }
}

void LocalMap::add(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id) {
  const auto tag = static_cast<std::uint32_t>(keyframe_id);
  ++keyframes_added_;
  for (const auto& p : points) {
    Voxel& voxel = find_or_insert(voxel_of(p, inverse_voxel_size_));
    if (voxel.observations == 0 || voxel.last_observer != tag) {
      ++voxel.observations;
      voxel.last_observer = tag;
    }
    if (voxel.count >= max_points_per_voxel_) continue;
    const Eigen::Vector3f pf = p.cast<float>();
    bool crowded = false;
    // A whole block of distances at a time (several per instruction); those past count go unread.
    for (std::uint32_t b = 0; b * kBlock < voxel.count && !crowded; ++b) {
      const Voxel::Block& block = voxel.blocks[b];
      std::array<float, kBlock> d2;
      for (std::size_t l = 0; l < kBlock; ++l) {
        d2[l] = squared_norm(block.x[l] - pf.x(), block.y[l] - pf.y(), block.z[l] - pf.z());
      }
      const std::uint32_t filled = std::min<std::uint32_t>(kBlock, voxel.count - b * kBlock);
      for (std::uint32_t l = 0; l < filled; ++l) crowded = crowded || d2[l] < min_spacing_squared_;
    }
    if (crowded) continue;
    voxel.set(voxel.count, pf);
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
    // A keyframe has several points in most of its voxels, and the first of them took all of its
    // points out: the later ones find none and leave the voxel untouched.
    std::uint32_t kept = 0;
    while (kept < voxel.count && voxel.keyframes[kept] != tag) ++kept;
    if (kept == voxel.count) continue;
    for (std::uint32_t i = kept + 1; i < voxel.count; ++i) {
      if (voxel.keyframes[i] == tag) continue;
      voxel.set(kept, voxel.point(i));
      voxel.keyframes[kept] = voxel.keyframes[i];
      ++kept;
    }
    point_count_ -= voxel.count - kept;
    voxel.count = kept;
    if (kept == 0) erase(key);
  }
}

std::vector<std::uint32_t> LocalMap::voxel_order(const std::vector<Eigen::Vector3d>& queries) const {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> by_voxel(queries.size());
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const VoxelKey key = voxel_key(queries[i]);
    // 21 bits an axis: the order only groups the queries, wrapping far away costs nothing.
    constexpr std::uint64_t kMask = (1U << 21) - 1;
    const std::uint64_t packed = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(key.x)) & kMask) << 42 |
                                 (static_cast<std::uint64_t>(static_cast<std::uint32_t>(key.y)) & kMask) << 21 |
                                 (static_cast<std::uint64_t>(static_cast<std::uint32_t>(key.z)) & kMask);
    by_voxel[i] = {packed, static_cast<std::uint32_t>(i)};
  }
  std::sort(by_voxel.begin(), by_voxel.end());
  std::vector<std::uint32_t> order(queries.size());
  for (std::size_t i = 0; i < by_voxel.size(); ++i) order[i] = by_voxel[i].second;
  return order;
}

int LocalMap::nearest(const Eigen::Vector3d& query, int k, double max_distance,
                      std::array<Eigen::Vector3d, kMaxNeighbours>& out) const {
  return NeighbourSearch(*this).nearest(query, k, max_distance, out);
}

void LocalMap::NeighbourSearch::Nearest::offer(float d2, std::uint16_t handle) {
  if (d2 >= worst) return;
  int pos = found < k ? found : k - 1;
  while (best_d2[static_cast<std::size_t>(pos)] > d2) {
    best_d2[static_cast<std::size_t>(pos) + 1] = best_d2[static_cast<std::size_t>(pos)];
    best[static_cast<std::size_t>(pos)] = best[static_cast<std::size_t>(pos - 1)];
    --pos;
  }
  best_d2[static_cast<std::size_t>(pos) + 1] = d2;
  best[static_cast<std::size_t>(pos)] = handle;
  if (found < k) ++found;
  if (found == k) worst = best_d2[static_cast<std::size_t>(k)];
}

void LocalMap::NeighbourSearch::prefetch_block(const VoxelKey& own, const VoxelKey& lo, const VoxelKey& hi) const {
  // The block's hash slots lie scattered over the table: ask for all of them at once, so that
  // their cache misses overlap instead of coming one after another in the visits.
  for (int i = std::max(lo.x - own.x, -1); i <= std::min(hi.x - own.x, 1); ++i) {
    for (int j = std::max(lo.y - own.y, -1); j <= std::min(hi.y - own.y, 1); ++j) {
      for (int l = std::max(lo.z - own.z, -1); l <= std::min(hi.z - own.z, 1); ++l) {
        prefetch(&map_->slots_[map_->slot_of({own.x + i, own.y + j, own.z + l})]);
      }
    }
  }
}

void LocalMap::NeighbourSearch::visit(int offset, const VoxelKey& key, const Eigen::Vector3f& query,
                                      Nearest& nearest) {
  if (!(looked_up_ >> offset & 1U)) {
    voxels_[static_cast<std::size_t>(offset)] = map_->find_observed(key);
    looked_up_ |= 1U << offset;
  }
  const Voxel* voxel = voxels_[static_cast<std::size_t>(offset)];
  if (voxel == nullptr) return;
  const std::uint32_t count = voxel->count;
  const float qx = query.x();
  const float qy = query.y();
  const float qz = query.z();
  std::array<float, kMaxPointsPerVoxel> d2;
  for (std::uint32_t b = 0; b * kBlock < count; ++b) {  // whole blocks: the tail's d2 go unread
    const Voxel::Block& block = voxel->blocks[b];
    for (int l = 0; l < kBlock; ++l) {
      const auto lane = static_cast<std::size_t>(l);
      d2[b * kBlock + static_cast<std::uint32_t>(l)] =
          squared_norm(block.x[lane] - qx, block.y[lane] - qy, block.z[lane] - qz);
    }
  }
  for (std::uint32_t j = 0; j < count; ++j) {
    nearest.offer(d2[j], static_cast<std::uint16_t>(offset << 5 | static_cast<int>(j)));
  }
}

int LocalMap::NeighbourSearch::nearest(const Eigen::Vector3d& query, int k, double max_distance,
                                       std::array<Eigen::Vector3d, kMaxNeighbours>& out) {
  static_assert(kMaxPointsPerVoxel <= 32, "a point's index takes 5 bits of its handle");
  Nearest nearest;
  nearest.k = std::min(k, kMaxNeighbours);
  nearest.best_d2[0] = -std::numeric_limits<float>::infinity();
  nearest.worst = static_cast<float>(max_distance * max_distance);
  const Eigen::Vector3f q = query.cast<float>();
  // Only the voxels that overlap the query's gate box can hold a neighbour: 1 to 8 of them for a
  // gate up to half a voxel, at most 27 for a gate up to a whole one (the configuration's limit,
  // hence the block of 27 around the query's voxel). The query's own voxel goes first; once k
  // neighbours are found, a voxel whose box lies farther than the k-th of them is skipped before
  // its hash lookup. Same neighbours, far fewer voxels visited with a wide gate in a dense map.
  const double inverse_voxel_size = map_->inverse_voxel_size_;
  const VoxelKey own = voxel_of(query, inverse_voxel_size);
  const VoxelKey lo = voxel_of(query - Eigen::Vector3d::Constant(max_distance), inverse_voxel_size);
  const VoxelKey hi = voxel_of(query + Eigen::Vector3d::Constant(max_distance), inverse_voxel_size);
  if (!have_centre_ || !(own == centre_)) {
    centre_ = own;
    have_centre_ = true;
    looked_up_ = 0;
    prefetch_block(own, lo, hi);
  }
  const float voxel_size = static_cast<float>(1.0 / inverse_voxel_size);
  // From the query to a voxel's box, per axis 0 inside it: a sum of one term per axis, so the
  // 3 x 3 terms of the block are computed once (squared), not for each of its 27 voxels.
  auto axis_terms = [&](float coordinate, std::int32_t centre) {
    std::array<float, 3> terms;
    for (int i = 0; i < 3; ++i) {
      const float lo_edge = static_cast<float>(centre - 1 + i) * voxel_size;
      const float gap = std::max(lo_edge - coordinate, 0.0F) + std::max(coordinate - lo_edge - voxel_size, 0.0F);
      terms[static_cast<std::size_t>(i)] = gap * gap;
    }
    return terms;
  };
  const std::array<float, 3> box_x = axis_terms(q.x(), own.x);
  const std::array<float, 3> box_y = axis_terms(q.y(), own.y);
  const std::array<float, 3> box_z = axis_terms(q.z(), own.z);
  constexpr int kOwn = 13;  // the block's centre
  visit(kOwn, own, q, nearest);
  // A sum of non-negative terms is at least each of them (also rounded): once an axis's term
  // reaches the k-th distance, its whole slab of the block is skipped.
  for (int i = std::max(lo.x - own.x, -1) + 1; i <= std::min(hi.x - own.x, 1) + 1; ++i) {
    const float sx = box_x[static_cast<std::size_t>(i)];
    if (sx >= nearest.worst) continue;
    for (int j = std::max(lo.y - own.y, -1) + 1; j <= std::min(hi.y - own.y, 1) + 1; ++j) {
      const float sy = box_y[static_cast<std::size_t>(j)];
      if (sy >= nearest.worst) continue;
      for (int l = std::max(lo.z - own.z, -1) + 1; l <= std::min(hi.z - own.z, 1) + 1; ++l) {
        const int offset = 9 * i + 3 * j + l;
        if (offset == kOwn || sx + (sy + box_z[static_cast<std::size_t>(l)]) >= nearest.worst) continue;
        visit(offset, {own.x + i - 1, own.y + j - 1, own.z + l - 1}, q, nearest);
      }
    }
  }
  for (int i = 0; i < nearest.found; ++i) {
    const std::uint16_t handle = nearest.best[static_cast<std::size_t>(i)];
    out[static_cast<std::size_t>(i)] = voxels_[handle >> 5U]->point(handle & 31U).cast<double>();
  }
  return nearest.found;
}

std::vector<Eigen::Vector3d> LocalMap::points() const {
  std::vector<Eigen::Vector3d> all;
  all.reserve(point_count_);
  for (const Slot& slot : slots_) {
    if (slot.voxel < 0) continue;
    const Voxel& voxel = voxels_[static_cast<std::size_t>(slot.voxel)];
    for (std::uint32_t i = 0; i < voxel.count; ++i) all.push_back(voxel.point(i).cast<double>());
  }
  return all;
}

}  // namespace liod
