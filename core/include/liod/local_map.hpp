#pragma once
// The local map: points of the keyframes in the sliding window, in a voxel hash that answers
// k-nearest-neighbour queries without rebuilding a tree per scan. Each point remembers its
// keyframe so that the oldest keyframe's points leave the map when it leaves the window.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "liod/voxel_grid.hpp"

namespace liod {

class LocalMap {
 public:
  static constexpr int kMaxNeighbours = 8;

  LocalMap(double voxel_size, int max_points_per_voxel, double min_point_spacing);

  /// Adds world-frame points of one keyframe, keeping at most max_points_per_voxel per voxel and
  /// no two points closer than min_point_spacing.
  void add(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id);
  /// Removes every point that came from this keyframe.
  void remove_keyframe(const std::vector<Eigen::Vector3d>& points, std::uint64_t keyframe_id);

  /// The k nearest map points within max_distance (<= the voxel size) of the query, nearest
  /// first; returns how many were found (<= k <= kMaxNeighbours).
  int nearest(const Eigen::Vector3d& query, int k, double max_distance,
              std::array<Eigen::Vector3d, kMaxNeighbours>& out) const;

  std::size_t size() const { return point_count_; }
  bool empty() const { return point_count_ == 0; }
  /// Every point in the map (for saving and visualisation).
  std::vector<Eigen::Vector3d> points() const;

 private:
  struct Entry {
    Eigen::Vector3d point;
    std::uint64_t keyframe;
  };
  using Voxel = std::vector<Entry>;

  double voxel_size_;
  double inverse_voxel_size_;
  std::size_t max_points_per_voxel_;
  double min_spacing_squared_;
  std::size_t point_count_ = 0;
  std::unordered_map<VoxelKey, Voxel, VoxelKeyHash> voxels_;
};

}  // namespace liod
