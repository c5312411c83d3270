// A busy backend must neither get the daemon restarted by the watchdog nor touch the odometry:
// it sheds keyframes (no loop check) when it falls behind, and a long unit of its work counts as
// progress up to threads.backend_work_limit_s (heartbeat.hpp).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <thread>

#include "liod/daemon/heartbeat.hpp"
#include "pipeline_run.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"

using namespace liod;
using namespace liod::test;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

/// Sleeps `seconds` in small steps while `slow` holds.
void sleep_while(const std::atomic<bool>& slow, double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (slow.load() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

}  // namespace

// Every keyframe's backend work takes 3 s (a loop check on a loaded machine, a slow disk's
// fsync), half as long again as the 2 s the watchdog allows a silent thread, while the drive plays
// live; the watchdog's view of the threads is polled every 100 ms, as `liod run` does, for 30 s:
// the 8 s drive plays at about a quarter of its recorded pace. (The
// odometry itself must keep the pace for its poses to equal the replay's, and a test machine
// running other tests beside this one leaves it less than the vehicle's computer does.)
TEST(BackendLoad, SlowBackendNeitherStallsTheWatchdogNorTouchesTheOdometry) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto ref = read_tum(reference_replay(*drive) / "scan.tum");
  ASSERT_GT(ref.size(), 50U);
  const ScratchDir state("backend-load");
  Config config = drive_config(*drive);
  config.backend.enabled = true;
  config.output.state_dir = state.string();
  config.time.imu_wait_s = 2.0;  // a loaded test machine: the IMU file source may lag the LiDAR's
  config.threads.scan_max_lag_s = 3600.0;  // every scan compared: no skipping on a slow test machine
  std::atomic<bool> slow{true};
  std::atomic<int> slow_units{0};
  std::vector<std::string> stalls;
  const double kPace = (ref.back().t - ref.front().t) / 30.0;
  const double drive_s = (ref.back().t - ref.front().t) / kPace;
  const auto started = std::chrono::steady_clock::now();
  const PipelineRun run = run_pipeline(
      config, *drive / "lidar.pcap", *drive / "imu.csv", kPace,
      [&](PipelineOptions& po) {
        po.backend.before_work = [&](const Keyframe&) {
          if (slow.load()) ++slow_units;
          sleep_while(slow, 3.0);
        };
      },
      [&](Pipeline& p) {
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        // While the file sources play (a live source never ends; a file's thread stops beating).
        if (elapsed < drive_s) {
          for (const auto& name : p.stalled(std::chrono::milliseconds(2000))) stalls.push_back(name);
        }
        // After the drive the backend may work fast: the test then ends within seconds.
        if (elapsed > drive_s + 3.0) slow = false;
      });
  ASSERT_EQ(run.error, "");
  std::printf("[ backend ] %d keyframes took 3 s each; health %s\n", slow_units.load(),
              run.health.substr(run.health.find("\"backend\"")).c_str());
  EXPECT_GE(slow_units.load(), 8);  // 30 s of 3 s units
  EXPECT_TRUE(stalls.empty()) << stalls.size() << " stalled observations, first: " << (stalls.empty() ? "" : stalls.front());
  EXPECT_EQ(run.health.find("\"keyframes_shed\":0,"), std::string::npos) << run.health;
  EXPECT_NE(run.health.find("\"keyframes_shed\":"), std::string::npos) << run.health;

  // The odometry's poses are those of a replay without any backend.
  std::vector<const pose::PoseMessage*> scans;
  for (const auto& p : run.poses) {
    if (p.event.message.type == pose::MessageType::ScanPose) scans.push_back(&p.event.message);
  }
  ASSERT_EQ(scans.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) {
    ASSERT_NEAR(ref[i].t, scans[i]->time, 1e-6) << "scan " << i;
    EXPECT_NEAR(ref[i].x, scans[i]->position.x(), 1e-5) << "scan " << i;
    EXPECT_NEAR(ref[i].y, scans[i]->position.y(), 1e-5) << "scan " << i;
    EXPECT_NEAR(ref[i].z, scans[i]->position.z(), 1e-5) << "scan " << i;
  }
}

// The watchdog's judgement over a minute of backend work at 5 s per keyframe, on a synthetic
// clock, checked every 100 ms as `liod run` does: never stalled. A unit that does not end within
// the work limit, or a loop that stops beating, is.
TEST(Heartbeat, LongUnitsOfWorkAreProgressUpToTheWorkLimit) {
  const std::int64_t beat_limit = 2 * kSecond;
  const std::int64_t work_limit = 60 * kSecond;
  Heartbeat hb;
  std::int64_t now = 1000 * kSecond;
  hb.beat(now);
  int stalled = 0;
  for (int unit = 0; unit < 12; ++unit) {  // 12 keyframes x 5 s
    hb.begin_work(now);
    for (int tick = 0; tick < 50; ++tick) {
      now += kSecond / 10;
      stalled += hb.stalled(now, beat_limit, work_limit);
    }
    EXPECT_NEAR(hb.busy_s(now), 5.0, 1e-9);
    hb.end_work(now);
    EXPECT_EQ(hb.busy_s(now), 0.0);
  }
  EXPECT_EQ(stalled, 0);

  hb.begin_work(now);  // hung in a unit of work
  EXPECT_FALSE(hb.stalled(now + work_limit, beat_limit, work_limit));
  EXPECT_TRUE(hb.stalled(now + work_limit + 1, beat_limit, work_limit));
  hb.end_work(now + kSecond);  // idle and beating: the short limit applies again
  EXPECT_FALSE(hb.stalled(now + 3 * kSecond, beat_limit, work_limit));
  EXPECT_TRUE(hb.stalled(now + 3 * kSecond + 1, beat_limit, work_limit));
}
