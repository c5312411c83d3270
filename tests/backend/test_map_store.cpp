// State persistence: round trip, corrupt/partial files named in the error, a crash mid-write
// (temp file left behind) still loads the last good state, and SIGKILL at random points during
// repeated saves always leaves a loadable directory.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "liod/backend/map_store.hpp"
#include "scratch_dir.hpp"

namespace {

namespace fs = std::filesystem;
using namespace liod;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = liod::test::program_scratch_dir() / name;
  fs::remove_all(dir);
  return dir;
}

struct Fixture {
  std::vector<BackendKeyframe> keyframes;
  PoseGraph graph;
};

void grow(Fixture& f, std::size_t n) {
  for (std::size_t i = f.keyframes.size(); i < n; ++i) {
    BackendKeyframe k;
    k.id = 10 + i;
    k.time = 0.5 * static_cast<double>(i);
    k.odometry_pose.translation() = Eigen::Vector3d(static_cast<double>(i), 0.5, 0.0);
    for (int j = 0; j < 200; ++j) k.planes.emplace_back(static_cast<float>(j), static_cast<float>(i), 1.0F);
    k.edges.emplace_back(1.0F, 2.0F, 3.0F);
    k.similarity.emplace_back(4.0F, 5.0F, 6.0F);
    f.keyframes.push_back(k);
    f.graph.add_node(k.odometry_pose);
    if (i > 0) {
      PoseGraphFactor factor;
      factor.from = i - 1;
      factor.to = i;
      factor.measured.translation() = Eigen::Vector3d(1, 0, 0);
      factor.information = relative_pose_information(0.05, 0.01);
      factor.loop = i % 7 == 0;
      f.graph.add_factor(factor);
    }
  }
}

TEST(MapStore, RoundTrip) {
  const fs::path dir = fresh_dir("roundtrip");
  Fixture f;
  grow(f, 5);
  StateWriter writer(dir);
  writer.save(f.keyframes, f.graph);
  grow(f, 9);
  writer.save(f.keyframes, f.graph);
  const PersistedState s = load_state(dir);
  ASSERT_EQ(s.keyframes.size(), 9U);
  ASSERT_EQ(s.poses.size(), 9U);
  ASSERT_EQ(s.factors.size(), 8U);
  for (std::size_t i = 0; i < 9; ++i) {
    EXPECT_EQ(s.keyframes[i].id, f.keyframes[i].id);
    EXPECT_EQ(s.keyframes[i].time, f.keyframes[i].time);
    EXPECT_EQ(s.keyframes[i].planes, f.keyframes[i].planes);
    EXPECT_TRUE(s.poses[i].isApprox(f.graph.pose(i)));
  }
  EXPECT_EQ(s.factors[6].loop, true);
  EXPECT_TRUE(s.factors[3].information.isApprox(f.graph.factors()[3].information));
  fs::remove_all(dir);
}

TEST(MapStore, PartialTempFileAfterACrashLoadsTheLastGoodState) {
  const fs::path dir = fresh_dir("crash");
  Fixture f;
  grow(f, 4);
  StateWriter(dir).save(f.keyframes, f.graph);
  // The crash: the next save died while writing graph.bin.tmp and a keyframe's temp file.
  {
    std::ofstream(dir / "graph.bin.tmp", std::ios::binary) << "LIODGRF1\x01\x00\x00";
    std::ofstream(dir / "keyframes" / "14.kf.tmp", std::ios::binary) << "LIODK";
  }
  const PersistedState s = load_state(dir);
  EXPECT_EQ(s.keyframes.size(), 4U);
  // A new writer clears the debris and continues.
  StateWriter writer(dir);
  EXPECT_FALSE(fs::exists(dir / "graph.bin.tmp"));
  grow(f, 6);
  writer.save(f.keyframes, f.graph);
  EXPECT_EQ(load_state(dir).keyframes.size(), 6U);
  fs::remove_all(dir);
}

TEST(MapStore, CorruptOrMissingFilesAreNamed) {
  const fs::path dir = fresh_dir("corrupt");
  EXPECT_THROW(load_state(dir), StateError);
  Fixture f;
  grow(f, 3);
  StateWriter(dir).save(f.keyframes, f.graph);
  auto expect_error = [&](const std::string& needle) {
    try {
      load_state(dir);
      ADD_FAILURE() << "no error, expected " << needle;
    } catch (const StateError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  // A flipped byte in graph.bin.
  const fs::path graph = dir / "graph.bin";
  std::string bytes;
  {
    std::ifstream in(graph, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::string flipped = bytes;
  flipped[40] = static_cast<char>(flipped[40] ^ 0x5A);
  std::ofstream(graph, std::ios::binary | std::ios::trunc) << flipped;
  expect_error("graph.bin: checksum mismatch");
  // Truncated.
  std::ofstream(graph, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
  expect_error("graph.bin");
  // Intact graph, but a keyframe it lists is gone.
  std::ofstream(graph, std::ios::binary | std::ios::trunc) << bytes;
  EXPECT_NO_THROW(load_state(dir));
  fs::remove(dir / "keyframes" / "11.kf");
  expect_error("11.kf: missing");
  fs::remove_all(dir);
}

TEST(MapStore, SigkillDuringSavesAlwaysLeavesALoadableState) {
  const fs::path dir = fresh_dir("sigkill");
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> delay_us(0, 30000);
  std::size_t last_loaded = 0;
  for (int round = 0; round < 15; ++round) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      // The child saves a growing state as fast as it can until it is killed.
      Fixture f;
      StateWriter writer(dir);
      for (std::size_t n = 1;; ++n) {
        grow(f, n);
        writer.save(f.keyframes, f.graph);
      }
    }
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us(rng) + 2000));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    if (!fs::exists(dir / "graph.bin")) continue;  // killed before the first commit
    PersistedState s;
    ASSERT_NO_THROW(s = load_state(dir)) << "round " << round;
    EXPECT_EQ(s.keyframes.size(), s.poses.size());
    last_loaded = s.keyframes.size();
  }
  EXPECT_GT(last_loaded, 0U);
  fs::remove_all(dir);
}

}  // namespace
