#pragma once
// Integer voxel coordinates and voxel-grid downsampling.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace liod {

struct VoxelKey {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t z = 0;
  bool operator==(const VoxelKey& other) const { return x == other.x && y == other.y && z == other.z; }
};

struct VoxelKeyHash {
  std::size_t operator()(const VoxelKey& k) const {
    // The spatial hash of Teschner et al. 2003 (large primes, XOR).
    return static_cast<std::size_t>((static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.x)) * 73856093ULL) ^
                                    (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.y)) * 19349669ULL) ^
                                    (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.z)) * 83492791ULL));
  }
};

/// floor() to an integer: truncation, minus one for a negative non-integer. Equal to std::floor
/// in the int32 range, and a third of its instructions on x86-64's baseline (no rounding
/// instruction there: GCC emulates floor on doubles); voxel keys are taken millions of times a scan.
/// Beyond the int32 range (a point of a diverged state, before the odometry restarts from it) the
/// key saturates, NaN to the lowest: the conversion would be undefined.
inline std::int32_t floor_to_int(double v) {
  constexpr double kLimit = 2147483647.0;
  if (!(v > -kLimit && v < kLimit)) [[unlikely]] {
    return v >= kLimit ? std::numeric_limits<std::int32_t>::max() : std::numeric_limits<std::int32_t>::min();
  }
  const auto truncated = static_cast<std::int32_t>(v);
  return truncated - static_cast<std::int32_t>(v < static_cast<double>(truncated));
}

inline VoxelKey voxel_of(const Eigen::Vector3d& p, double inverse_size) {
  return {floor_to_int(p.x() * inverse_size), floor_to_int(p.y() * inverse_size), floor_to_int(p.z() * inverse_size)};
}

/// A set of voxel keys for one pass of thinning: open addressing in one array of slots (key and
/// number together, so a probe reads one cache line), so that the tens of thousands of keys a scan
/// inserts cost no allocation each (std::unordered_set's nodes took a tenth of the front end's
/// instructions).
class VoxelSet {
 public:
  /// Sized for half of `points` distinct keys (a thinning keeps a fraction of its points);
  /// it grows when more arrive.
  explicit VoxelSet(std::size_t points);
  struct Insertion {
    bool inserted;        // the key was not in the set yet
    std::uint32_t index;  // the key's number: 0, 1, 2, ... in the order keys were first inserted
  };
  Insertion insert_numbered(const VoxelKey& key);
  /// True if the key was not in the set yet.
  bool insert(const VoxelKey& key) { return insert_numbered(key).inserted; }

 private:
  static constexpr std::uint32_t kFree = 0xFFFFFFFFU;  // a slot's number while it holds no key
  struct Slot {
    VoxelKey key;
    std::uint32_t number = kFree;
  };
  void allocate(std::size_t capacity);
  void grow();
  Insertion place(const VoxelKey& key, std::uint32_t index_if_new);

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

/// Keeps the first point that falls in each voxel of the given size (a real measured point,
/// not a centroid, so that surfaces are not smeared across corners).
std::vector<Eigen::Vector3d> voxel_downsample(const std::vector<Eigen::Vector3d>& points, double voxel_size);

/// Keeps the point of lowest score in each voxel (the first of equals), in the order the voxels
/// were first seen: with equal scores, voxel_downsample.
std::vector<Eigen::Vector3d> voxel_downsample_lowest(const std::vector<Eigen::Vector3d>& points,
                                                     const std::vector<float>& scores, double voxel_size);

}  // namespace liod
