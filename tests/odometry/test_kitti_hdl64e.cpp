// KITTI raw acceptance (issue 58): a simulated HDL-64E drive in KITTI raw's layout, replayed with
// `liod replay --kitti-raw` and scored against its OXTS extract as liod-eval reads it, against the
// same route driven with the RS-Helios (same seed, so the same world, trajectory, mounting and IMU
// samples: the Helios drive's IMU at the OXTS extract's 100 Hz). The HDL-64E's ATE and KITTI drift
// must be within twice the Helios's. The drives: `liod-sim --route urban --seed 1 --duration 10
// --max-speed 12`, with `--lidar hdl64e` and with `--imu-rate 100`.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "liod/config.hpp"
#include "liod/daemon/replay.hpp"
#include "liod/eval/evaluate.hpp"
#include "liod/eval/io.hpp"
#include "liod/eval/oxts.hpp"
#include "simulated_drive.hpp"
#include "test_env.hpp"

namespace {

namespace fs = std::filesystem;

constexpr const char* kRoute = "--route urban --seed 1 --duration 10 --max-speed 12";
// liod-sim's KITTI layout of seed 1 from its default epoch (1700000000: 2023-11-14).
constexpr const char* kDrive = "2023_11_14/2023_11_14_drive_0001_extract";

struct Score {
  double ate_m = 0.0;
  double drift_pct = 0.0;
  std::size_t poses = 0;
};

Score score(const liod::eval::Trajectory& gt, const std::string& est) {
  const auto r = liod::eval::evaluate(gt, liod::eval::read_tum(est), liod::eval::EvalOptions{});
  EXPECT_TRUE(r.kitti.translational_pct.has_value()) << "no 100 m segment in " << est;
  return {r.ate.translation.rmse, r.kitti.translational_pct.value_or(1e9), r.est_poses};
}

liod::Config config(const std::vector<std::string>& extra) {
  std::vector<std::string> files = {std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml",
                                    std::string(LIOD_SOURCE_DIR) + "/config/vehicles/liod-sim-car.yaml"};
  files.insert(files.end(), extra.begin(), extra.end());
  return liod::load_config(files);
}

TEST(KittiHdl64e, SimulatedKittiRawDriveScoresWithinTwiceTheHeliosOnTheSameRoute) {
  LIOD_REQUIRE_SIM();
  const fs::path kitti = liod::test::cached_drive_dir("kitti_hdl64e_urban_s1", std::string("--lidar hdl64e ") + kRoute);
  const fs::path helios = liod::test::cached_drive_dir("helios_urban_s1_imu100", std::string("--imu-rate 100 ") + kRoute);
  ASSERT_FALSE(kitti.empty()) << "liod-sim failed to write the KITTI drive";
  ASSERT_FALSE(helios.empty()) << "liod-sim failed to write the Helios drive";
  const fs::path drive = kitti / kDrive;

  // The OXTS extract read as the devkit converts it is the simulator's own truth, relative to the
  // first pose: the Mercator round trip and the Euler angles lose nothing that matters.
  const auto oxts = liod::eval::read_oxts(drive.string());
  const auto truth = liod::eval::read_tum((kitti / "groundtruth.tum").string());
  ASSERT_EQ(oxts.size(), truth.size());
  double worst_m = 0.0;
  double worst_deg = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const Eigen::Isometry3d rel = truth.poses.front().inverse() * truth.poses[i];
    worst_m = std::max(worst_m, (rel.translation() - oxts.poses[i].translation()).norm());
    worst_deg = std::max(worst_deg, liod::eval::rotation_angle(rel.linear().transpose() * oxts.poses[i].linear()) * 57.29578);
    ASSERT_NEAR(oxts.stamps[i], truth.stamps[i], 1e-6);
  }
  EXPECT_LT(worst_m, 2e-4);
  EXPECT_LT(worst_deg, 1e-4);

  liod::ReplayOptions k;
  k.kitti_raw = drive.string();
  k.trajectory_tum = (kitti / "test_odometry.tum").string();
  std::ostringstream k_out;
  ASSERT_EQ(liod::run_replay(config({}), k, k_out), 0) << k_out.str();
  EXPECT_NE(k_out.str().find("sweeps: 99 of 99 read, 0 returns"), std::string::npos) << k_out.str();

  liod::ReplayOptions h;
  h.pcap = (helios / "lidar.pcap").string();
  h.imu_csv = (helios / "imu.csv").string();
  h.trajectory_tum = (helios / "test_odometry.tum").string();
  std::ostringstream h_out;
  ASSERT_EQ(liod::run_replay(config({(helios / "extrinsics.yaml").string()}), h, h_out), 0) << h_out.str();

  const Score hdl = score(oxts, k.trajectory_tum);
  const Score rs = score(liod::eval::read_tum((helios / "groundtruth.tum").string()), h.trajectory_tum);
  std::printf("OXTS against the truth: %.2g m, %.2g deg at most\n", worst_m, worst_deg);
  std::printf("HDL-64E, KITTI raw: %zu poses, ATE %.4f m, KITTI drift %.3f %%\n", hdl.poses, hdl.ate_m, hdl.drift_pct);
  std::printf("RS-Helios, pcap:    %zu poses, ATE %.4f m, KITTI drift %.3f %%\n", rs.poses, rs.ate_m, rs.drift_pct);
  EXPECT_GE(hdl.poses, 95U);
  EXPECT_LE(hdl.ate_m, 2.0 * rs.ate_m);
  EXPECT_LE(hdl.drift_pct, 2.0 * rs.drift_pct);
}

}  // namespace
