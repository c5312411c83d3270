// The map frame on the pose socket (docs/pose-protocol.md, protocol version 2): each pose carries
// the odometry-frame pose, unchanged by the backend, and the map-frame pose, the backend's latest
// correction T_map_odom applied, with the correction's sequence number.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "liod/daemon/replay.hpp"
#include "pipeline_run.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"
#include "simulated_drive.hpp"

using namespace liod;
using namespace liod::test;

namespace {

/// 70 s around a block at up to 15 m/s: the first lap ends after about 50 s, and the backend
/// closes loops from then on.
const std::filesystem::path* loop_drive() {
  static const std::filesystem::path dir =
      cached_drive_dir("loop-drive", "--route loop --seed 5 --duration 70 --max-speed 15");
  return dir.empty() ? nullptr : &dir;
}

Eigen::Isometry3d odometry_pose(const pose::PoseMessage& m) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = m.orientation.toRotationMatrix();
  t.translation() = m.position;
  return t;
}

Eigen::Isometry3d map_pose(const pose::PoseMessage& m) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = m.map_orientation.toRotationMatrix();
  t.translation() = m.map_position;
  return t;
}

/// The replay's scan-rate trajectory; with the backend on, corrected by the optimised graph at the end.
std::vector<TumPose> replayed(const std::filesystem::path& drive, const ScratchDir& dir, bool backend) {
  Config config = drive_config(drive);
  config.backend.enabled = backend;
  ReplayOptions o;
  o.pcap = (drive / "lidar.pcap").string();
  o.imu_csv = (drive / "imu.csv").string();
  o.trajectory_tum = (dir / (backend ? "corrected.tum" : "plain.tum")).string();
  std::ostringstream out;
  EXPECT_EQ(run_replay(config, o, out), 0) << out.str();
  return read_tum(o.trajectory_tum);
}

}  // namespace

TEST(MapFrame, CorrectionsReachEveryPoseAndLeaveTheOdometryFrameAlone) {
  LIOD_REQUIRE_SIM();
  const auto* drive = loop_drive();
  ASSERT_NE(drive, nullptr) << "liod-sim failed: see " << (drive_tree() / "test-data/loop-drive/sim.log");
  const ScratchDir dir("map-frame");
  const auto plain = replayed(*drive, dir, false);
  const auto corrected = replayed(*drive, dir, true);
  ASSERT_GT(plain.size(), 600U);

  Config config = drive_config(*drive);
  config.backend.enabled = true;
  const PipelineRun run = run_pipeline(config, *drive / "lidar.pcap", *drive / "imu.csv", 0.0);
  ASSERT_EQ(run.error, "");

  std::map<std::uint32_t, Eigen::Isometry3d> corrections;  // T_map_odom of each sequence number
  std::uint32_t last_sequence = 0;
  std::size_t scans = 0, inconsistent = 0, not_localized = 0;
  for (const auto& p : run.poses) {
    const auto& m = p.event.message;
    not_localized += (m.flags & pose::kNotLocalized) != 0;
    const Eigen::Isometry3d t = map_pose(m) * odometry_pose(m).inverse();
    const auto [it, added] = corrections.emplace(m.correction_sequence, t);
    if (!added && !(it->second.translation() - t.translation()).isZero(1e-6)) ++inconsistent;
    if (m.type != pose::MessageType::ScanPose) continue;
    EXPECT_GE(m.correction_sequence, last_sequence) << "a scan pose at " << m.time;
    last_sequence = m.correction_sequence;
    // The odometry frame is the replay's without a backend.
    ASSERT_LT(scans, plain.size());
    EXPECT_NEAR(m.time, plain[scans].t, 1e-6);
    EXPECT_NEAR(m.position.x(), plain[scans].x, 1e-5) << "scan " << scans;
    EXPECT_NEAR(m.position.y(), plain[scans].y, 1e-5) << "scan " << scans;
    ++scans;
  }
  EXPECT_EQ(scans, plain.size());
  EXPECT_EQ(not_localized, 0U);
  EXPECT_EQ(inconsistent, 0U) << "poses with one correction sequence number but different corrections";
  EXPECT_TRUE(corrections.at(0).isApprox(Eigen::Isometry3d::Identity(), 1e-12)) << "before the first loop";
  ASSERT_GE(last_sequence, 3U) << "the backend closed no loops";

  // Once the loops are closed, the map frame is the replay's corrected trajectory.
  double worst_m = 0.0, largest_correction_m = 0.0;
  std::size_t compared = 0;
  for (const auto& [sequence, t] : corrections) largest_correction_m = std::max(largest_correction_m, t.translation().norm());
  for (const auto& p : run.poses) {
    const auto& m = p.event.message;
    if (m.type != pose::MessageType::ScanPose || m.correction_sequence != last_sequence) continue;
    for (const auto& c : corrected) {
      if (std::abs(c.t - m.time) > 1e-6) continue;
      worst_m = std::max(worst_m, (m.map_position - Eigen::Vector3d(c.x, c.y, c.z)).norm());
      ++compared;
    }
  }
  const double last_correction_m = corrections.at(last_sequence).translation().norm();
  std::printf("[ map ] %u corrections (largest %.3f m, the last %.3f m); %zu scan poses after the last: within %.3f m "
              "of the replay's corrected trajectory\n", last_sequence, largest_correction_m, last_correction_m, compared, worst_m);
  EXPECT_GT(compared, 0U);
  EXPECT_LT(worst_m, 0.05);
  // The simulated odometry drifts little, so the corrections are small: the map frame must still be
  // nearer the corrected trajectory than the odometry frame is (by the correction).
  EXPECT_LT(worst_m, 0.5 * last_correction_m);
}

// Without a backend the map frame is the odometry frame, and says so.
TEST(MapFrame, WithoutABackendPosesAreNotLocalized) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const Config config = drive_config(*drive);
  const PipelineRun run = run_pipeline(config, *drive / "lidar.pcap", *drive / "imu.csv", 0.0);
  ASSERT_EQ(run.error, "");
  ASSERT_FALSE(run.poses.empty());
  for (const auto& p : run.poses) {
    const auto& m = p.event.message;
    ASSERT_NE(m.flags & pose::kNotLocalized, 0U);
    ASSERT_EQ(m.correction_sequence, 0U);
    ASSERT_EQ(m.map_position, m.position);
  }
}
