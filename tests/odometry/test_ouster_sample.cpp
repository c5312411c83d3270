// The real Ouster OS1-128 sample (shared/data/ouster): three sweeps from a car under way at about
// 2.5 m/s, read through the point-cloud path (rings from elevation, the sensor's per-point time)
// and registered pairwise with the IMU's prediction (sweep_registration.hpp). The motion between
// sweeps must agree with the reference poses that ship with the sample (the Ouster SDK's own
// estimate, not ground truth) within 5 cm.

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>

#include "liod/drivers/cloud_sweep.hpp"
#include "liod/drivers/ouster_sample.hpp"
#include "liod/sweep_registration.hpp"
#include "test_env.hpp"

namespace {

namespace fs = std::filesystem;
using liod::Pose;

fs::path ouster_dir() { return liod::test::shared_dir() / "data" / "ouster"; }

/// KITTI pose lines: row-major 3x4 [R | t].
std::vector<Pose> read_kitti_poses(const fs::path& path) {
  std::ifstream in(path);
  std::vector<Pose> poses;
  std::array<double, 12> v{};
  while (in >> v[0]) {
    for (std::size_t i = 1; i < v.size(); ++i) in >> v[i];
    Eigen::Matrix3d r;
    r << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    poses.push_back({Eigen::Quaterniond(r).normalized(), Eigen::Vector3d(v[3], v[7], v[11])});
  }
  return poses;
}

struct Sample {
  liod::drivers::OusterMetadata metadata;
  std::vector<liod::Scan> scans;
  std::vector<liod::ImuSample> imu;
  std::vector<liod::drivers::CloudScanStats> stats;
};

Sample load_sample() {
  Sample s;
  s.metadata = liod::drivers::read_ouster_metadata(ouster_dir() / "raw" / "OS-1-128_v2.3.0_1024x10.json");
  const auto frames = liod::drivers::read_ouster_frame_list(ouster_dir() / "frames.csv");
  const auto config = s.metadata.cloud_config();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    liod::drivers::CloudScanStats stats;
    s.scans.push_back(liod::drivers::make_scan(liod::drivers::read_ouster_frame(frames[i], i), config, &stats));
    s.stats.push_back(stats);
  }
  s.imu = liod::drivers::read_ouster_imu(ouster_dir() / "imu.csv");
  return s;
}

liod::SweepRegistration make_registration(const Sample& s) {
  liod::FrontEndConfig front;
  const Eigen::Isometry3d to_imu = s.metadata.sensor_to_imu();
  front.extrinsics.lidar_to_imu_rotation = Eigen::Quaterniond(to_imu.linear());
  front.extrinsics.lidar_to_imu_translation = to_imu.translation();
  liod::SweepRegistration registration(liod::sweep_registration_config(front));
  for (const auto& sample : s.imu) registration.add_imu(sample);
  return registration;
}

TEST(OusterSample, RingsFromElevationFollowEachColumnsBeams) {
  LIOD_REQUIRE_SHARED(ouster_dir() / "frames.csv");
  const Sample s = load_sample();
  ASSERT_EQ(s.scans.size(), 3U);
  for (std::size_t i = 0; i < s.scans.size(); ++i) {
    const liod::Scan& scan = s.scans[i];
    EXPECT_EQ(scan.beam_count, 128);
    EXPECT_LT(s.stats[i].no_beam, s.stats[i].points_in / 1000) << "sweep " << i << ": returns off every beam";
    // A column's returns come top beam first (the decoder's order, kept by the stable sort on
    // time): its rings must fall strictly, one beam's elevation at a time.
    std::size_t steps = 0;
    std::size_t falling = 0;
    for (std::size_t k = 1; k < scan.points.size(); ++k) {
      if (scan.points[k].time != scan.points[k - 1].time) continue;
      ++steps;
      if (scan.points[k].ring < scan.points[k - 1].ring) ++falling;
    }
    EXPECT_GT(steps, scan.points.size() / 2);
    EXPECT_GT(static_cast<double>(falling), 0.999 * static_cast<double>(steps)) << "sweep " << i;
  }
}

TEST(OusterSample, ConsecutiveSweepsMoveAsTheReferencePoses) {
  LIOD_REQUIRE_SHARED(ouster_dir() / "frames.csv");
  const Sample s = load_sample();
  const auto reference = read_kitti_poses(ouster_dir() / "raw" / "OS-1-128_v2.3.0_1024x10_lb_n3_poses_kitti.txt");
  ASSERT_EQ(reference.size(), 3U);
  const liod::SweepRegistration registration = make_registration(s);
  for (std::size_t i = 0; i + 1 < s.scans.size(); ++i) {
    const auto motion = registration.register_pair(s.scans[i], s.scans[i + 1]);
    ASSERT_TRUE(motion.has_value()) << "pair " << i;
    const Pose expected = reference[i].inverse() * reference[i + 1];
    const Eigen::Vector3d error = motion->lidar.translation - expected.translation;
    const double angle_deg = Eigen::AngleAxisd(motion->lidar.rotation.conjugate() * expected.rotation).angle() * 180.0 / M_PI;
    std::printf("sweeps %zu-%zu: liod (%.4f, %.4f, %.4f) m, reference (%.4f, %.4f, %.4f) m, difference %.4f m, "
                "%.3f deg; speed %.3f m/s, %d rounds, %d residuals, rms %.4f m\n",
                i, i + 1, motion->lidar.translation.x(), motion->lidar.translation.y(), motion->lidar.translation.z(),
                expected.translation.x(), expected.translation.y(), expected.translation.z(), error.norm(), angle_deg,
                motion->velocity_body.norm(), motion->rounds, motion->residuals, motion->rms_residual_m);
    EXPECT_LT(error.norm(), 0.05) << "pair " << i;
    EXPECT_LT(angle_deg, 0.5) << "pair " << i;
    EXPECT_GT(motion->lidar.translation.norm(), 0.2) << "pair " << i << ": the car is under way";
    EXPECT_EQ(motion->degenerate_directions, 0);
  }
}

}  // namespace
