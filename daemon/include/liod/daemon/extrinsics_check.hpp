#pragma once
// The start-up check of the configured LiDAR-IMU extrinsic and time offset: once the odometry
// has published `window_s` of scan poses that show the LiDAR's motion, the calibration (core/calibration/) runs once on them
// and the IMU samples of the same time. When the drive turned enough to tell, and the estimate
// differs from the configuration beyond its uncertainty, both are logged and every later pose
// carries pose::kExtrinsicsSuspect (run `liod calibrate`). A window with too little turning is
// dropped and the next one tried.
//
// The odometry ran with the configured values, so its poses carry a part of their error and the
// estimate lies between the configuration and the truth (one pass of `liod calibrate`): a
// disagreement it finds is real, and at least as large as it says.

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "liod/algorithm_config.hpp"
#include "liod/calibration/extrinsic_calibration.hpp"
#include "liod/types.hpp"

namespace liod {

/// Whether a scan pose with these flags (pose_protocol.hpp) shows the LiDAR's motion: not while
/// the filter starts, nor when a sensor dropped out, the registration contradicted the IMU, the
/// state failed its checks or the scan had too few features. A degenerate scan counts: its
/// translation along one direction is the IMU's, which a sparse road (or a motorway, which the
/// calibration must see to refuse) gives scan after scan.
bool shows_lidar_motion(std::uint32_t flags);

struct ExtrinsicsCheckConfig {
  /// Beyond what one pass gets wrong itself on a minute in town (docs/results.md, "Calibration":
  /// after three passes within 0.1°, 3 mm and 0.7 ms): a difference smaller than these is not
  /// reported, whatever the standard deviations say.
  static constexpr double kDefaultRotationFloorDeg = 0.3;
  static constexpr double kDefaultTranslationFloorM = 0.03;
  static constexpr double kDefaultOffsetFloorS = 0.002;
  /// A difference beyond this many standard deviations of the estimate disagrees.
  static constexpr double kDefaultSigmas = 3.0;
  double window_s = 60.0;
  bool background = true;  // false: the check runs on the caller's thread (deterministic replays)
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
  double rotation_floor_deg = kDefaultRotationFloorDeg;
  double translation_floor_m = kDefaultTranslationFloorM;
  double offset_floor_s = kDefaultOffsetFloorS;
  double sigmas = kDefaultSigmas;
};

class ExtrinsicsCheck {
 public:
  ExtrinsicsCheck(const ExtrinsicsConfig& configured, ExtrinsicsCheckConfig config);
  ~ExtrinsicsCheck();
  ExtrinsicsCheck(const ExtrinsicsCheck&) = delete;
  ExtrinsicsCheck& operator=(const ExtrinsicsCheck&) = delete;

  void add_imu(const ImuSample& sample);
  /// A scan's body pose (world frame) and its flags. True once the configured extrinsics were
  /// found to disagree (it stays so for the run).
  bool add_scan(double time, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& position, std::uint32_t flags);
  bool suspect() const noexcept { return suspect_; }
  /// True once a window turned enough to judge (the check is then over).
  bool judged() const noexcept { return phase_ == Phase::kDone; }

 private:
  enum class Phase { kCollecting, kChecking, kDone };
  void start_check();
  void finish_check(const calibration::CalibrationResult& result);

  ExtrinsicsConfig configured_;
  ExtrinsicsCheckConfig config_;
  Phase phase_ = Phase::kCollecting;
  bool suspect_ = false;
  std::vector<ImuSample> imu_;
  std::vector<calibration::LidarPose> poses_;
  std::thread worker_;
  std::atomic<bool> worker_done_{false};
  std::unique_ptr<calibration::CalibrationResult> worker_result_;
};

}  // namespace liod
