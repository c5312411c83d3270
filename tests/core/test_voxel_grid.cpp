#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "liod/voxel_grid.hpp"

namespace {

using Key = std::tuple<long, long, long>;

Key key_of(const Eigen::Vector3d& p, double size) {
  return {static_cast<long>(std::floor(p.x() / size)), static_cast<long>(std::floor(p.y() / size)),
          static_cast<long>(std::floor(p.z() / size))};
}

// Enough points (and voxels) that the set grows several times from its first capacity: the keys'
// numbers must survive the rehash.
std::vector<Eigen::Vector3d> scattered_points(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-15.0, 15.0);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < n; ++i) points.emplace_back(u(rng), u(rng), u(rng) * 0.2);
  return points;
}

TEST(VoxelSet, NumbersKeysInFirstInsertionOrderAcrossGrowth) {
  liod::VoxelSet set(1);
  std::map<Key, std::uint32_t> expected;
  for (const auto& p : scattered_points(20000, 3)) {
    const auto key = key_of(p, 0.5);
    const auto [inserted, number] = set.insert_numbered(liod::voxel_of(p, 2.0));
    const auto found = expected.find(key);
    if (found == expected.end()) {
      ASSERT_TRUE(inserted);
      ASSERT_EQ(number, expected.size());
      expected.emplace(key, number);
    } else {
      ASSERT_FALSE(inserted);
      ASSERT_EQ(number, found->second);
    }
  }
  EXPECT_GT(expected.size(), 1000u);
}

TEST(VoxelDownsample, LowestKeepsEachVoxelsLowestScoreInFirstSeenOrder) {
  const auto points = scattered_points(20000, 5);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0F, 0.05F);
  std::vector<float> scores;
  for (std::size_t i = 0; i < points.size(); ++i) scores.push_back(u(rng));
  // Brute force: each voxel's lowest score (the first of equals), voxels in first-seen order.
  std::map<Key, std::size_t> lowest;
  std::vector<Key> order;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto key = key_of(points[i], 0.6);
    const auto found = lowest.find(key);
    if (found == lowest.end()) {
      lowest.emplace(key, i);
      order.push_back(key);
    } else if (scores[i] < scores[found->second]) {
      found->second = i;
    }
  }
  const auto kept = liod::voxel_downsample_lowest(points, scores, 0.6);
  ASSERT_EQ(kept.size(), order.size());
  for (std::size_t v = 0; v < order.size(); ++v) EXPECT_EQ(kept[v], points[lowest[order[v]]]) << v;
  // Not merely the first point of each voxel: in most voxels of several points another is lower.
  std::map<Key, int> count;
  for (const auto& p : points) ++count[key_of(p, 0.6)];
  std::size_t shared = 0;
  for (const auto& [key, n] : count) shared += n > 1 ? 1 : 0;
  const auto first = liod::voxel_downsample(points, 0.6);
  ASSERT_EQ(first.size(), kept.size());
  std::size_t differ = 0;
  for (std::size_t v = 0; v < kept.size(); ++v) differ += kept[v] != first[v] ? 1 : 0;
  EXPECT_GT(differ, shared / 2);
}

TEST(VoxelDownsample, LowestWithEqualScoresIsTheFirstPointOfEachVoxel) {
  const auto points = scattered_points(5000, 9);
  const std::vector<float> equal(points.size(), 0.01F);
  EXPECT_EQ(liod::voxel_downsample_lowest(points, equal, 0.6), liod::voxel_downsample(points, 0.6));
}

}  // namespace
