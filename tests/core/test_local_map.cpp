#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "liod/local_map.hpp"

namespace {

std::vector<Eigen::Vector3d> random_cloud(std::size_t n, unsigned seed, double extent) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-extent, extent);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i < n; ++i) out.emplace_back(u(rng), u(rng), u(rng));
  return out;
}

TEST(LocalMap, NearestNeighboursMatchBruteForce) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  const auto cloud = random_cloud(5000, 1, 10.0);
  map.add(cloud, 0);
  ASSERT_EQ(map.size(), cloud.size());
  for (const auto& q : random_cloud(200, 2, 9.0)) {
    std::array<Eigen::Vector3d, liod::LocalMap::kMaxNeighbours> nn;
    const int found = map.nearest(q, 5, 1.0, nn);
    std::vector<double> d;
    for (const auto& p : cloud) {
      if ((p - q).norm() < 1.0) d.push_back((p - q).norm());
    }
    std::sort(d.begin(), d.end());
    ASSERT_EQ(found, static_cast<int>(std::min<std::size_t>(5, d.size())));
    for (int i = 0; i < found; ++i) EXPECT_NEAR((nn[static_cast<std::size_t>(i)] - q).norm(), d[static_cast<std::size_t>(i)], 1e-5);  // stored as float
  }
}

TEST(LocalMap, VoxelOrderGroupsQueriesByVoxelAndAnswersThemAlike) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  map.add(random_cloud(5000, 3, 10.0), 0);
  const auto queries = random_cloud(400, 4, 9.0);
  const auto order = map.voxel_order(queries);
  // A permutation in which each voxel's queries come in one run.
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  std::vector<liod::VoxelKey> finished;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const auto key = map.voxel_key(queries[order[i]]);
    if (i > 0 && key == map.voxel_key(queries[order[i - 1]])) continue;
    EXPECT_TRUE(std::none_of(finished.begin(), finished.end(), [&](const liod::VoxelKey& k) { return k == key; }));
    finished.push_back(key);
  }
  // One search taken in that order answers each query as a fresh one does.
  liod::LocalMap::NeighbourSearch search(map);
  for (const auto i : order) {
    std::array<Eigen::Vector3d, liod::LocalMap::kMaxNeighbours> shared;
    std::array<Eigen::Vector3d, liod::LocalMap::kMaxNeighbours> fresh;
    const int n = search.nearest(queries[i], 8, 1.0, shared);
    ASSERT_EQ(n, map.nearest(queries[i], 8, 1.0, fresh));
    for (int j = 0; j < n; ++j) EXPECT_EQ(shared[static_cast<std::size_t>(j)], fresh[static_cast<std::size_t>(j)]);
  }
}

// Full voxels (their points span several of the voxel's storage blocks), then half of them
// removed (the rest compacted across the blocks): the answers stay those of a brute-force search
// over what the map keeps.
TEST(LocalMap, FullVoxelsAnswerAsBruteForceBeforeAndAfterARemoval) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  const auto a = random_cloud(1000, 5, 2.0);  // about half of each voxel, b the rest
  const auto b = random_cloud(3000, 6, 2.0);
  map.add(a, 1);
  map.add(b, 2);
  ASSERT_EQ(map.size(), 64U * liod::LocalMap::kMaxPointsPerVoxel);  // 4 x 4 x 4 voxels, every one full
  for (int removed = 0; removed < 2; ++removed) {
    const auto kept = map.points();
    for (const auto& q : random_cloud(300, 7 + static_cast<unsigned>(removed), 1.8)) {
      std::array<Eigen::Vector3d, liod::LocalMap::kMaxNeighbours> nn;
      const int found = map.nearest(q, liod::LocalMap::kMaxNeighbours, 0.7, nn);
      std::vector<double> d;
      for (const auto& p : kept) {
        if ((p - q).norm() < 0.7) d.push_back((p - q).norm());
      }
      std::sort(d.begin(), d.end());
      ASSERT_EQ(found, static_cast<int>(std::min<std::size_t>(liod::LocalMap::kMaxNeighbours, d.size())));
      for (int i = 0; i < found; ++i) EXPECT_NEAR((nn[static_cast<std::size_t>(i)] - q).norm(), d[static_cast<std::size_t>(i)], 1e-5);
    }
    if (removed == 0) {
      map.remove_keyframe(a, 1);
      EXPECT_EQ(map.size(), kept.size() - a.size());
    }
  }
}

TEST(LocalMap, SpacingAndCapacityLimitDensity) {
  liod::LocalMap map(1.0, 3, 0.2);
  map.add({{0.1, 0.1, 0.1}, {0.15, 0.1, 0.1}, {0.5, 0.5, 0.5}, {0.9, 0.9, 0.9}, {0.9, 0.1, 0.1}}, 0);
  EXPECT_EQ(map.size(), 3U);  // one too close, one over capacity
}

TEST(LocalMap, RemovingAKeyframeRemovesOnlyItsPoints) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  const auto a = random_cloud(300, 3, 5.0);
  const auto b = random_cloud(300, 4, 5.0);
  map.add(a, 1);
  map.add(b, 2);
  EXPECT_EQ(map.size(), 600U);
  map.remove_keyframe(a, 1);
  EXPECT_EQ(map.size(), 300U);
  std::array<Eigen::Vector3d, liod::LocalMap::kMaxNeighbours> nn;
  for (const auto& p : b) {
    ASSERT_EQ(map.nearest(p, 1, 0.5, nn), 1);
    EXPECT_LT((nn[0] - p).norm(), 1e-5);
  }
}

}  // namespace

TEST(LocalMap, SurvivesManyInsertionsAndRemovalsOfKeyframes) {
  // A long drive: keyframes enter and leave; the hash must keep finding what is left.
  liod::LocalMap map(1.0, 20, 0.1);
  std::vector<std::vector<Eigen::Vector3d>> window;
  for (unsigned kf = 0; kf < 200; ++kf) {
    auto cloud = random_cloud(400, 100 + kf, 6.0);
    for (auto& p : cloud) p.x() += kf * 2.0;  // the vehicle moves on
    map.add(cloud, kf);
    window.push_back(cloud);
    if (window.size() > 25) {
      map.remove_keyframe(window.front(), kf - 25);
      window.erase(window.begin());
    }
  }
  std::size_t expected = 0;
  for (const auto& cloud : window) expected += cloud.size();
  EXPECT_LE(map.size(), expected);
  EXPECT_GT(map.size(), expected / 2);
  EXPECT_EQ(map.points().size(), map.size());
  std::array<Eigen::Vector3d, liod::LocalMap::kMaxNeighbours> nn;
  EXPECT_EQ(map.nearest({2.0, 0.0, 0.0}, 1, 1.0, nn), 0);  // the first keyframes are gone
  int hits = 0;
  for (const auto& p : window.back()) hits += map.nearest(p, 1, 0.11, nn);
  EXPECT_EQ(hits, static_cast<int>(window.back().size()));
}

// A wall seen from three keyframes and a vehicle's back face that moved 1.5 m between them (as one
// pacing the car does): with min_observations 2 the wall answers queries and the vehicle's trail
// does not; a map of one keyframe answers from everything.
TEST(LocalMap, VoxelsSeenByOneKeyframeOnlyAreNotMatched) {
  auto face = [](double x) {  // a 2 m x 1.4 m face across the track at x, 10 cm grid
    std::vector<Eigen::Vector3d> pts;
    for (double y = 3.0; y <= 5.0; y += 0.1) {
      for (double z = 0.2; z <= 1.6; z += 0.1) pts.emplace_back(x, y, z);
    }
    return pts;
  };
  auto wall = [](std::uint64_t k) {  // a wall along the track, its points shifted a little per keyframe
    std::vector<Eigen::Vector3d> pts;
    for (double x = 0.0; x <= 20.0; x += 0.25) {
      for (double z = 0.0; z <= 2.0; z += 0.25) pts.emplace_back(x + 0.05 * static_cast<double>(k), -4.0, z);
    }
    return pts;
  };
  std::array<Eigen::Vector3d, liod::LocalMap::kMaxNeighbours> nn;
  liod::LocalMap map(1.0, 20, 0.2, 2);
  std::vector<Eigen::Vector3d> first = wall(0);
  const auto back0 = face(10.3);
  first.insert(first.end(), back0.begin(), back0.end());
  map.add(first, 0);
  EXPECT_EQ(map.nearest({10.3, 4.0, 1.0}, 5, 1.0, nn), 5) << "a map of one keyframe answers from all of it";
  for (std::uint64_t k = 1; k <= 2; ++k) {
    std::vector<Eigen::Vector3d> pts = wall(k);
    const auto back = face(10.3 + 1.5 * static_cast<double>(k));
    pts.insert(pts.end(), back.begin(), back.end());
    map.add(pts, k);
  }
  EXPECT_EQ(map.nearest({5.1, -4.0, 1.1}, 5, 1.0, nn), 5) << "the wall, seen three times";
  for (double x : {10.3, 11.8, 13.3}) {
    EXPECT_EQ(map.nearest({x, 4.0, 1.0}, 5, 0.4, nn), 0) << "the vehicle's face at x = " << x;
  }
  liod::LocalMap all(1.0, 20, 0.2, 1);
  for (std::uint64_t k = 0; k <= 2; ++k) all.add(face(10.3 + 1.5 * static_cast<double>(k)), k);
  EXPECT_EQ(all.nearest({11.8, 4.0, 1.0}, 5, 0.4, nn), 5) << "min_observations 1 matches every voxel";
}
