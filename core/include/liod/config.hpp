#pragma once
// liod's whole configuration: one typed struct, filled and validated only by load_config().
// Every key is documented in config/liod.yaml.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace liod {

enum class LidarModel { kHelios5515, kHelios16P };
enum class DeskewMode { kImu, kConstantVelocity, kNone };
enum class CurvatureMode { kAdaptive, kFixed };
enum class KeyframeGating { kHausdorff, kDistanceAngle };
/// How an edge point's distance to its map line is measured: along the LiDAR ray (its range, which
/// the silhouette of a post or a corner does not shift with the viewpoint) or the shortest way (LOAM).
enum class EdgeResidual { kAlongRay, kPointToLine };

struct LogConfig {
  std::string level = "info";  // trace, debug, info, warn, error, off
};

enum class CalibrationUpdates { kPin, kFollow };

struct LidarConfig {
  LidarModel model = LidarModel::kHelios5515;
  int msop_port = 6699;
  int difop_port = 7788;
  std::string angles_csv;        // fallback calibration until a DIFOP arrives; empty = wait for DIFOP
  double min_range_m = 0.1;      // decoder limits (sensor spec)
  double max_range_m = 180.0;
  double split_azimuth_deg = 0.0;
  int packets_before_difop = 4096;  // without angles_csv: MSOP held until the first DIFOP (1 s is ~1500)
  CalibrationUpdates calibration_updates = CalibrationUpdates::kPin;  // a later DIFOP's differing calibration: pin (flagged) | follow (at a sweep boundary)
};

struct ImuConfig {
  double rate_hz = 200.0;               // nominal rate; used to detect gaps
  double gyro_noise_density = 5.0e-4;   // rad/s/sqrt(Hz)
  double accel_noise_density = 5.0e-3;  // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 5.0e-5;   // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 1.0e-2;  // m/s^3/sqrt(Hz), inflated on purpose (config/liod.yaml)
  double gravity_m_s2 = 9.80665;
  double max_gap_s = 0.05;              // a longer gap marks the IMU as lost
  double gyro_range_rad_s = 34.91;      // measurement range (Xsens MTi-630: 2000 deg/s): beyond = dropped, at = saturated
  double accel_range_m_s2 = 98.07;      // measurement range (Xsens MTi-630: 10 g): beyond = dropped, at = saturated
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
  double min_range_m = 2.0;          // returns closer than this are not used
  /// Self-crop: returns inside this box of the body (IMU) frame hit the vehicle itself.
  /// Disabled while min is not below max on every axis.
  Eigen::Vector3d crop_box_min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d crop_box_max_m = Eigen::Vector3d::Zero();
  double max_range_m = 120.0;
  /// The vehicle's forward direction in the body (IMU) frame, a unit vector: a rolling start
  /// searches its speed along it (a road vehicle does not slide sideways).
  Eigen::Vector3d forward_axis = Eigen::Vector3d::UnitX();
  /// The vehicle's up direction in the body (IMU) frame, a unit vector orthogonal to forward_axis.
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
  /// Std of the velocity along up_axis (a wheeled vehicle does not move along it; suspension and
  /// bumps do a little). Ties the pitch to the direction of travel. 0: constraint off.
  double vertical_velocity_std_mps = 0.05;
  double occlusion_jump_m = 0.5;     // neighbour range jump that marks an occlusion edge (scaled by range)
  double edge_curvature = 0.1;       // c above this: edge candidate
  double plane_curvature = 0.05;     // c below this: planar candidate
  int sectors_per_ring = 8;
  int max_edges_per_sector = 6;
  double plane_voxel_m = 0.6;        // downsampling of the planar features of a scan
  double edge_voxel_m = 0.3;
  double map_voxel_m = 1.0;          // local map hash cell size
  int map_points_per_voxel = 20;
  double map_min_point_spacing_m = 0.2;
  int max_iterations = 5;
  int forced_searches = 1;  // iterations that search the map afresh; later ones only if the pose moved
  double lidar_noise_m = 0.03;       // std of a point-to-plane/line residual
  double max_correspondence_m = 0.5; // loop registration (backend)
  int correspondence_neighbours = 8;     // map neighbours of a plane / line correspondence (front end)
  double correspondence_gate_m = 1.0;    // front end: farther map neighbours are not used
  double plane_thickness_m = 0.03;       // every neighbour within this of its fitted plane
  bool fit_uncertainty = true;           // a residual's variance includes its fitted plane's / line's uncertainty
  EdgeResidual edge_residual = EdgeResidual::kAlongRay;
  bool beam_calibration = true;  // learn each beam's elevation offset from its ground residuals (beam_calibration.hpp)
  bool beam_range_calibration = true;  // with beam_calibration: each beam's range offset too (beam_calibration.hpp)
  bool post_edges = true;  // along_ray only: edges on posts (map points one above the other) match the post's axis
  double post_depth_m = 0.08;  // post_edges: an edge point's post axis lies this far behind it along the ray
  double surface_end_extrapolation = 0.5;  // an edge ending a surface seen at grazing incidence: moved on this share of a step
  double crossing_edge_tolerance_m = 0.1;  // an edge where the ring runs off a surface across a horizontal border that the next ring carries on: dropped (0: kept)
  double post_max_width_m = 0.4;  // post_edges: an edge ending a ring's run this narrow is placed by the run's axis (0: never)
  bool move_off_planes_across = true;  // after a standstill start, until move_off_distance_m: walls (and once rolling, the ground) locate across the track only
  double move_off_distance_m = 10.0;  // move_off_planes_across lasts until the vehicle is this far from where it stood (and 2 keyframes)
  double keyframe_distance_m = 1.0;
  double keyframe_angle_deg = 10.0;
  double hausdorff_threshold_m = 0.6; // h1
  double hausdorff_voxel_m = 1.0;     // clouds are downsampled to this before the Hausdorff test
  int window_keyframes = 200;
  /// A scan whose registration moves the pose further than this from the IMU prediction (squared
  /// Mahalanobis distance over the 6 pose dimensions) is not let to update the biases and gravity.
  double max_prediction_nis = 200.0;
  double degeneracy_eigenvalue = 30.0;  // LiDAR information (weighted residual count) below which a direction is degenerate
  /// After a degenerate scan the forward accelerometer bias and gravity tilt are held, except while
  /// the vehicle turns faster than this (deg/s, IMU yaw rate): the turn separates the two. 0: always held.
  double hold_release_yaw_rate_deg_s = 5.0;
  /// A held forward bias is released only by a scan with this many times degeneracy_eigenvalue of
  /// information along its weakest direction: a gantry's few scans must not release it (hysteresis).
  double hold_release_eigenvalue_factor = 2.0;
  /// While the forward bias is held, the median rate of the LiDAR's forward velocity corrections
  /// over this much held time (s; 0: never), times the gain, is taken off the bias (held_bias_trim.hpp).
  double held_bias_trim_window_s = 20.0;
  double held_bias_trim_gain = 0.5;
  bool degeneracy_projection = false;   // true: degenerate directions get no LiDAR update (else flagged only)
  double init_gyro_bias_std = 0.01;      // rad/s
  /// A start decided a standstill takes the gyro's mean at rest for its bias, known to this (rad/s).
  double standstill_gyro_bias_std = 0.001;
  double init_accel_bias_std = 0.2;      // m/s^2
  double init_velocity_std = 20.0;       // m/s: unknown speed at a rolling start
  double init_tilt_std_deg = 5.0;
};

enum class LoopDistance { k2D, k3D };

/// The backend (issue 5): keyframe pose graph, loop closure, maps. See docs/backend.md.
struct BackendConfig {
  bool enabled = false;
  double loop_radius_m = 10.0;          // candidates within this distance of the current keyframe...
  double loop_time_gap_s = 20.0;        // ...and at least this much older
  LoopDistance loop_distance = LoopDistance::k2D;  // 2d: x-y distance (the paper) | 3d (ablation)
  int loop_candidates = 2;              // candidates verified per keyframe (nearest first, distinct passes)
  int loop_cooldown_keyframes = 3;      // keyframes without loop search after an accepted loop
  int submap_keyframes = 10;            // the candidate's sub-map: candidate +- this many keyframes
  bool similarity_check = true;         // the Hausdorff similarity test before registration (ablation)
  double similarity_threshold_m = 1.0;  // partial Hausdorff distance above which a pair is dissimilar
  double similarity_quantile = 0.8;     // quantile of the nearest distances (1 = classic Hausdorff)
  double similarity_search_m = 3.0;     // coarse alignment search, +- in x and y
  double similarity_search_yaw_deg = 3.0;  // and in yaw
  double loop_max_rms_m = 0.1;          // registration accepted below this point-to-plane rms...
  double loop_min_inlier_fraction = 0.5;  // ...with at least this fraction of the points within 2 rms
  double max_vertical_m = 1.5;          // registered height minus graph height beyond this: false loop
  double max_tilt_deg = 2.0;            // registered vs graph tilt (roll/pitch) beyond this: false loop
  double robust_loss_scale = 3.0;       // Cauchy scale of the loop factors, in sigmas
  double odometry_translation_sigma_m = 0.05;  // odometry factor between consecutive keyframes
  double odometry_rotation_sigma_deg = 0.1;
  double loop_translation_sigma_m = 0.03;      // loop factor: ~2x the registration error measured on the sim drives
  double loop_rotation_sigma_deg = 0.1;
  double tilt_sigma_deg = 0.5;          // gravity (roll/pitch) factor per keyframe; 0 = none
  int max_solver_iterations = 50;
  int solve_window_keyframes = 1000;    // a loop's solve frees at most this many newest keyframes; 0 = all
  double keyframe_voxel_m = 0.3;        // keyframe points kept by the backend (body frame)
  double map_voxel_m = 0.3;             // downsampling of the global map PCD
  bool persist = false;                 // write keyframes + graph to output.state_dir (atomically)
  int memory_keyframes = 200;           // keyframe clouds kept in memory (LRU); others on disk; 0 = all in memory
};

struct OutputConfig {
  std::string pose_socket = "/run/liod/pose.sock";
  std::string state_dir = "/var/lib/liod";
};


// ---- live daemon (issue 6): drivers, time, threads, pose socket ----------------------------
struct LidarDriverConfig {
  std::string bind_address = "0.0.0.0";   // local IPv4 address the MSOP/DIFOP sockets bind to
  std::string multicast_group;             // "" = unicast; else an IPv4 group to join
  std::string multicast_interface = "0.0.0.0";  // local address of the interface that joins the group
  std::string source_address;              // "" = the first RS-Helios sender; else only datagrams from this IPv4 address
  int receive_buffer_bytes = 16 * 1024 * 1024;  // SO_RCVBUF(FORCE): 1 s of MSOP is ~1.9 MB
  int batch = 64;                          // datagrams per recvmmsg call
  double lost_after_s = 0.5;               // no sweep for this long flags "LiDAR lost"
};

enum class ImuTransport { kSerial, kCan, kFile, kNone };
enum class CanProfile { kJ1939, kTable };

/// One CAN signal of the `table` profile: a little/big-endian integer at a byte offset of a
/// frame, value = raw * scale + offset, in the unit liod expects (rad/s or m/s^2).
struct CanSignalConfig {
  std::string quantity;      // gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z
  std::uint32_t can_id = 0;  // 11- or 29-bit identifier (compared after masking with id_mask)
  std::uint32_t id_mask = 0x1FFFFFFF;
  int byte_offset = 0;
  int length_bytes = 2;      // 1, 2 or 4
  bool big_endian = false;
  bool is_signed = false;
  double scale = 1.0;
  double offset = 0.0;
};

struct ImuDriverConfig {
  ImuTransport transport = ImuTransport::kSerial;
  std::string serial_device = "/dev/ttyUSB0";  // Xsens MTi, MTData2 output
  int serial_baud = 921600;
  std::string can_interface = "can0";          // SocketCAN interface
  CanProfile can_profile = CanProfile::kJ1939; // J1939 PGN 61482 (rate) + 61485 (acceleration)
  int j1939_source_address = -1;               // -1 = any sender; else only this J1939 source address
  std::vector<CanSignalConfig> can_signals;    // the `table` profile's layout
  std::string file;                            // transport `file`: an IMU CSV played at `file_pace`
  double file_pace = 1.0;                      // 1 = recorded pace
  double lost_after_s = 0.1;                   // no sample for this long flags "IMU lost"
};

struct DriversConfig {
  LidarDriverConfig lidar;
  ImuDriverConfig imu;
};

enum class LidarClock { kAuto, kSensor, kHost };

struct TimeConfig {
  LidarClock lidar_clock = LidarClock::kAuto;  // auto: sensor time when DIFOP says PTP/GPS synced and it agrees with the host, else host
  double offset_window_s = 2.0;     // host-sensor offset = minimum of (arrival - header) over this window
  double jump_threshold_s = 0.1;    // an offset or host clock step beyond this is a clock jump
  double jump_flag_s = 10.0;        // poses carry the clock_jump flag this long after one
  double imu_wait_s = 0.1;          // a scan waits at most this long (host time) for the IMU to reach its end
  std::string pps_chip;             // "" = no PPS; else a GPIO chip name (e.g. gpiochip0)
  int pps_line = 0;                 // line offset of the PPS input on that chip
};

struct ThreadConfig {
  int priority = 0;  // 0 = normal scheduling; 1..99 = SCHED_FIFO priority (needs CAP_SYS_NICE)
  int cpu = -1;      // -1 = any CPU; else pin to this CPU
};

struct ThreadsConfig {
  ThreadConfig lidar{70, -1};
  ThreadConfig imu{75, -1};
  ThreadConfig odometry{60, -1};
  ThreadConfig publisher{65, -1};
  int backend_nice = 10;            // the backend runs SCHED_OTHER at this nice value
  int scan_ring = 8;                // ring sizes (rounded up to powers of two)
  int imu_ring = 4096;
  int pose_ring = 4096;
  int keyframe_ring = 64;
};

struct PoseSocketConfig {
  std::string mode = "0660";        // permissions of the socket file (octal)
  int max_clients = 32;
  int client_buffer_bytes = 262144; // a client further behind than this skips messages
  double stuck_timeout_s = 2.0;     // a client that accepts nothing for this long is disconnected
  bool imu_rate = true;             // also publish IMU-rate poses
  double imu_rate_horizon_s = 1.0;  // no IMU-rate pose more than this after the last scan update (data time)
  double health_interval_s = 1.0;   // health message period on the socket
  double health_log_interval_s = 10.0;  // health line period in the log
};

struct Config {
  LogConfig log;
  LidarConfig lidar;
  ImuConfig imu;
  ExtrinsicsConfig extrinsics;
  OdometryConfig odometry;
  BackendConfig backend;
  OutputConfig output;
  DriversConfig drivers;
  TimeConfig time;
  ThreadsConfig threads;
  PoseSocketConfig pose_socket;
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
