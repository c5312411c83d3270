#include "liod/daemon/extrinsics_check.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "liod/daemon/pose_protocol.hpp"

namespace liod {
namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
/// IMU samples kept before the window's first pose: the first scan interval needs them.
constexpr double kImuBeforeFirstPoseS = 1.0;

std::string describe(const ExtrinsicsConfig& e) {
  const Eigen::Quaterniond& q = e.lidar_to_imu_rotation;
  const Eigen::Vector3d& t = e.lidar_to_imu_translation;
  return fmt::format("translation [{:.3f}, {:.3f}, {:.3f}] m, rotation_xyzw [{:.5f}, {:.5f}, {:.5f}, {:.5f}], "
                     "time offset {:.4f} s",
                     t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(), e.lidar_time_offset_s);
}

}  // namespace

bool shows_lidar_motion(std::uint32_t flags) {
  constexpr std::uint32_t kUnusable = pose::kInitializing | pose::kImuLost | pose::kLidarLost | pose::kFewFeatures |
                                      pose::kImuInconsistent | pose::kImplausible | pose::kSweepTruncated;
  return (flags & kUnusable) == 0;
}

ExtrinsicsCheck::ExtrinsicsCheck(const ExtrinsicsConfig& configured, ExtrinsicsCheckConfig config)
    : configured_(configured), config_(std::move(config)) {}

ExtrinsicsCheck::~ExtrinsicsCheck() {
  if (worker_.joinable()) worker_.join();
}

void ExtrinsicsCheck::add_imu(const ImuSample& sample) {
  if (phase_ != Phase::kCollecting) return;
  imu_.push_back(sample);
  // Before the first ok pose only the last second is needed.
  if (poses_.empty() && imu_.front().time < sample.time - 2.0 * kImuBeforeFirstPoseS) {
    const double keep_from = sample.time - kImuBeforeFirstPoseS;
    std::erase_if(imu_, [keep_from](const ImuSample& s) { return s.time < keep_from; });
  }
}

bool ExtrinsicsCheck::add_scan(double time, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& position,
                               std::uint32_t flags) {
  if (phase_ == Phase::kChecking && worker_done_.load(std::memory_order_acquire)) {
    worker_.join();
    finish_check(*worker_result_);
  }
  if (phase_ != Phase::kCollecting || !shows_lidar_motion(flags)) return suspect_;
  const Eigen::Matrix3d r_bl = configured_.lidar_to_imu_rotation.toRotationMatrix();
  poses_.push_back({time, rotation * r_bl, position + rotation * configured_.lidar_to_imu_translation});
  if (poses_.back().time - poses_.front().time >= config_.window_s) start_check();
  return suspect_;
}

void ExtrinsicsCheck::start_check() {
  calibration::CalibrationConfig calibration_config;
  calibration_config.up_axis = config_.up_axis;
  if (!config_.background) {
    finish_check(calibration::calibrate_extrinsics(poses_, imu_, configured_, calibration_config));
    return;
  }
  // Seconds of work for the low-priority side: the odometry thread only hands the data over.
  phase_ = Phase::kChecking;
  worker_done_.store(false);
  worker_ = std::thread([this, calibration_config, poses = std::move(poses_), imu = std::move(imu_)] {
    worker_result_ = std::make_unique<calibration::CalibrationResult>(
        calibration::calibrate_extrinsics(poses, imu, configured_, calibration_config));
    worker_done_.store(true, std::memory_order_release);
  });
  poses_.clear();
  imu_.clear();
}

void ExtrinsicsCheck::finish_check(const calibration::CalibrationResult& r) {
  poses_.clear();
  imu_.clear();
  if (!r.usable) {
    spdlog::info("extrinsics check: {}; trying the next {:.0f} s", r.refusals.empty() ? "no estimate" : r.refusals.front(),
                 config_.window_s);
    phase_ = Phase::kCollecting;
    return;
  }
  phase_ = Phase::kDone;
  const ExtrinsicsConfig& e = r.fitted;
  const double rotation = Eigen::AngleAxisd(configured_.lidar_to_imu_rotation.conjugate() * e.lidar_to_imu_rotation).angle();
  const double rotation_limit = std::max(config_.rotation_floor_deg * kRadPerDeg, config_.sigmas * r.fit.rotation_std.maxCoeff());
  const double translation = (e.lidar_to_imu_translation - configured_.lidar_to_imu_translation).norm();
  const double translation_limit = std::max(config_.translation_floor_m, config_.sigmas * r.fit.translation_std.maxCoeff());
  const double offset = std::abs(e.lidar_time_offset_s - configured_.lidar_time_offset_s);
  const double offset_limit = std::max(config_.offset_floor_s, config_.sigmas * r.time_shift.shift_std_s);
  suspect_ = rotation > rotation_limit || translation > translation_limit || offset > offset_limit;
  const auto message = fmt::format(
      "extrinsics check: configured {}; estimated {} (differences {:.2f} deg, {:.3f} m, {:.1f} ms; limits {:.2f} deg, "
      "{:.3f} m, {:.1f} ms)",
      describe(configured_), describe(e), rotation / kRadPerDeg, translation, offset * 1e3, rotation_limit / kRadPerDeg,
      translation_limit, offset_limit * 1e3);
  if (suspect_) {
    spdlog::warn("{}: they disagree, poses from now on carry extrinsics_suspect; run liod calibrate", message);
  } else {
    spdlog::info("{}: they agree", message);
  }
}

}  // namespace liod
