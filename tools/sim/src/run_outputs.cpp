// The run's text outputs: imu.csv, groundtruth.tum, extrinsics.yaml and scenario.yaml.

#include <Eigen/Geometry>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <ostream>
#include <numbers>
#include <stdexcept>
#include <string>

#include "liod/sim/simulator.hpp"

namespace liod::sim {

namespace {
struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_out(const std::filesystem::path& p) {
  File f(std::fopen(p.string().c_str(), "wb"));
  if (!f) {
    throw std::runtime_error("cannot create '" + p.string() + "'");
  }
  return f;
}

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string vec(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "[%.10g, %.10g, %.10g]", v.x(), v.y(), v.z());
  return buf;
}
}  // namespace

std::string format_time(std::int64_t epoch_s, double t) {
  const std::int64_t ns = std::llround(t * 1e9);
  const std::int64_t total_sec = epoch_s + (ns >= 0 ? ns / 1000000000 : (ns - 999999999) / 1000000000);
  const std::int64_t frac = ns - (total_sec - epoch_s) * 1000000000;
  char buf[48];
  std::snprintf(buf, sizeof buf, "%" PRId64 ".%09" PRId64, total_sec, frac);
  return buf;
}

RunReport Simulation::write_all(const std::function<void(double)>& progress) const {
  const std::filesystem::path dir(config_.out_dir);
  if (!std::filesystem::is_directory(dir)) {
    throw std::runtime_error("output directory '" + config_.out_dir + "' does not exist");
  }
  RunReport report = config_.lidar == LidarKind::Hdl64e ? write_kitti_raw(progress)
                                                         : write_lidar((dir / "lidar.pcap").string(), progress);
  write_imu_and_truth(report);
  write_yaml(report);
  return report;
}

void Simulation::write_imu_and_truth(RunReport& report) const {
  const std::filesystem::path dir(config_.out_dir);
  File imu = open_out(dir / "imu.csv");
  File gt = open_out(dir / "groundtruth.tum");
  std::fputs("time_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n", imu.get());
  ImuModel model(imu_noise_, config_.imu_rate, derive_seed(config_.scene.seed, kImuStream));
  const auto n = static_cast<std::int64_t>(std::floor(config_.scene.duration * config_.imu_rate + 1e-9));
  Eigen::Quaterniond prev(1, 0, 0, 0);
  for (std::int64_t k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / config_.imu_rate;
    const BodyState s = trajectory_->state(t);
    const ImuReading r = model.measure(s);
    const std::string ts = format_time(config_.epoch_s, t);
    std::fprintf(imu.get(), "%s,%.9e,%.9e,%.9e,%.9e,%.9e,%.9e\n", ts.c_str(), r.gyro.x(), r.gyro.y(),
                 r.gyro.z(), r.accel.x(), r.accel.y(), r.accel.z());
    Eigen::Quaterniond q(s.rotation);
    q.normalize();
    if (q.dot(prev) < 0.0) {
      q.coeffs() *= -1.0;  // keep the sign continuous for naive interpolators
    }
    prev = q;
    std::fprintf(gt.get(), "%s %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", ts.c_str(), s.position.x(),
                 s.position.y(), s.position.z(), q.x(), q.y(), q.z(), q.w());
    ++report.imu_samples;
  }
  if (std::ferror(imu.get()) != 0 || std::ferror(gt.get()) != 0) {
    throw std::runtime_error("write failed in '" + config_.out_dir + "'");
  }
}

void Simulation::write_yaml(const RunReport& report) const {
  const std::filesystem::path dir(config_.out_dir);
  const Eigen::Quaterniond q(imu_from_lidar_.rotation);
  {
    std::ofstream e(dir / "extrinsics.yaml");
    e << "# Written by liod-sim " << kSimVersion << " (route " << route_name(config_.scene.route)
      << ", seed " << config_.scene.seed << ")\n"
      << "extrinsics:\n"
      << "  lidar_to_imu:\n"
      << "    translation_m: " << vec(imu_from_lidar_.translation) << "  # p_imu = R * p_lidar + t\n"
      << "    rotation_xyzw: [" << num(q.x()) << ", " << num(q.y()) << ", " << num(q.z()) << ", "
      << num(q.w()) << "]\n"
      << "  lidar_time_offset_s: " << num(time_offset_) << "  # t_imu = t_lidar + offset\n";
    if (!e) {
      throw std::runtime_error("cannot write extrinsics.yaml in '" + config_.out_dir + "'");
    }
  }
  const SceneRequest& r = config_.scene;
  const double deg = 180.0 / std::numbers::pi;
  const Eigen::Vector3d rpy = imu_from_lidar_.rotation.eulerAngles(2, 1, 0).reverse() * deg;
  std::ofstream s(dir / "scenario.yaml");
  s << "# liod-sim scenario: every parameter of this run. Same seed and options -> same bytes.\n"
    << "version: " << kSimVersion << "\n"
    << "route: " << route_name(r.route) << "\n"
    << "seed: " << r.seed << "\n"
    << (r.route_seed ? "route_seed: " + std::to_string(*r.route_seed) + "\n" : std::string())
    << "duration_s: " << num(r.duration) << "\n"
    << "max_speed_mps: " << num(r.max_speed) << "\n"
    << "start: " << (scene_.plan.static_start_s > 0.0 ? "static" : "rolling") << "\n"
    << "static_start_s: " << num(scene_.plan.static_start_s) << "\n"
    << "noise: " << (config_.noise ? "true" : "false") << "\n"
    << "epoch_s: " << config_.epoch_s << "  # IMU-clock UTC time of t = 0\n"
    << "clocks:\n"
    << "  imu_csv_and_groundtruth: IMU clock\n"
    << "  lidar_packets: LiDAR clock (PTP), t_imu = t_lidar + lidar_time_offset_s\n"
    << "  pcap_record_time: host clock (= IMU clock), packet completion + 0.18 ms + Exp(35 us) latency\n"
    << "world:\n"
    << "  summary: \"" << scene_.summary << "\"\n"
    << "  area_min: [" << num(scene_.world.min_corner().x()) << ", " << num(scene_.world.min_corner().y()) << "]\n"
    << "  area_max: [" << num(scene_.world.max_corner().x()) << ", " << num(scene_.world.max_corner().y()) << "]\n"
    << "  ground_cell_m: " << num(scene_.world.cell_size()) << "\n"
    << "  boxes: " << scene_.world.boxes.size() << "\n"
    << "  cylinders: " << scene_.world.cylinders.size() << "\n"
    << "  porous_ellipsoids: " << scene_.world.ellipsoids.size() << "\n"
    << "  terrain_waves: " << scene_.world.terrain.waves.size() << "\n"
    << "  terrain_hills: " << scene_.world.terrain.hills.size() << "\n"
    << "  road_roughness_iso8608_g0_m3: " << num(scene_.road_roughness) << "\n"
    << "drive:\n"
    << "  distance_m: " << num(stats_.distance) << "\n"
    << "  top_speed_mps: " << num(stats_.top_speed) << "\n"
    << "  peak_lateral_accel_mps2: " << num(stats_.peak_lateral_accel) << "\n"
    << "  peak_accel_mps2: " << num(stats_.peak_long_accel) << "\n"
    << "  peak_decel_mps2: " << num(stats_.peak_decel) << "\n"
    << "  planned_stops: " << scene_.plan.stops.size() << "\n"
    << "  stops: " << stats_.stops << "\n"
    << "vehicle:\n"
    << "  wheelbase_m: " << num(vehicle_.wheelbase) << "\n"
    << "  track_m: " << num(vehicle_.track) << "\n"
    << "  imu_height_above_road_m: " << num(vehicle_.imu_height) << "\n"
    << "  max_lateral_accel_mps2: " << num(vehicle_.max_lateral_accel) << "\n"
    << "  max_accel_mps2: " << num(vehicle_.max_accel) << "\n"
    << "  max_decel_mps2: " << num(vehicle_.max_decel) << "\n"
    << "  max_jerk_mps3: " << num(vehicle_.max_jerk) << "\n"
    << "  body_modes_hz: [" << num(vehicle_.body_heave_hz) << ", " << num(vehicle_.body_pitch_hz) << ", "
    << num(vehicle_.body_roll_hz) << "]  # heave, pitch, roll\n"
    << "  ego_body_visible: " << (config_.ego_body ? "true" : "false") << "\n"
    << "  ego_body_boxes_imu_frame:  # [min xyz, max xyz]; crop these from the scans\n";
  for (std::size_t i = 0; i < ego_.box_min.size(); ++i) {
    s << "    - [" << vec(ego_.box_min[i]) << ", " << vec(ego_.box_max[i]) << "]\n";
  }
  s << "extrinsics:\n"
    << "  lidar_to_imu_translation_m: " << vec(imu_from_lidar_.translation) << "\n"
    << "  lidar_to_imu_rotation_xyzw: [" << num(q.x()) << ", " << num(q.y()) << ", " << num(q.z()) << ", "
    << num(q.w()) << "]\n"
    << "  lidar_to_imu_rpy_deg: " << vec(rpy) << "  # R = Rz(yaw) Ry(pitch) Rx(roll)\n"
    << "  lidar_time_offset_s: " << num(time_offset_) << "\n"
    << "lidar:\n";
  if (hdl_) {
    write_hdl64e_yaml(s);
  } else {
    write_helios_yaml(s);
  }
  const ImuModel probe(imu_noise_, config_.imu_rate, derive_seed(config_.scene.seed, kImuStream));
  s << "imu:\n"
    << "  rate_hz: " << num(config_.imu_rate) << "\n"
    << "  gravity_mps2: 9.80665\n"
    << "  gyro_noise_density_rad_s_sqrthz: " << num(imu_noise_.gyro_noise_density) << "\n"
    << "  gyro_bias_random_walk_rad_s2_sqrthz: " << num(imu_noise_.gyro_bias_random_walk) << "\n"
    << "  gyro_bias_instability_rad_s: " << num(imu_noise_.gyro_bias_instability) << "\n"
    << "  accel_noise_density_mps2_sqrthz: " << num(imu_noise_.accel_noise_density) << "\n"
    << "  accel_bias_random_walk_mps3_sqrthz: " << num(imu_noise_.accel_bias_random_walk) << "\n"
    << "  accel_bias_instability_mps2: " << num(imu_noise_.accel_bias_instability) << "\n"
    << "  bias_correlation_time_s: " << num(imu_noise_.bias_correlation_time) << "\n"
    << "  gyro_scale_sigma: " << num(imu_noise_.gyro_scale_sigma) << "\n"
    << "  accel_scale_sigma: " << num(imu_noise_.accel_scale_sigma) << "\n"
    << "  misalignment_sigma_rad: " << num(imu_noise_.misalignment_sigma) << "\n"
    << "  initial_gyro_bias_rad_s: " << vec(probe.initial_gyro_bias()) << "\n"
    << "  initial_accel_bias_mps2: " << vec(probe.initial_accel_bias()) << "\n";
  if (config_.conditions.any()) {
    write_conditions_yaml(s);
  }
  s << "outputs:\n"
    << "  msop_packets: " << report.msop_packets << "\n"
    << "  difop_packets: " << report.difop_packets << "\n"
    << "  lidar_returns: " << report.returns << "\n"
    << "  imu_samples: " << report.imu_samples << "\n";
  if (hdl_) {
    s << "  kitti_raw_sweeps: " << report.sweeps << "\n"
      << "  kitti_raw_drive: \"" << kitti_raw_drive(config_) << "\"\n";
  }
  if (!s) {
    throw std::runtime_error("cannot write scenario.yaml in '" + config_.out_dir + "'");
  }
}

void Simulation::write_helios_yaml(std::ostream& s) const {
  s << "  model: RS-Helios-5515 (32 beams), 600 rpm, 1800 firings per turn\n"
    << "  return_mode: " << (config_.dual_return ? "dual (strongest, last)" : "single (strongest)") << "\n"
    << "  angles_csv: \"" << config_.angles_csv << "\"\n"
    << "  firing_offsets: nebula measured single-return table (us)\n"
    << "  first_azimuth_step: " << az_start_step_ << "\n"
    << "  max_range_m: " << num(lidar_params_.max_range) << "\n"
    << "  min_range_m: " << num(lidar_params_.min_range) << "\n"
    << "  range_at_10pct_reflectivity_m: " << num(lidar_params_.range_at_10pct) << "\n"
    << "  range_sigma_m: " << num(lidar_noise_.range_sigma) << "  # + per_m * d + weak / sqrt(snr)\n"
    << "  range_sigma_per_m: " << num(lidar_noise_.range_sigma_per_m) << "\n"
    << "  weak_return_sigma_m: " << num(lidar_noise_.weak_return_sigma) << "\n"
    << "  channel_bias_sigma_m: " << num(lidar_noise_.channel_bias_sigma) << "\n"
    << "  angle_error_deg: " << num(lidar_noise_.angle_error_deg) << "  # uniform, true vs published\n"
    << "  random_dropout: " << num(lidar_noise_.random_dropout) << "\n"
    << "  channel_bias_m: [";
  for (int c = 0; c < kChannels; ++c) {
    s << (c ? ", " : "") << num(config_.noise ? lidar_->channel_bias()[static_cast<std::size_t>(c)] : 0.0);
  }
  s << "]\n";
}

void Simulation::write_hdl64e_yaml(std::ostream& s) const {
  const HdlParams p;
  s << "  model: Velodyne HDL-64E S2 (64 beams), 600 rpm, " << kHdlFiringsPerTurn << " firings per turn, counter-clockwise\n"
    << "  output: KITTI raw (velodyne_points/data/*.bin: x y z reflectance, no ring, no time; oxts/ at 100 Hz)\n"
    << "  max_range_m: " << num(p.max_range) << "\n"
    << "  min_range_m: " << num(p.min_range) << "\n"
    << "  range_at_10pct_reflectivity_m: " << num(p.range_at_10pct) << "\n"
    << "  unit_elevation_spread_deg: " << num(p.unit_elevation_spread_deg) << "  # uniform, the unit vs the manual's table\n"
    << "  range_sigma_m: " << num(lidar_noise_.range_sigma) << "  # + per_m * d + weak / sqrt(snr)\n"
    << "  range_sigma_per_m: " << num(lidar_noise_.range_sigma_per_m) << "\n"
    << "  weak_return_sigma_m: " << num(lidar_noise_.weak_return_sigma) << "\n"
    << "  channel_bias_sigma_m: " << num(lidar_noise_.channel_bias_sigma) << "\n"
    << "  angle_error_deg: " << num(lidar_noise_.angle_error_deg) << "  # uniform, true vs calibration file\n"
    << "  random_dropout: " << num(lidar_noise_.random_dropout) << "\n"
    << "  elevations_deg: [";
  for (int l = 0; l < kHdlLasers; ++l) s << (l ? ", " : "") << num(hdl_->true_elevations_deg()[static_cast<std::size_t>(l)]);
  s << "]\n  channel_bias_m: [";
  for (int l = 0; l < kHdlLasers; ++l) s << (l ? ", " : "") << num(hdl_->range_bias()[static_cast<std::size_t>(l)]);
  s << "]\n";
}

void Simulation::write_conditions_yaml(std::ostream& s) const {
  const RoadConditions& c = config_.conditions;
  s << "conditions:  # added to the road (liod-sim --hard and its parts)\n"
    << "  imu_part: " << (c.consumer_imu ? "Bosch BMI088 (data sheet BST-BMI088-DS001)" : "default MEMS unit") << "\n"
    << "  road_vibration_scale: " << num(c.vibration_scale)
    << "  # 1: body bounce 3 Hz 4 mm, wheel hop 11 Hz 0.4 mm, pitch 9 Hz 0.8 mrad, roll 11 Hz 0.4 mrad\n"
    << "  random_dropout: " << num(c.dropout) << "\n"
    << "  rain_returns_per_s: " << num(c.rain_rate) << "\n"
    << "  wind: " << (c.wind ? "true" : "false") << "\n";
  if (traffic_) {
    s << "  traffic_vehicles: " << traffic_->size() << "\n";
  }
  if (open_stretch_) {
    s << "  open_stretch:\n"
      << "    enter_s: " << num(open_stretch_->t_begin) << "\n"
      << "    leave_s: " << num(open_stretch_->t_end) << "\n"
      << "    from_xy: [" << num(open_stretch_->path.front().x()) << ", " << num(open_stretch_->path.front().y()) << "]\n"
      << "    to_xy: [" << num(open_stretch_->path.back().x()) << ", " << num(open_stretch_->path.back().y()) << "]\n"
      << "    primitives_removed: " << open_stretch_->removed << "\n"
      << "    hedge_boxes: " << open_stretch_->hedge << "\n";
  }
}

}  // namespace liod::sim
