// The backend's state directory across runs, and `liod map export` from it: two replays into one
// directory keep both runs' keyframes, consistent with the graph; the exported map is a PCD that
// PCL reads, with finite points around the trajectory, thinned by --voxel.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <map>
#include <sstream>

#include "liod/backend/map_store.hpp"
#include "liod/daemon/map_export.hpp"
#include "pipeline_run.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"

using namespace liod;
using namespace liod::test;

namespace {

Config persisting_config(const std::filesystem::path& drive, const ScratchDir& state) {
  Config config = drive_config(drive);
  config.backend.enabled = true;
  config.backend.persist = true;
  config.output.state_dir = state.string();
  return config;
}

std::map<std::string, std::string> keyframe_files(const std::filesystem::path& state) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(state / "keyframes")) {
    std::ifstream in(entry.path(), std::ios::binary);
    files[entry.path().filename().string()] = std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return files;
}

pcl::PointCloud<pcl::PointXYZ> read_pcd(const std::filesystem::path& path) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  EXPECT_EQ(pcl::io::loadPCDFile(path.string(), cloud), 0) << path;
  return cloud;
}

}  // namespace

TEST(StateDir, TwoReplaysKeepBothRunsKeyframes) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const ScratchDir state("state-runs");
  const Config config = persisting_config(*drive, state);
  ASSERT_EQ(run_pipeline(config, *drive / "lidar.pcap", *drive / "imu.csv", 0.0).error, "");
  const PersistedState first = load_state(state.path());
  ASSERT_GT(first.keyframes.size(), 5U);
  const auto first_files = keyframe_files(state.path());
  ASSERT_EQ(first_files.size(), first.keyframes.size());

  ASSERT_EQ(run_pipeline(config, *drive / "lidar.pcap", *drive / "imu.csv", 0.0).error, "");
  const PersistedState both = load_state(state.path());
  const std::size_t n1 = first.keyframes.size();
  ASSERT_EQ(both.keyframes.size(), 2 * n1);  // the same drive twice, lockstep: as many keyframes
  // The first run's files are untouched, and the graph still names each with its run.
  const auto files = keyframe_files(state.path());
  for (const auto& [name, bytes] : first_files) EXPECT_EQ(files.at(name), bytes) << name;
  ASSERT_EQ(files.size(), both.keyframes.size());  // every file is named by the graph, once
  for (std::size_t i = 0; i < both.keyframes.size(); ++i) {
    EXPECT_EQ(both.runs[i], i < n1 ? 0U : 1U) << i;
    EXPECT_EQ(files.count(std::to_string(both.keyframes[i].id) + ".kf"), 1U) << i;
    if (i < n1) {
      EXPECT_EQ(both.keyframes[i].id, first.keyframes[i].id);
      EXPECT_TRUE(both.poses[i].isApprox(first.poses[i]));
    } else {
      EXPECT_GT(both.keyframes[i].id, first.keyframes.back().id);
      // The same drive: the second run's keyframe sits where the first run's did.
      EXPECT_LT((both.poses[i].translation() - first.poses[i - n1].translation()).norm(), 0.05) << i;
    }
  }
  for (const auto& f : both.factors) EXPECT_EQ(both.runs[f.from], both.runs[f.to]);
}

TEST(StateDir, MapExportWritesAPcdAroundTheTrajectory) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const ScratchDir state("state-export");
  const Config config = persisting_config(*drive, state);
  ASSERT_EQ(run_pipeline(config, *drive / "lidar.pcap", *drive / "imu.csv", 0.0).error, "");
  const PersistedGraph graph = load_graph(state.path());
  ASSERT_GT(graph.nodes.size(), 5U);

  std::ostringstream log;
  ASSERT_EQ(run_map_export({state.string(), (state / "all.pcd").string(), 0.0}, log), 0) << log.str();
  ASSERT_EQ(run_map_export({state.string(), (state / "coarse.pcd").string(), 2.0}, log), 0) << log.str();
  const auto all = read_pcd(state / "all.pcd");
  const auto coarse = read_pcd(state / "coarse.pcd");
  ASSERT_GT(all.size(), 1000U);
  EXPECT_GT(coarse.size(), 0U);
  EXPECT_LT(coarse.size(), all.size() / 2);
  const double range = config.odometry.max_range_m;
  for (const auto& p : all) {
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    const Eigen::Vector3d point(p.x, p.y, p.z);
    double nearest = 1e18;
    for (const auto& n : graph.nodes) nearest = std::min(nearest, (point - n.pose.translation()).norm());
    ASSERT_LT(nearest, range) << "a point " << nearest << " m from every keyframe";
  }
  // The run's own map.pcd, written at its end by the same writer, reads back too.
  EXPECT_GT(read_pcd(state / "map.pcd").size(), 0U);
}
