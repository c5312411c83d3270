// `liod calibrate` on simulated drives whose true LiDAR-IMU extrinsic and clock offset are known
// (liod-sim's extrinsics.yaml) while liod is given a wrong one: the command recovers the truth,
// the odometry with its estimate is as accurate as with the truth, the daemon's start-up check
// flags the wrong config only, and a drive without turns is refused. One test per drive (each test is a process of its own under ctest).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <sys/wait.h>

#include <chrono>
#include <memory>
#include <thread>

#include "liod/config.hpp"
#include "liod/daemon/calibrate_command.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/pose_protocol.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/daemon/trajectory_writer.hpp"
#include "liod/eval/evaluate.hpp"
#include "liod/eval/io.hpp"
#include "scratch_dir.hpp"
#include "simulated_drive.hpp"
#include "test_env.hpp"

namespace {

namespace fs = std::filesystem;
constexpr double kRadPerDegree = 3.14159265358979323846 / 180.0;

std::vector<std::string> base_configs() {
  return {(liod::test::source_dir() / "config/liod.yaml").string(),
          (liod::test::source_dir() / "config/vehicles/liod-sim-car.yaml").string()};
}

liod::ExtrinsicsConfig load_extrinsics(const std::vector<fs::path>& extra) {
  auto files = base_configs();
  for (const auto& f : extra) files.push_back(f.string());
  return liod::load_config(files).extrinsics;
}

/// The truth turned by `angle_deg` about `axis`, moved by `translation` and its offset by `offset_s`.
void write_wrong_config(const fs::path& path, const liod::ExtrinsicsConfig& truth, const Eigen::Vector3d& axis,
                        double angle_deg, const Eigen::Vector3d& translation, double offset_s) {
  const Eigen::Quaterniond q = (Eigen::Quaterniond(Eigen::AngleAxisd(angle_deg * kRadPerDegree, axis.normalized())) *
                                truth.lidar_to_imu_rotation).normalized();
  const Eigen::Vector3d t = truth.lidar_to_imu_translation + translation;
  std::ofstream f(path);
  f << std::setprecision(12) << "extrinsics:\n  lidar_to_imu:\n    translation_m: [" << t.x() << ", " << t.y() << ", "
    << t.z() << "]\n    rotation_xyzw: [" << q.x() << ", " << q.y() << ", " << q.z() << ", " << q.w()
    << "]\n  lidar_time_offset_s: " << truth.lidar_time_offset_s + offset_s << "\n";
}

struct Calibrated {
  int exit_code = -1;
  std::string output;
};

Calibrated run_calibrate(const fs::path& drive, const fs::path& wrong, const fs::path& out) {
  std::string cmd = liod::test::built_program("liod").string() + " --log-level warn calibrate";
  for (const auto& c : base_configs()) cmd += " --config " + c;
  cmd += " --config " + wrong.string() + " --pcap " + (drive / "lidar.pcap").string() + " --imu " +
         (drive / "imu.csv").string() + " --out " + out.string() + " > " + out.string() + ".log 2>&1";
  const int status = std::system(cmd.c_str());
  Calibrated c;
  c.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream log(out.string() + ".log");
  std::ostringstream s;
  s << log.rdbuf();
  c.output = s.str();
  return c;
}

struct Replayed {
  double ate = 0.0;
  std::size_t suspect_scans = 0;  // scan poses flagged extrinsics_suspect
};

/// The drive through the pipeline as `liod replay` runs it, with the start-up check of the
/// extrinsics after `check_s` (the drives are a minute long, the default check comes at 60 s).
Replayed replay(const fs::path& drive, const std::vector<fs::path>& extrinsics, const fs::path& tum, double check_s) {
  auto files = base_configs();
  for (const auto& f : extrinsics) files.push_back(f.string());
  liod::Config config = liod::load_config(files);
  config.odometry.extrinsics_check_s = check_s;
  const std::vector<std::uint16_t> ports{static_cast<std::uint16_t>(config.lidar.msop_port),
                                         static_cast<std::uint16_t>(config.lidar.difop_port)};
  liod::PipelineOptions po;
  po.ordering = liod::Ordering::Lockstep;
  po.imu_rate_poses = false;
  po.realtime_threads = false;
  liod::Pipeline pipeline(config, po);
  liod::TrajectoryWriter writer(tum.string());
  Replayed r;
  pipeline.add_sink([&](const liod::PoseEvent& ev) {
    if (ev.message.type != liod::pose::MessageType::ScanPose) return;
    writer.write(ev.message.time, ev.message.position, ev.message.orientation);
    r.suspect_scans += (ev.message.flags & liod::pose::kExtrinsicsSuspect) != 0;
  });
  auto pace = std::make_shared<liod::PaceClock>();
  pipeline.start(std::make_unique<liod::PcapLidarSource>((drive / "lidar.pcap").string(), ports, pace),
                 std::make_unique<liod::CsvImuSource>((drive / "imu.csv").string(), pace));
  while (!pipeline.finished() && pipeline.error().empty()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  pipeline.join();
  EXPECT_EQ(pipeline.error(), "");
  EXPECT_TRUE(writer.close());
  r.ate = liod::eval::evaluate(liod::eval::read_tum((drive / "groundtruth.tum").string()), liod::eval::read_tum(tum.string()),
                               liod::eval::EvalOptions{})
              .ate.translation.rmse;
  return r;
}

/// The whole check on one drive: liod is given the truth off by `angle_deg` about `axis`,
/// `translation` and `offset_s`.
void check_drive(const fs::path& drive, const Eigen::Vector3d& axis, double angle_deg, const Eigen::Vector3d& translation,
                 double offset_s) {
  const liod::test::ScratchDir scratch("calibration");
  const fs::path truth_file = drive / "extrinsics.yaml";
  const liod::ExtrinsicsConfig truth = load_extrinsics({truth_file});
  const fs::path wrong = scratch.path() / "wrong.yaml";
  write_wrong_config(wrong, truth, axis, angle_deg, translation, offset_s);
  const fs::path fragment = scratch.path() / "extrinsics.yaml";

  const Calibrated c = run_calibrate(drive, wrong, fragment);
  std::cout << c.output;
  ASSERT_EQ(c.exit_code, 0) << c.output;
  // The fragment layers over the wrong config, as a user gives it: the last --config.
  const liod::ExtrinsicsConfig est = load_extrinsics({wrong, fragment});
  const double rotation_error_deg =
      Eigen::AngleAxisd(est.lidar_to_imu_rotation.conjugate() * truth.lidar_to_imu_rotation).angle() / kRadPerDegree;
  const Eigen::Vector3d translation_error = est.lidar_to_imu_translation - truth.lidar_to_imu_translation;
  const double offset_error_ms = (est.lidar_time_offset_s - truth.lidar_time_offset_s) * 1e3;

  // The daemon's start-up check after 40 s: silent with the truth and the estimate, flags the wrong config.
  constexpr double kCheckS = 40.0;
  const Replayed truth_run = replay(drive, {truth_file}, scratch.path() / "truth.tum", kCheckS);
  const Replayed estimate_run = replay(drive, {wrong, fragment}, scratch.path() / "estimate.tum", kCheckS);
  const Replayed wrong_run = replay(drive, {wrong}, scratch.path() / "wrong.tum", kCheckS);
  const double ate_truth = truth_run.ate;
  const double ate_estimate = estimate_run.ate;
  const double ate_wrong = wrong_run.ate;
  std::cout << "[ calibration ] start-up check: scans flagged extrinsics_suspect with the truth " << truth_run.suspect_scans
            << ", the estimate " << estimate_run.suspect_scans << ", the wrong config " << wrong_run.suspect_scans << std::endl;
  EXPECT_EQ(truth_run.suspect_scans, 0U);
  EXPECT_EQ(estimate_run.suspect_scans, 0U);
  EXPECT_GT(wrong_run.suspect_scans, 50U);  // from the check (~42 s) to the drive's end
  std::cout << std::fixed << std::setprecision(4) << "[ calibration ] error: rotation " << rotation_error_deg
            << " deg, translation " << translation_error.x() * 100 << ", " << translation_error.y() * 100 << ", "
            << translation_error.z() * 100 << " cm, offset " << offset_error_ms << " ms; ATE with the truth " << ate_truth
            << " m, the estimate " << ate_estimate << " m, the wrong config " << ate_wrong << " m" << std::endl;
  EXPECT_LT(rotation_error_deg, 0.1);
  EXPECT_LT(translation_error.head<2>().norm(), 0.01);
  // The height is the config's (CalibrationConfig::hold_up_lever_arm): its error stays.
  EXPECT_NEAR(translation_error.z(), translation.z(), 1e-4);
  EXPECT_LT(std::abs(offset_error_ms), 1.0);
  EXPECT_LE(ate_estimate, 1.5 * ate_truth);
  EXPECT_GT(ate_wrong, 3.0 * ate_truth);  // the miscalibration mattered
}

}  // namespace

// The fault tests' 60 s urban drive (seed 1): the seed's own mounting, liod's config 2 deg, 8.1 cm
// (2 cm of it in height, a tape measure's error) and +20 ms off.
TEST(CalibrateDrive, UrbanSeed1RecoversTheSeedsMounting) {
  LIOD_REQUIRE_SIM();
  LIOD_REQUIRE_PROGRAM("liod");
  const fs::path drive = liod::test::cached_drive_dir("reboot-drive", "--route urban --seed 1 --duration 60 --max-speed 12");
  ASSERT_FALSE(drive.empty()) << "liod-sim failed";
  check_drive(drive, Eigen::Vector3d(1.0, -1.0, 1.0), 2.0, Eigen::Vector3d(0.06, -0.05, 0.02), 0.020);
}

// A mounting chosen with liod-sim's options, the LiDAR's clock 12 ms ahead of the IMU's; liod's
// config 1.8 deg mostly in yaw, 8.8 cm (2 cm in height) and -20 ms off.
TEST(CalibrateDrive, UrbanSeed2RecoversAChosenMountingAndANegativeOffset) {
  LIOD_REQUIRE_SIM();
  LIOD_REQUIRE_PROGRAM("liod");
  const fs::path drive = liod::test::cached_drive_dir(
      "calibration-urban-drive", "--route urban --seed 2 --duration 60 --max-speed 12 --extrinsic-rotation-deg -1,2.5,-3 "
                                 "--extrinsic-translation-m 0.55,-0.04,1.08 --time-offset-s -0.012");
  ASSERT_FALSE(drive.empty()) << "liod-sim failed";
  const liod::ExtrinsicsConfig truth = load_extrinsics({drive / "extrinsics.yaml"});
  EXPECT_NEAR(truth.lidar_time_offset_s, -0.012, 1e-9);  // the sim wrote the chosen truth
  EXPECT_NEAR(truth.lidar_to_imu_translation.x(), 0.55, 1e-9);
  check_drive(drive, Eigen::Vector3d(0.3, -0.2, 1.0), 1.8, Eigen::Vector3d(-0.07, 0.05, -0.02), -0.020);
}

// The fault tests' 60 s highway drive (seed 7): hardly a turn. The command refuses, says why and
// writes nothing.
TEST(CalibrateDrive, HighwayIsRefusedForTooLittleRotation) {
  LIOD_REQUIRE_SIM();
  LIOD_REQUIRE_PROGRAM("liod");
  const fs::path drive = liod::test::cached_drive_dir("crest-start-drive", "--route highway --seed 7 --duration 60 --max-speed 15");
  ASSERT_FALSE(drive.empty()) << "liod-sim failed";
  const liod::test::ScratchDir scratch("calibration");
  const fs::path fragment = scratch.path() / "extrinsics.yaml";
  const Calibrated c = run_calibrate(drive, drive / "extrinsics.yaml", fragment);
  std::cout << c.output;
  EXPECT_EQ(c.exit_code, liod::kCalibrationRefusedExit) << c.output;
  EXPECT_NE(c.output.find("too little rotation"), std::string::npos) << c.output;
  EXPECT_FALSE(fs::exists(fragment));
}
