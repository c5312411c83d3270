#pragma once
// Two consecutive sweeps registered with the IMU's prediction, for a recording too short for the
// odometry's start-up (start_up.hpp): a fraction of a second from a vehicle under way holds no
// standstill and too few scans for the speed search. The IMU gives the attitude (gravity), the
// turn and the change of velocity across the pair; the LiDAR gives the translation. The speed
// the deskew needs is found in rounds: deskew both sweeps with the current speed (a standstill
// at first), register the second on the first, take the speed the registration implies, repeat.

#include <deque>
#include <optional>

#include "liod/algorithm_config.hpp"
#include "liod/curvature_features.hpp"
#include "liod/deskew.hpp"
#include "liod/imu_trajectory.hpp"
#include "liod/iterated_update.hpp"
#include "liod/types.hpp"

namespace liod {

struct SweepRegistrationConfig {
  FeatureParams features;
  DeskewParams deskew;
  UpdateParams update;
  Pose lidar_to_imu;
  double lidar_time_offset_s = 0.0;
  ImuNoise noise;
  // The first sweep's map, as the front end's local map keeps it.
  double map_voxel_m = 1.0;
  int map_points_per_voxel = 20;
  double map_min_point_spacing_m = 0.2;
  // The registration's prior (1 sigma): the IMU's rotation over 0.1 s is good to a small fraction
  // of a degree; the position is the LiDAR's to find.
  double rotation_std_deg = 1.0;
  double position_std_m = 2.0;
  /// Deskew-and-register rounds; the speed of the last one is reported.
  int rounds = 4;
  /// Rounds end early once the speed changes by less than this.
  double speed_tolerance_m_s = 0.005;
  /// IMU samples averaged for the attitude (gravity) around the pair.
  std::size_t min_alignment_samples = 5;
};

/// The front end's feature, deskew, update and IMU settings and extrinsics, as the odometry uses them.
SweepRegistrationConfig sweep_registration_config(const FrontEndConfig& config);

struct SweepMotion {
  /// The second sweep's end pose in the frame of the first's end: LiDAR and body (IMU) frames.
  Pose lidar;
  Pose body;
  /// The body velocity at the first sweep's end, in that body frame, m/s.
  Eigen::Vector3d velocity_body = Eigen::Vector3d::Zero();
  /// The last round's registration.
  int residuals = 0;
  double rms_residual_m = 0.0;
  int degenerate_directions = 0;
  int rounds = 0;
};

class SweepRegistration {
 public:
  explicit SweepRegistration(SweepRegistrationConfig config);

  /// Samples in time order (a sample older than the last is ignored).
  void add_imu(const ImuSample& sample);
  /// The motion from `first`'s end to `second`'s end; nullopt without IMU samples over the pair
  /// (the nearest one is held for a sweep that starts a few milliseconds before the IMU) or with
  /// too few features to register.
  std::optional<SweepMotion> register_pair(const Scan& first, const Scan& second) const;

 private:
  struct Round;
  Round run_round(const Scan& first, const ScanFeatures& first_features, const Scan& second,
                  const ScanFeatures& second_features, const NavState& start) const;

  SweepRegistrationConfig config_;
  std::deque<ImuSample> imu_;
};

}  // namespace liod
