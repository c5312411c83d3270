#pragma once
// One simulated drive: the scene, the true trajectory, the sensor mounting and models, built
// deterministically from the configuration, and the writer of the run's files.

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "liod/sim/conditions.hpp"
#include "liod/sim/drive.hpp"
#include "liod/sim/hdl64e.hpp"
#include "liod/sim/imu_model.hpp"
#include "liod/sim/lidar_model.hpp"
#include "liod/sim/scene.hpp"
#include "liod/sim/traffic.hpp"
#include "liod/sim/trajectory.hpp"

namespace liod::sim {

inline constexpr const char* kSimVersion = "1.0.0";
// The IMU's random stream: the same samples whatever files they go to (imu.csv, KITTI's OXTS).
inline constexpr std::uint64_t kImuStream = 0x696D75ULL;

/// The LiDAR of the drive: the RS-Helios-5515 as packets in a pcap, or the Velodyne HDL-64E as
/// KITTI recorded it (sweeps as .bin files and the OXTS extract in KITTI raw's layout).
enum class LidarKind { Helios, Hdl64e };

struct SimConfig {
  SceneRequest scene;
  double imu_rate = 200.0;
  bool noise = true;          // false: exact IMU, no LiDAR range noise/bias/angle error
  // The unit's true beam angles differ from its published table by up to this (uniform, per
  // channel); 0 isolates what the rest of the noise costs (docs/design.md, "Beam calibration").
  double angle_error_deg = 0.005;
  bool dual_return = false;
  bool ego_body = true;       // the LiDAR sees the roof and bonnet of its own car
  int threads = 2;
  std::string angles_csv;
  std::string out_dir;
  std::int64_t epoch_s = 1700000000;  // IMU-clock time of the run's t = 0 (UTC seconds)
  // The mounting the seed draws, replaced where set: a drive whose true LiDAR-IMU extrinsic or
  // clock offset is a chosen one (calibration tests). Roll, pitch, yaw in degrees (R = Rz Ry Rx).
  std::optional<Eigen::Vector3d> extrinsic_rpy_deg;
  std::optional<Eigen::Vector3d> extrinsic_translation_m;
  std::optional<double> time_offset_s;
  RoadConditions conditions;  // none by default
  LidarKind lidar = LidarKind::Helios;
  // Hdl64e: the folder that receives KITTI raw's layout (kitti_raw_drive() names the drive in it).
  std::string kitti_dir;
};

/// KITTI raw's layout of the drive under `kitti_dir`: DATE/DATE_drive_NNNN_extract, the date of
/// the run's start (epoch_s) and the seed's last four digits as the drive number.
std::string kitti_raw_drive(const SimConfig& config);

struct RunReport {
  std::uint64_t msop_packets = 0;
  std::uint64_t difop_packets = 0;
  std::uint64_t returns = 0;
  std::uint64_t rays = 0;
  std::uint64_t imu_samples = 0;
  std::uint64_t sweeps = 0;  // HDL-64E turns written
};

class Simulation {
 public:
  explicit Simulation(SimConfig config);

  /// Writes lidar.pcap, imu.csv, groundtruth.tum, extrinsics.yaml and scenario.yaml into out_dir;
  /// with the HDL-64E, KITTI raw's layout into kitti_dir in place of lidar.pcap.
  RunReport write_all(const std::function<void(double)>& progress = {}) const;
  /// Only the LiDAR capture (used by the benchmark).
  RunReport write_lidar(const std::string& path, const std::function<void(double)>& progress = {}) const;

  const SimConfig& config() const { return config_; }
  const Scene& scene() const { return scene_; }
  const Trajectory& trajectory() const { return *trajectory_; }
  const LidarModel& lidar() const { return *lidar_; }  // the Helios (null with the HDL-64E)
  const Hdl64eModel* hdl64e() const { return hdl_.get(); }
  const EgoBody& ego() const { return ego_; }
  const DriveStats& drive_stats() const { return stats_; }
  /// p_imu = R p_lidar + t.
  const Pose& imu_from_lidar() const { return imu_from_lidar_; }
  /// t_imu = t_lidar + offset.
  double time_offset() const { return time_offset_; }
  /// World pose of the LiDAR at IMU-clock time t (seconds after the run's start).
  Pose lidar_pose(double t) const;
  /// The other vehicles (null without --traffic) and the open stretch (if asked for).
  const Traffic* traffic() const { return traffic_.get(); }
  const std::optional<OpenStretch>& open_stretch() const { return open_stretch_; }
  const ImuNoise& imu_noise() const { return imu_noise_; }

 private:
  void write_imu_and_truth(RunReport& report) const;
  void write_yaml(const RunReport& report) const;
  void write_conditions_yaml(std::ostream& s) const;
  void write_helios_yaml(std::ostream& s) const;
  void write_hdl64e_yaml(std::ostream& s) const;
  // KITTI raw's layout (kitti_outputs.cpp).
  RunReport write_kitti_raw(const std::function<void(double)>& progress) const;
  void write_kitti_sweeps(const std::string& drive, RunReport& report, const std::function<void(double)>& progress) const;
  void write_oxts(const std::string& drive) const;

  SimConfig config_;
  Scene scene_;
  std::unique_ptr<Trajectory> trajectory_;
  std::unique_ptr<LidarModel> lidar_;
  std::unique_ptr<Hdl64eModel> hdl_;
  EgoBody ego_;
  DriveStats stats_;
  Pose imu_from_lidar_;
  double time_offset_ = 0.0;
  VehicleParams vehicle_;
  LidarParams lidar_params_;
  LidarNoise lidar_noise_;
  ImuNoise imu_noise_;
  int az_start_step_ = 0;
  std::unique_ptr<Traffic> traffic_;
  std::optional<OpenStretch> open_stretch_;
};

/// "1700000012.345678901" from an integer epoch and a relative time, without double rounding.
std::string format_time(std::int64_t epoch_s, double t);

}  // namespace liod::sim
