// State persistence: round trip, crash debris ignored, corrupt/missing files named, runs that
// share a directory keep each other's keyframes, and SIGKILL at random points during repeated
// runs' saves always leaves a loadable directory that never loses a commit.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "state_fixture.hpp"

namespace {

namespace fs = std::filesystem;
using namespace liod;
using liod::test::fresh_state_dir;
using liod::test::read_bytes;
using liod::test::StateFixture;
using liod::test::write_bytes;

TEST(MapStore, RoundTrip) {
  const fs::path dir = fresh_state_dir("roundtrip");
  StateFixture f;
  f.first_id = 10;
  test::grow(f, 5);
  StateWriter writer(dir);
  writer.save(f.keyframes, f.graph);
  test::grow(f, 9);
  test::bend(f, 3, 0.25);
  writer.save(f.keyframes, f.graph);
  writer.flush();
  const PersistedState s = load_state(dir);
  ASSERT_EQ(s.keyframes.size(), 9U);
  ASSERT_EQ(s.poses.size(), 9U);
  ASSERT_EQ(s.factors.size(), 8U);
  for (std::size_t i = 0; i < 9; ++i) {
    EXPECT_EQ(s.keyframes[i].id, f.keyframes[i].id);
    EXPECT_EQ(s.keyframes[i].time, f.keyframes[i].time);
    EXPECT_EQ(s.keyframes[i].planes, f.keyframes[i].planes);
    EXPECT_TRUE(s.poses[i].isApprox(f.graph.pose(i))) << i;
    EXPECT_EQ(s.runs[i], 0U);
  }
  EXPECT_EQ(s.factors[6].loop, true);
  EXPECT_EQ(s.factors[6].from, 6U);
  EXPECT_TRUE(s.factors[3].information.isApprox(f.graph.factors()[3].information));
  EXPECT_TRUE(s.notes.empty());
  fs::remove_all(dir);
}

TEST(MapStore, PartialTempFilesAfterACrashAreIgnoredAndCleared) {
  const fs::path dir = fresh_state_dir("crash");
  StateFixture f;
  test::grow(f, 4);
  StateWriter(dir).save(f.keyframes, f.graph);
  // The crash: a compaction died while writing its temp files, and a keyframe's temp file.
  write_bytes(dir / "graph.bin.tmp", std::string("LIODGRF1\x02\x00\x00", 7));
  write_bytes(dir / "journal.bin.tmp", "LIODJ");
  write_bytes(dir / "keyframes" / "4.kf.tmp", "LIODK");
  EXPECT_EQ(load_state(dir).keyframes.size(), 4U);
  // A new run clears the debris and continues after the first run's ids.
  StateWriter writer(dir);
  EXPECT_FALSE(fs::exists(dir / "graph.bin.tmp"));
  EXPECT_FALSE(fs::exists(dir / "keyframes" / "4.kf.tmp"));
  EXPECT_EQ(writer.first_keyframe_id(), 4U);
  EXPECT_EQ(writer.run(), 1U);
  StateFixture second;
  second.first_id = writer.first_keyframe_id();
  test::grow(second, 2);
  writer.save(second.keyframes, second.graph);
  writer.flush();
  EXPECT_EQ(load_state(dir).keyframes.size(), 6U);
  fs::remove_all(dir);
}

TEST(MapStore, CorruptOrMissingFilesAreNamed) {
  const fs::path dir = fresh_state_dir("corrupt");
  EXPECT_THROW(load_state(dir), StateError);
  StateFixture f;
  f.first_id = 10;
  test::grow(f, 3);
  {
    StateWriter writer(dir);
    writer.save(f.keyframes, f.graph);
  }
  auto expect_error = [&](const std::string& needle) {
    try {
      load_state(dir);
      ADD_FAILURE() << "no error, expected " << needle;
    } catch (const StateError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  EXPECT_NO_THROW(load_state(dir));
  fs::remove(dir / "keyframes" / "11.kf");
  expect_error("11.kf: missing");
  // A snapshot (a run whose writer compacts at once) with a flipped byte.
  const fs::path other = fresh_state_dir("corrupt-snapshot");
  {
    StateWriter writer(other, StateWriterOptions{0.0, 0});
    writer.save(f.keyframes, f.graph);
  }
  ASSERT_TRUE(fs::exists(other / "graph.bin"));
  std::string bytes = read_bytes(other / "graph.bin");
  bytes[40] = static_cast<char>(bytes[40] ^ 0x5A);
  write_bytes(other / "graph.bin", bytes);
  try {
    load_state(other);
    ADD_FAILURE() << "a flipped byte in graph.bin loaded";
  } catch (const StateError& e) {
    EXPECT_NE(std::string(e.what()).find("graph.bin: checksum mismatch"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
  fs::remove_all(other);
}

// Two runs into one directory: the second run's ids continue after the first's, both runs'
// keyframe files stay as written, and the graph names every one of them with its run.
TEST(MapStore, RunsSharingADirectoryKeepEachOthersKeyframes) {
  const fs::path dir = fresh_state_dir("runs");
  StateFixture first;
  test::grow(first, 6);
  {
    StateWriter writer(dir);
    writer.save(first.keyframes, first.graph);
  }
  const std::string first_file = read_bytes(dir / "keyframes" / "0.kf");
  StateFixture second;
  {
    StateWriter writer(dir);
    EXPECT_EQ(writer.graph().nodes.size(), 6U);
    second.first_id = writer.first_keyframe_id();
    second.points = 50;
    test::grow(second, 4);
    writer.save(second.keyframes, second.graph);
  }
  EXPECT_EQ(second.first_id, 6U);
  EXPECT_EQ(read_bytes(dir / "keyframes" / "0.kf"), first_file);
  const PersistedState s = load_state(dir);
  ASSERT_EQ(s.keyframes.size(), 10U);
  ASSERT_EQ(s.factors.size(), 5U + 3U);
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(s.keyframes[i].id, i);
    EXPECT_EQ(s.runs[i], i < 6 ? 0U : 1U);
    EXPECT_EQ(s.keyframes[i].planes.size(), i < 6 ? 200U : 50U);
  }
  // The second run's factors join its own nodes only.
  for (std::size_t k = 5; k < s.factors.size(); ++k) EXPECT_GE(s.factors[k].from, 6U);
  // A keyframe file that no graph names (a run that died before its first commit) is not reused.
  write_bytes(dir / "keyframes" / "25.kf", "debris of a run that died");
  EXPECT_EQ(StateWriter(dir).first_keyframe_id(), 26U);
  fs::remove_all(dir);
}

TEST(MapStore, SigkillDuringSavesAlwaysLeavesALoadableState) {
  const fs::path dir = fresh_state_dir("sigkill");
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> delay_us(0, 30000);
  std::size_t last_loaded = 0;
  for (int round = 0; round < 15; ++round) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      // Each child is a run: it saves a growing state as fast as it can, compacting often, until
      // it is killed.
      StateWriter writer(dir, StateWriterOptions{1.0, 4096});
      StateFixture f;
      f.first_id = writer.first_keyframe_id();
      f.points = 20;
      for (std::size_t n = 1;; ++n) {
        test::grow(f, n);
        if (n % 5 == 0) test::bend(f, 4, 0.01);
        writer.save(f.keyframes, f.graph);
      }
    }
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us(rng) + 2000));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    if (!fs::exists(dir / "journal.bin")) continue;  // killed before the first commit
    PersistedState s;
    ASSERT_NO_THROW(s = load_state(dir)) << "round " << round;
    EXPECT_EQ(s.keyframes.size(), s.poses.size());
    // A kill is no power loss: every save that returned is in the files, and no run's start loses one.
    EXPECT_GE(s.keyframes.size(), last_loaded) << "round " << round;
    last_loaded = s.keyframes.size();
  }
  EXPECT_GT(last_loaded, 0U);
  fs::remove_all(dir);
}

}  // namespace
