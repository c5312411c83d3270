// The keyframe store keeps a bounded number of clouds in memory: the least recently used ones
// leave memory once written to the spill and come back bit for bit when asked for.

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>

#include "liod/backend/keyframe_store.hpp"
#include "liod/backend/map_store.hpp"
#include "scratch_dir.hpp"

namespace {

namespace fs = std::filesystem;
using namespace liod;

fs::path scratch_dir(const std::string& name) {
  const fs::path dir = liod::test::program_scratch_dir() / name;
  fs::remove_all(dir);
  return dir;
}

BackendKeyframe random_keyframe(std::uint64_t id, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-50.0F, 50.0F);
  BackendKeyframe k;
  k.id = id;
  k.time = 0.1 * static_cast<double>(id) + 1e-7;
  k.odometry_pose = Eigen::AngleAxisd(0.01 * static_cast<double>(id), Eigen::Vector3d(0.2, 0.1, 1.0).normalized());
  k.odometry_pose.translation() = Eigen::Vector3d(1.3 * static_cast<double>(id), -0.7, 0.05);
  for (int j = 0; j < 500; ++j) k.planes.emplace_back(u(rng), u(rng), u(rng));
  for (int j = 0; j < 50; ++j) k.edges.emplace_back(u(rng), u(rng), u(rng));
  for (int j = 0; j < 80; ++j) k.similarity.emplace_back(u(rng), u(rng), u(rng));
  return k;
}

bool same_bits(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Eigen::Vector3f)) == 0;
}

TEST(KeyframeStore, EvictsTheLeastRecentlyUsedAndReloadsThemBitIdentically) {
  const fs::path dir = scratch_dir("lru");
  std::mt19937 rng(5);
  std::vector<BackendKeyframe> originals;
  {
    auto spill = std::make_shared<KeyframeDirectory>(dir, KeyframeDirectory::Kind::kScratch);
    KeyframeStore store(3, spill);
    for (std::uint64_t i = 0; i < 10; ++i) {
      originals.push_back(random_keyframe(i, rng));
      store.add(originals.back());
    }
    // Only the 3 newest clouds are in memory; every pose and time is.
    EXPECT_EQ(store.in_memory_count(), 3U);
    EXPECT_EQ(store.evictions(), 7U);
    for (std::size_t k = 0; k < 10; ++k) {
      EXPECT_EQ(store.in_memory(k), k >= 7) << k;
      EXPECT_TRUE(store.spilled(k));
      EXPECT_EQ(store.id(k), originals[k].id);
      EXPECT_EQ(store.time(k), originals[k].time);
      EXPECT_TRUE(store.odometry_pose(k).isApprox(originals[k].odometry_pose, 0.0));
    }

    // A read brings an evicted cloud back, bit for bit, and pushes out the least recently used (7).
    const auto back = store.get(2);
    EXPECT_EQ(store.reads(), 1U);
    EXPECT_TRUE(store.in_memory(2));
    EXPECT_FALSE(store.in_memory(7));
    EXPECT_EQ(store.in_memory_count(), 3U);
    EXPECT_EQ(back->id, originals[2].id);
    EXPECT_EQ(back->time, originals[2].time);
    // The file keeps the pose as a quaternion (the state format); the backend reads poses from
    // the store's index, which never leaves memory, so only the clouds must be bit-exact.
    EXPECT_TRUE(back->odometry_pose.isApprox(originals[2].odometry_pose, 1e-12));
    EXPECT_TRUE(same_bits(back->planes, originals[2].planes));
    EXPECT_TRUE(same_bits(back->edges, originals[2].edges));
    EXPECT_TRUE(same_bits(back->similarity, originals[2].similarity));

    // Using 8 makes 9 the least recently used; the evicted pointer stays valid for its holder.
    const auto nine = store.get(9);
    (void)store.get(8);
    (void)store.get(2);
    (void)store.get(0);
    EXPECT_FALSE(store.in_memory(9));
    EXPECT_TRUE(same_bits(nine->planes, originals[9].planes));
    EXPECT_EQ(store.reads(), 2U);

    // peek reads without disturbing the cache.
    const auto five = store.peek(5);
    EXPECT_TRUE(same_bits(five->planes, originals[5].planes));
    EXPECT_FALSE(store.in_memory(5));
    EXPECT_EQ(store.reads(), 2U);
    EXPECT_TRUE(store.in_memory(0) && store.in_memory(2) && store.in_memory(8));
  }
  // A scratch directory goes with the store.
  EXPECT_FALSE(fs::exists(dir));
}

// A spill that fails keeps the cloud in memory: the bound is lost for it, not the keyframe.
class FailingSpill final : public KeyframeSpill {
 public:
  void write(const BackendKeyframe& k) override {
    if (k.id % 2 == 0) throw std::runtime_error("disk full");
    written_.push_back(k);
  }
  BackendKeyframe read(std::uint64_t id) const override {
    for (const auto& k : written_) {
      if (k.id == id) return k;
    }
    throw std::runtime_error("never written");
  }

 private:
  std::vector<BackendKeyframe> written_;
};

TEST(KeyframeStore, KeepsWhatTheSpillCouldNotTake) {
  std::mt19937 rng(6);
  KeyframeStore store(2, std::make_shared<FailingSpill>());
  for (std::uint64_t i = 0; i < 8; ++i) store.add(random_keyframe(i, rng));
  EXPECT_EQ(store.spill_failures(), 4U);
  for (std::size_t k = 0; k < 8; ++k) {
    EXPECT_EQ(store.spilled(k), k % 2 == 1) << k;
    if (k % 2 == 0) {
      EXPECT_TRUE(store.in_memory(k)) << k;
    }
  }
  EXPECT_EQ(store.get(1)->id, 1U);
}

TEST(KeyframeStore, WithoutASpillEverythingStays) {
  std::mt19937 rng(7);
  KeyframeStore store(2, nullptr);
  for (std::uint64_t i = 0; i < 6; ++i) store.add(random_keyframe(i, rng));
  EXPECT_EQ(store.in_memory_count(), 6U);
  EXPECT_EQ(store.evictions(), 0U);
}

}  // namespace
