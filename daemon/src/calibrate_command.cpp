#include "liod/daemon/calibrate_command.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "liod/calibration/extrinsic_calibration.hpp"
#include "liod/daemon/extrinsics_check.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/drivers/imu_csv.hpp"

namespace liod {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

/// The drive through the odometry (as `liod replay`, as fast as possible, no backend): the
/// LiDAR's world poses of the scans that show its motion (shows_lidar_motion), body pose times
/// the configured extrinsic, on the IMU clock.
std::vector<calibration::LidarPose> lidar_poses(Config config, const CalibrateOptions& options) {
  config.backend.enabled = false;
  config.backend.persist = false;
  config.imu.gyro_noise_density *= options.gyro_noise_scale;
  const std::vector<std::uint16_t> ports{static_cast<std::uint16_t>(config.lidar.msop_port),
                                         static_cast<std::uint16_t>(config.lidar.difop_port)};
  auto pace = std::make_shared<PaceClock>();
  PipelineOptions po;
  po.ordering = Ordering::Lockstep;
  po.imu_rate_poses = false;
  po.realtime_threads = false;
  Pipeline pipeline(config, po);
  const Eigen::Matrix3d r_bl = config.extrinsics.lidar_to_imu_rotation.toRotationMatrix();
  const Eigen::Vector3d t_bl = config.extrinsics.lidar_to_imu_translation;
  std::vector<calibration::LidarPose> poses;
  pipeline.add_sink([&](const PoseEvent& ev) {
    const auto& m = ev.message;
    if (m.type == pose::MessageType::ImuPose || !shows_lidar_motion(m.flags)) return;
    const Eigen::Matrix3d r_wb = m.orientation.toRotationMatrix();
    poses.push_back({m.time, r_wb * r_bl, m.position + r_wb * t_bl});
  });
  pipeline.start(std::make_unique<PcapLidarSource>(options.pcap, ports, pace),
                 std::make_unique<CsvImuSource>(options.imu_csv, pace));
  while (!pipeline.finished() && pipeline.error().empty()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  pipeline.join();
  if (!pipeline.error().empty()) throw std::runtime_error(pipeline.error());
  if (poses.empty()) throw std::runtime_error("the odometry estimated no pose: do the pcap and the IMU log cover the same time?");
  const double start = poses.front().time + options.skip_s;
  std::erase_if(poses, [start](const calibration::LidarPose& p) { return p.time < start; });
  return poses;
}

void print_pass(int pass, const ExtrinsicsConfig& from, const calibration::CalibrationResult& r, std::ostream& out) {
  const Eigen::Matrix3d& m = r.fit.lidar_to_imu;  // R = Rz(yaw) Ry(pitch) Rx(roll)
  const Eigen::Vector3d rpy =
      Eigen::Vector3d(std::atan2(m(2, 1), m(2, 2)), -std::asin(std::clamp(m(2, 0), -1.0, 1.0)), std::atan2(m(1, 0), m(0, 0))) *
      kRadToDeg;
  const double turned = Eigen::AngleAxisd(from.lidar_to_imu_rotation.conjugate() * Eigen::Quaterniond(r.fit.lidar_to_imu)).angle();
  out << std::fixed << std::setprecision(4) << "pass " << pass << ": time offset " << std::setprecision(5)
      << from.lidar_time_offset_s + r.time_shift.shift_s << " s (shift " << r.time_shift.shift_s * 1e3
      << " ms, rate correlation " << std::setprecision(3) << r.time_shift.correlation << ")\n"
      << std::setprecision(3) << "  rotation r,p,y " << rpy.x() << ", " << rpy.y() << ", " << rpy.z() << " deg ("
      << turned * kRadToDeg << " deg from the pass's config), std about x,y,z " << std::setprecision(4)
      << r.fit.rotation_std.x() * kRadToDeg << ", " << r.fit.rotation_std.y() * kRadToDeg << ", "
      << r.fit.rotation_std.z() * kRadToDeg << " deg\n"
      << "  translation " << r.fit.translation.x() << ", " << r.fit.translation.y() << ", " << r.fit.translation.z()
      << " m, std " << r.fit.translation_std.x() * 100 << ", " << r.fit.translation_std.y() * 100 << ", "
      << r.fit.translation_std.z() * 100 << " cm (the part along odometry.up_axis kept from the config)\n"
      << "  turn-rate spread (principal axes) " << r.hand_eye.rate_spread.x() << ", " << r.hand_eye.rate_spread.y()
      << ", " << r.hand_eye.rate_spread.z() << " rad/s; residuals gyro " << r.fit.gyro_rms << " rad/s, accel "
      << r.fit.accel_rms << " m/s over " << r.fit.gyro_residuals << " + " << r.fit.accel_residuals << '\n';
}

void write_fragment(const std::string& path, const ExtrinsicsConfig& e, const CalibrateOptions& options) {
  const std::filesystem::path target(path);
  const std::filesystem::path temporary = target.string() + ".tmp";
  {
    std::ofstream f(temporary);
    const Eigen::Quaterniond& q = e.lidar_to_imu_rotation;
    f << std::setprecision(9) << "# liod calibrate --pcap " << options.pcap << " --imu " << options.imu_csv << '\n'
      << "extrinsics:\n"
      << "  lidar_to_imu:              # p_imu = R * p_lidar + t\n"
      << "    translation_m: [" << e.lidar_to_imu_translation.x() << ", " << e.lidar_to_imu_translation.y() << ", "
      << e.lidar_to_imu_translation.z() << "]\n"
      << "    rotation_xyzw: [" << q.x() << ", " << q.y() << ", " << q.z() << ", " << q.w() << "]\n"
      << "  lidar_time_offset_s: " << e.lidar_time_offset_s << "   # t_imu = t_lidar + offset\n";
    f.flush();
    if (!f) throw std::runtime_error(temporary.string() + ": write failed");
  }
  std::filesystem::rename(temporary, target);
}

}  // namespace

int run_calibrate(const Config& config, const CalibrateOptions& options, std::ostream& out) {
  const std::vector<ImuSample> imu = drivers::read_imu_csv(options.imu_csv);
  Config pass_config = config;
  calibration::CalibrationResult result;
  for (int pass = 1; pass <= options.passes; ++pass) {
    const auto poses = lidar_poses(pass_config, options);
    calibration::CalibrationConfig calibration_config;
    calibration_config.up_axis = config.odometry.up_axis;
    result = calibration::calibrate_extrinsics(poses, imu, pass_config.extrinsics, calibration_config);
    print_pass(pass, pass_config.extrinsics, result, out);
    // Every pass but the last needs only an estimate to replay with; the last one is judged.
    if (!result.accepted && (pass == options.passes || !result.usable)) {
      out << "refused: this drive cannot calibrate the LiDAR-IMU extrinsics:\n";
      for (const auto& reason : result.refusals) out << "  - " << reason << '\n';
      out << std::flush;
      spdlog::error("calibration refused: {}", result.refusals.front());
      return kCalibrationRefusedExit;
    }
    pass_config.extrinsics = result.fitted;
  }
  write_fragment(options.out, result.estimate, options);
  out << "wrote " << options.out << " (use it as the last --config)\n";
  return 0;
}

}  // namespace liod
