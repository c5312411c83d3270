#pragma once
// The per-scan front end (DESIGN.md, modules 1 and 2): IMU prediction, per-point deskew,
// distance-adaptive curvature features, tightly coupled scan-to-local-map update, keyframe
// gating with the Hausdorff test, and the sliding window of keyframes that forms the local map.
// No threads, no I/O: feed IMU samples and scans in time order, get poses back.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "liod/beam_calibration.hpp"
#include "liod/body_rocking.hpp"
#include "liod/config.hpp"
#include "liod/curvature_features.hpp"
#include "liod/held_bias_trim.hpp"
#include "liod/imu_preintegration.hpp"
#include "liod/imu_trajectory.hpp"
#include "liod/iterated_update.hpp"
#include "liod/local_map.hpp"
#include "liod/speed_search.hpp"
#include "liod/types.hpp"

namespace liod {

enum OdometryStatus : std::uint32_t {
  kStatusInitializing = 1U << 0,
  kStatusDegenerate = 1U << 1,
  kStatusKeyframe = 1U << 2,
  kStatusImuGap = 1U << 3,
  kStatusFewFeatures = 1U << 4,
  kStatusSpeedUnknown = 1U << 5,  // the first scan: attitude and origin only, the speed comes with later scans
  kStatusImuInconsistent = 1U << 6,  // the LiDAR contradicted the IMU prediction (odometry.max_prediction_nis)
};

struct Keyframe {
  std::uint64_t id = 0;
  NavState state;
  std::vector<Eigen::Vector3d> planes_world;
  std::vector<Eigen::Vector3d> edges_world;
  std::vector<Eigen::Vector3d> post_axes_world;  // edges_world as post axes (post_axes), with posts on
  std::vector<Eigen::Vector3d> similarity_cloud_world;  // downsampled, for the Hausdorff test; the newest keyframe's only
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
  explicit LidarInertialOdometry(const Config& config);

  /// Samples must arrive in time order; out-of-order or non-finite ones are dropped (counted).
  void add_imu(const ImuSample& sample);
  /// Latest IMU time, or -inf before any sample.
  double latest_imu_time() const;
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
  static FeatureParams feature_params(const Config& config);

  /// The gravity vector in the world frame (estimated) that the states are propagated with.
  const Eigen::Vector3d& gravity() const { return state_.gravity; }

  bool initialized() const { return initialized_; }
  const std::deque<Keyframe>& keyframes() const { return keyframes_; }
  const LocalMap& plane_map() const { return plane_map_; }
  std::size_t dropped_imu_samples() const { return dropped_imu_; }
  /// IMU samples held for the coming scans (at most a minute's).
  std::size_t buffered_imu_samples() const { return imu_.size(); }
  /// Scans whose IMU prediction the LiDAR contradicted beyond odometry.max_prediction_nis.
  std::size_t inconsistent_imu_scans() const { return inconsistent_imu_scans_; }

 private:
  struct RingPoint {
    std::uint16_t ring;
    Eigen::Vector3d lidar;
  };
  struct Features {
    std::vector<Eigen::Vector3d> planes;      // registration queries (sparse)
    std::vector<Eigen::Vector3d> edges;
    std::vector<Eigen::Vector3d> map_planes;  // what a keyframe adds to the map (denser)
    std::vector<RingPoint> map_plane_sources;  // each map plane point's beam and LiDAR-frame point
  };
  struct TimedPoint {
    double time;           // IMU clock
    Eigen::Vector3d body;  // IMU frame at that time
  };
  void initialize(const Scan& scan, OdometryResult& result);
  struct StructurePoints {
    std::vector<TimedPoint> all;        // vertical structure (speed_search.hpp), thinned
    std::vector<TimedPoint> off_lines;  // without the rails and barriers along the road
  };
  StructurePoints vertical_structure_points(const Scan& scan) const;

  /// Adds the scan to the speed search; the speed at the first scan once the evidence suffices.
  /// `motion`: what the gyro says of the body up to the scan's end (body_motion_until).
  std::optional<double> search_speed(const Scan& scan, BodyMotion motion);
  void start_at_speed(double speed);
  void settle_gyro_bias_at_rest(double from, double to);
  /// A standstill start: the gyro bias, measured at rest, gets odometry.standstill_gyro_bias_std.
  void trust_gyro_bias_measured_at_rest();
  /// What the gyro's roll-and-pitch rocking says of the motion up to `time` (body_rocking.hpp).
  BodyMotion body_motion_until(double time) const;
  std::optional<OdometryResult> process(const Scan& scan, const ScanFeatures* extracted);
  /// `extracted`: the scan's features, or nullptr to extract them here.
  void process_scan(const Scan& scan, const ScanFeatures* extracted, OdometryResult& result);
  PoseTable deskew_trajectory(const Scan& scan, const NavState& start, const NavState& predicted_end,
                              const std::vector<ImuInterval>& intervals) const;
  void deskew_features(const Scan& scan, const ScanFeatures& indices, const PoseTable& relative, Features& out) const;
  StateCovariance propagate_covariance(const ImuPreintegration& preintegration, const NavState& start) const;
  void consider_keyframe(const Features& features, OdometryResult& result);
  std::vector<Eigen::Vector3d> similarity_cloud(const Features& features) const;  // world frame, downsampled
  void add_keyframe(const Features& features, std::vector<Eigen::Vector3d> similarity_cloud_world);

  Config config_;
  ExtrinsicsConfig extrinsics_;
  Pose lidar_to_imu_;
  ImuNoise noise_;
  UpdateParams update_params_;
  FeatureExtractor extractor_;
  ScanFeatures scan_features_;
  BeamCalibration beam_calibration_;
  void learn_beam_calibration(const Features& features);

  std::deque<ImuSample> imu_;
  std::size_t dropped_imu_ = 0;
  std::size_t inconsistent_imu_scans_ = 0;
  bool initialized_ = false;
  bool map_trusted_ = false;
  // A rolling start until the scans' vertical structure tells the speed: the scans' structure
  // points, and the overlap of each with those before it, without the rails, summed per speed
  // hypothesis.
  struct SpeedSearch {
    double first_end_time = 0.0;
    bool all_structure_standstill = false;  // the first scans' best speed with all of the structure, below 1 m/s
    bool evidence_standstill = false;    // the best speed off the rails so far, below 1 m/s
    bool rocked = false;                 // the IMU saw the body rock while the search went on (body_rocking.hpp)
    std::optional<double> moving_peak;   // while the body rocks: a second peak of that evidence (separate_peak)
    std::optional<double> unclear_speed; // that evidence's best speed while it does not stand clear of its aliases
    std::vector<Scan> held;  // every scan since the first (at most kMaxSpeedSearch_s of them)
    std::vector<StructurePoints> structure;
    std::vector<double> evidence;      // off the rails, from the second scan on
    std::vector<double> evidence_all;  // all of the structure, up to the kAllStructureScans-th scan
  };
  std::optional<SpeedSearch> speed_search_;
  // The forward accelerometer bias is kept out of the next LiDAR update: at a rolling start, and
  // after a scan that left the along-track position unconstrained (process_scan explains why).
  bool hold_forward_accel_bias_ = false;
  HeldBiasTrim held_bias_trim_;  // what the LiDAR's corrections say of the bias while it is held
  // Started from a standstill and not yet odometry.move_off_distance_m from it: walls, and the
  // ground once the body rolls, locate the scan across the track only
  // (odometry.move_off_planes_across; process_scan explains why).
  bool moving_off_ = false;
  Eigen::Vector3d standstill_position_ = Eigen::Vector3d::Zero();  // where a standstill start stood
  int scans_since_imu_inconsistent_ = 0;
  NavState state_;
  StateCovariance covariance_ = StateCovariance::Zero();
  Eigen::Vector3d last_angular_rate_ = Eigen::Vector3d::Zero();  // body frame, for constant-velocity deskew

  LocalMap plane_map_;
  LocalMap edge_map_;
  LocalMap post_axis_map_;  // the keyframes' post_axes_world
  std::deque<Keyframe> keyframes_;
  std::uint64_t next_keyframe_id_ = 0;
};

}  // namespace liod
