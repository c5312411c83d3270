#pragma once
// The local map: points of the keyframes in the sliding window, in a voxel hash that answers
// k-nearest-neighbour queries without rebuilding a tree per scan. Each point remembers its
// keyframe so that the oldest keyframe's points leave the map when it leaves the window.
// The hash is open-addressed (linear probing) over a pool of fixed-capacity voxels: a query's
// 27 look-ups touch a few cache lines instead of chasing a node-based map's pointers.
//
// Moving objects: each voxel counts the keyframes that saw something in it, and a query uses only
// voxels seen by at least min_observations of them. A static surface is seen again from the next
// keyframe, keyframe_distance_m on; a vehicle that moved a voxel or more between two keyframes
// (one pacing the car moves as far as the car) leaves a trail of voxels each seen once, and the
// trail would otherwise hold the registration where the scene says little along the track
// (docs/design.md, "Moving objects"). A map of a single keyframe uses everything it has.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "liod/map_limits.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {

class LocalMap {
  struct Voxel;

 public:
  static constexpr int kMaxNeighbours = kMapMaxNeighbours;
  static constexpr int kMaxPointsPerVoxel = kMapMaxPointsPerVoxel;

  /// max_points_per_voxel is capped at kMaxPointsPerVoxel; min_observations: the keyframes that
  /// must have seen a voxel before queries use it (1: every voxel).
  LocalMap(double voxel_size, int max_points_per_voxel, double min_point_spacing, int min_observations = 1);

  /// Adds world-frame points of one keyframe, keeping at most max_points_per_voxel per voxel and
  /// no two points closer than min_point_spacing. Every voxel a point falls in counts the
  /// keyframe as an observation, also where the point itself is not kept.
  void add(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id);
  /// Removes every point that came from this keyframe (`points` are the ones it added).
  void remove_keyframe(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id);

  /// The k nearest map points within max_distance (<= the voxel size) of the query, nearest
  /// first; returns how many were found (<= k <= kMaxNeighbours).
  int nearest(const Eigen::Vector3d& query, int k, double max_distance,
              std::array<Eigen::Vector3d, kMaxNeighbours>& out) const;

  /// The voxel a point falls in: queries sorted by it share their look-ups in a NeighbourSearch.
  VoxelKey voxel_key(const Eigen::Vector3d& p) const { return voxel_of(p, inverse_voxel_size_); }
  /// The queries' indices sorted by their voxel: taken in this order, a NeighbourSearch answers
  /// each from the look-ups of the last.
  std::vector<std::uint32_t> voxel_order(const std::vector<Eigen::Vector3d>& queries) const;

  /// Answers nearest() for a run of queries, keeping the voxels looked up around the last query's
  /// voxel: a scan's queries, taken voxel by voxel, skip most of their 27 hash look-ups and find
  /// the voxels' points still in cache. Same answers as LocalMap::nearest. Valid while the map
  /// is unchanged.
  class NeighbourSearch {
   public:
    explicit NeighbourSearch(const LocalMap& map) : map_(&map) {}
    int nearest(const Eigen::Vector3d& query, int k, double max_distance,
                std::array<Eigen::Vector3d, kMaxNeighbours>& out);

   private:
    // The k nearest so far, nearest first: best_d2[i + 1] is the i-th's squared distance
    // (best_d2[0], below any distance, ends the insertion's shifting without a bounds test), and
    // best[i] which point it is: its voxel's block offset times 32 plus its index there, so that
    // the insertion shifts a small integer, not the point.
    struct Nearest {
      int k = 0;
      int found = 0;
      float worst = 0.0F;  // the gate's square until k are found, then the k-th's squared distance
      std::array<float, kMaxNeighbours + 1> best_d2;
      std::array<std::uint16_t, kMaxNeighbours> best;
      void offer(float d2, std::uint16_t handle);
    };
    /// Prefetches the hash slots of the block of voxels around `own` that the gate box reaches.
    void prefetch_block(const VoxelKey& own, const VoxelKey& lo, const VoxelKey& hi) const;
    /// Offers the points of the voxel at `offset` (9 x + 3 y + z in the block, 0..26) to `nearest`.
    void visit(int offset, const VoxelKey& key, const Eigen::Vector3f& query, Nearest& nearest);

    const LocalMap* map_;
    VoxelKey centre_;
    bool have_centre_ = false;
    std::uint32_t looked_up_ = 0;  // bit i: voxels_[i] holds the look-up of block offset i
    std::array<const Voxel*, 27> voxels_{};
  };

  std::size_t size() const { return point_count_; }
  bool empty() const { return point_count_ == 0; }
  /// Every point in the map (for saving and visualisation).
  std::vector<Eigen::Vector3d> points() const;

 private:
  // Coordinates apart in blocks of eight points (x's, y's, z's), so that the distances to a
  // voxel's points are computed several at a time, and a voxel of n points spans only the cache
  // lines of its first n / 8 blocks. The count leads, in the first block's line.
  static constexpr int kBlock = 8;
  static_assert(kMaxPointsPerVoxel % kBlock == 0, "whole blocks");
  struct Voxel {
    struct Block {
      std::array<float, kBlock> x{};
      std::array<float, kBlock> y{};
      std::array<float, kBlock> z{};
    };
    std::uint32_t count = 0;
    std::uint32_t observations = 0;    // keyframes that saw this voxel
    std::uint32_t last_observer = 0;   // the newest of them (its id's low bits)
    std::array<Block, kMaxPointsPerVoxel / kBlock> blocks{};
    std::array<std::uint32_t, kMaxPointsPerVoxel> keyframes{};
    Eigen::Vector3f point(std::uint32_t i) const {
      const Block& b = blocks[i / kBlock];
      return {b.x[i % kBlock], b.y[i % kBlock], b.z[i % kBlock]};
    }
    void set(std::uint32_t i, const Eigen::Vector3f& p) {
      Block& b = blocks[i / kBlock];
      b.x[i % kBlock] = p.x();
      b.y[i % kBlock] = p.y();
      b.z[i % kBlock] = p.z();
    }
  };
  // The key sits in the slot, so that probing reads the slot array only, not the voxels.
  struct Slot {
    VoxelKey key;
    std::int32_t voxel = kEmpty;  // index into voxels_, or kEmpty / kDeleted
  };
  static constexpr std::int32_t kEmpty = -1;
  static constexpr std::int32_t kDeleted = -2;

  std::size_t slot_of(const VoxelKey& key) const { return VoxelKeyHash{}(key) & (slots_.size() - 1); }
  std::int32_t find_index(const VoxelKey& key) const;
  const Voxel* find(const VoxelKey& key) const;
  /// find(), but null for a voxel seen by too few keyframes to be used.
  const Voxel* find_observed(const VoxelKey& key) const;
  Voxel& find_or_insert(const VoxelKey& key);
  void erase(const VoxelKey& key);
  void rehash(std::size_t capacity);

  double inverse_voxel_size_;
  std::uint32_t max_points_per_voxel_;
  float min_spacing_squared_;
  std::uint32_t min_observations_;
  std::uint32_t keyframes_added_ = 0;
  std::size_t point_count_ = 0;
  std::vector<Slot> slots_;
  std::vector<Voxel> voxels_;
  std::vector<std::int32_t> free_voxels_;
  std::size_t used_slots_ = 0;  // live + deleted, for the load factor
};

}  // namespace liod
