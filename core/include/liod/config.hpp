#pragma once
// liod's whole configuration: one typed struct, filled and validated only by load_config().
// Every key is documented in config/liod.yaml.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <stdexcept>
#include <string>
#include <vector>

namespace liod {

enum class LidarModel { kHelios5515, kHelios16P };
enum class DeskewMode { kImu, kConstantVelocity, kNone };
enum class CurvatureMode { kAdaptive, kFixed };
enum class KeyframeGating { kHausdorff, kDistanceAngle };

struct LogConfig {
  std::string level = "info";  // trace, debug, info, warn, error, off
};

struct LidarConfig {
  LidarModel model = LidarModel::kHelios5515;
  int msop_port = 6699;
  int difop_port = 7788;
  std::string angles_csv;        // fallback calibration until a DIFOP arrives; empty = wait for DIFOP
  double min_range_m = 0.1;      // decoder limits (sensor spec)
  double max_range_m = 180.0;
  double split_azimuth_deg = 0.0;
};

struct ImuConfig {
  double rate_hz = 200.0;               // nominal rate; used to detect gaps
  double gyro_noise_density = 2.0e-3;   // rad/s/sqrt(Hz)
  double accel_noise_density = 2.0e-2;  // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 5.0e-5;   // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 1.0e-3;  // m/s^3/sqrt(Hz)
  double gravity_m_s2 = 9.80665;
  double max_gap_s = 0.05;              // a longer gap marks the IMU as lost
};

struct ExtrinsicsConfig {
  /// p_imu = rotation * p_lidar + translation
  Eigen::Vector3d lidar_to_imu_translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond lidar_to_imu_rotation = Eigen::Quaterniond::Identity();
  /// t_imu = t_lidar + lidar_time_offset_s
  double lidar_time_offset_s = 0.0;
};

struct OdometryConfig {
  DeskewMode deskew = DeskewMode::kImu;
  CurvatureMode curvature = CurvatureMode::kAdaptive;
  KeyframeGating keyframe_gating = KeyframeGating::kHausdorff;
  double min_range_m = 2.0;          // self-crop: returns closer than this hit the vehicle
  double max_range_m = 120.0;
  double occlusion_jump_m = 0.5;     // neighbour range jump that marks an occlusion edge (scaled by range)
  double edge_curvature = 0.2;       // c above this: edge candidate
  double plane_curvature = 0.05;     // c below this: planar candidate
  int sectors_per_ring = 8;
  int max_edges_per_sector = 6;
  double plane_voxel_m = 0.6;        // downsampling of the planar features of a scan
  double edge_voxel_m = 0.3;
  double map_voxel_m = 1.0;          // local map hash cell size
  int map_points_per_voxel = 20;
  double map_min_point_spacing_m = 0.2;
  int max_iterations = 5;
  double lidar_noise_m = 0.03;       // std of a point-to-plane/line residual
  double max_correspondence_m = 1.5;
  double keyframe_distance_m = 1.0;
  double keyframe_angle_deg = 10.0;
  double hausdorff_threshold_m = 0.6; // h1
  double hausdorff_voxel_m = 1.0;     // clouds are downsampled to this before the Hausdorff test
  int window_keyframes = 25;
  double degeneracy_eigenvalue = 200.0;  // smallest Hessian eigenvalue (1/m^2 units) considered well constrained
  double init_gyro_bias_std = 0.01;      // rad/s
  double init_accel_bias_std = 0.2;      // m/s^2
  double init_velocity_std = 20.0;       // m/s: unknown speed at a rolling start
  double init_tilt_std_deg = 5.0;
};

struct BackendConfig {
  bool enabled = false;
};

struct OutputConfig {
  std::string pose_socket = "/run/liod/pose.sock";
  std::string state_dir = "/var/lib/liod";
};

struct Config {
  LogConfig log;
  LidarConfig lidar;
  ImuConfig imu;
  ExtrinsicsConfig extrinsics;
  OdometryConfig odometry;
  BackendConfig backend;
  OutputConfig output;
};

/// Thrown for any configuration problem; the message names the file, the key and the value.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Loads the files in order, each overriding the keys it sets (e.g. the main file, then a
/// simulator's extrinsics.yaml), starting from the defaults above. Throws ConfigError.
Config load_config(const std::vector<std::string>& paths);

/// Same, from YAML text (for tests); `origin` names it in errors.
Config load_config_from_string(const std::string& yaml_text, const std::string& origin);

}  // namespace liod
