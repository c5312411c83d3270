#pragma once
// The per-scan front end (the seed paper's modules 1 and 2): IMU prediction, per-point deskew,
// distance-adaptive curvature features, a tightly coupled scan-to-local-map update, keyframe
// gating with the Hausdorff test and the sliding window of keyframes that forms the local map.
// No threads, no I/O: feed IMU samples and scans in time order, get poses back. The pipeline's
// steps are LidarInertialOdometry::process_scan's; each lives in a unit of its own.

#include <cstdint>
#include <deque>
#include <optional>

#include "liod/beam_calibration.hpp"
#include "liod/bias_holds.hpp"
#include "liod/algorithm_config.hpp"
#include "liod/curvature_features.hpp"
#include "liod/deskew.hpp"
#include "liod/imu_buffer.hpp"
#include "liod/imu_preintegration.hpp"
#include "liod/iterated_update.hpp"
#include "liod/keyframe.hpp"
#include "liod/keyframe_window.hpp"
#include "liod/move_off.hpp"
#include "liod/reinitialization.hpp"
#include "liod/start_up.hpp"
#include "liod/state_sanity.hpp"
#include "liod/types.hpp"

namespace liod {

enum OdometryStatus : std::uint32_t {
  kStatusInitializing = 1U << 0,
  kStatusDegenerate = 1U << 1,
  kStatusKeyframe = 1U << 2,
  kStatusImuGap = 1U << 3,
  kStatusFewFeatures = 1U << 4,
  kStatusSpeedUnknown = 1U << 5,  // the first scan: attitude and origin only, the speed comes with later scans
  kStatusImuInconsistent = 1U << 6,  // the LiDAR contradicted the IMU prediction (bias_holds.hpp)
};

struct OdometryResult {
  NavState state;  // body (IMU) frame at the scan's end time, on the IMU clock
  StateCovariance covariance = StateCovariance::Zero();
  std::uint32_t status = 0;
  std::size_t points = 0;
  std::size_t edge_features = 0;
  std::size_t plane_features = 0;
  int residuals = 0;
  int iterations = 0;
  double rms_residual_m = 0.0;
  double min_translation_eigenvalue = 0.0;
  double hausdorff_m = -1.0;  // -1 when no test ran
  /// What the LiDAR changed in the IMU-predicted velocity (body frame): over a stretch, its mean
  /// rate along the track is the forward acceleration error the IMU prediction makes there.
  Eigen::Vector3d velocity_correction_body = Eigen::Vector3d::Zero();
  /// The forward accelerometer bias and gravity tilt were held out of this scan's update.
  bool forward_hold = false;
  double deskew_ms = 0.0;
  double features_ms = 0.0;
  double registration_ms = 0.0;
  double map_ms = 0.0;
};

class LidarInertialOdometry {
 public:
  /// `limits`: what a plausible state is; the odometry re-initialises from one beyond them
  /// (reinitialization.hpp). The daemon passes its pose_socket.* limits.
  explicit LidarInertialOdometry(const FrontEndConfig& config, const StateLimits& limits = {});

  /// Samples must arrive in time order; out-of-order, non-finite and out-of-range ones are
  /// dropped (counted).
  void add_imu(const ImuSample& sample) { imu_.add(sample); }
  /// Latest IMU time, or -inf before any sample.
  double latest_imu_time() const { return imu_.latest_time(); }
  /// Time on the IMU clock at which this scan ends: process it once IMU data reaches it.
  double scan_end_time(const Scan& scan) const { return scan.end_time + extrinsics_.lidar_time_offset_s; }

  /// Estimates the body state at the scan's end. Returns nullopt while it cannot yet (no IMU
  /// data around the scan, or a rolling start's speed not found yet: the first scan's result
  /// has the attitude only). Points must carry per-point times.
  std::optional<OdometryResult> process(const Scan& scan);
  /// The same with the scan's features already extracted by an extractor made with
  /// feature_params() (the daemon extracts on the LiDAR thread while this one registers the scan
  /// before); result.features_ms is then 0.
  std::optional<OdometryResult> process(const Scan& scan, const ScanFeatures& extracted);
  /// The feature extractor's parameters for this configuration.
  static FeatureParams feature_params(const FrontEndConfig& config);

  /// The gravity vector in the world frame (estimated) that the states are propagated with.
  const Eigen::Vector3d& gravity() const { return state_.gravity; }

  bool initialized() const { return initialized_; }
  const std::deque<Keyframe>& keyframes() const { return window_.keyframes(); }
  const LocalMap& plane_map() const { return window_.plane_map(); }
  std::size_t dropped_imu_samples() const { return imu_.dropped(); }
  /// IMU samples held for the coming scans (at most a minute's).
  std::size_t buffered_imu_samples() const { return imu_.size(); }
  /// Scans whose IMU prediction the LiDAR contradicted beyond odometry.max_prediction_nis.
  std::size_t inconsistent_imu_scans() const { return holds_.inconsistent_scans(); }
  /// New local maps started after an outage the prediction could not bridge (reinitialization.hpp).
  std::size_t new_maps() const { return reinit_.new_maps(); }
  /// Start-ups again from an implausible state.
  std::size_t restarts() const { return reinit_.restarts(); }

 private:
  /// The IMU's prediction of the scan's end state from the last one.
  struct Prediction {
    NavState start;
    std::vector<ImuInterval> intervals;
    ImuPreintegration preintegration;
    NavState predicted;
    StateCovariance covariance;
    PoseTable relative;  // the deskew's poses, relative to the predicted end
  };

  std::optional<OdometryResult> process(const Scan& scan, const ScanFeatures* extracted);
  void initialize(const Scan& scan, OdometryResult& result);
  /// A scan while the start-up searches the speed: its result once decided.
  std::optional<OdometryResult> search_start(const Scan& scan, const ScanFeatures* extracted);
  /// `extracted`: the scan's features, or nullptr to extract them here.
  void process_scan(const Scan& scan, const ScanFeatures* extracted, OdometryResult& result);
  /// kBridgeWholeScan: the IMU's samples over the scan are not used (it contradicted the LiDAR).
  enum class ImuUse { kMeasured, kBridgeWholeScan };
  Prediction predict(const Scan& scan, OdometryResult& result, ImuUse use = ImuUse::kMeasured) const;
  StateCovariance propagate_covariance(const ImuPreintegration& preintegration, const NavState& start) const;
  DeskewedFeatures deskew(const Scan& scan, const ScanFeatures& indices, const PoseTable& relative) const;
  void register_scan(const Scan& scan, const ScanFeatures& indices, Prediction& prediction,
                     DeskewedFeatures& features, OdometryResult& result);
  void bridge_contradicting_imu(const Scan& scan, const ScanFeatures& indices, UpdateParams params,
                                Prediction& prediction, DeskewedFeatures& features, UpdateResult& updated);
  UpdateResult update(const Prediction& prediction, const DeskewedFeatures& features, const UpdateParams& params) const;
  void update_map(const DeskewedFeatures& features, OdometryResult& result);
  void keep_keyframe_imu(const Prediction& prediction, std::uint32_t status);
  /// Before registering a scan: a new map if the prediction left the map's registration basin.
  void restart_map_if_lost(Prediction& prediction);
  /// After a scan: the recovery's flag, the published covariance, and the start-up again from an
  /// implausible state.
  void check_recovery(OdometryResult& result);

  FrontEndConfig config_;
  ExtrinsicsConfig extrinsics_;
  Pose lidar_to_imu_;
  ImuNoise noise_;
  UpdateParams update_params_;
  DeskewParams deskew_params_;
  FeatureExtractor extractor_;
  ScanFeatures scan_features_;
  BeamCalibration beam_calibration_;

  ImuBuffer imu_;
  StartUp start_up_;
  BiasHolds holds_;
  MoveOff move_off_;
  KeyframeWindow window_;
  Reinitialization reinit_;
  bool initialized_ = false;
  bool map_trusted_ = false;  // the map was started afresh once the speed was known
  NavState state_;
  StateCovariance covariance_ = StateCovariance::Zero();
  Eigen::Vector3d last_angular_rate_ = Eigen::Vector3d::Zero();  // body frame, for constant-velocity deskew and gaps
  std::vector<ImuInterval> imu_since_keyframe_;  // for the next keyframe (Keyframe::imu_since_previous)
  bool imu_since_keyframe_measured_ = true;      // no bridged interval among them
};

}  // namespace liod
