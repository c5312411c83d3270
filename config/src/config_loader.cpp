// The one place where configuration is parsed and validated. Every key is declared once, in the
// section of the library that owns it, with its type and admissible values; the loader rejects
// anything else.

#include <fstream>
#include <limits>
#include <sstream>

#include "liod/config.hpp"
#include "liod/map_limits.hpp"
#include "schema.hpp"

namespace liod {
namespace {

using config_schema::fail;
using config_schema::Schema;
using config_schema::Setter;
using config_schema::Source;

// The algorithm's keys (core/algorithm_config.hpp): the IMU's noise, the extrinsics, the front end.
void declare_front_end(Schema& s, FrontEndConfig& c) {
  s.real("imu.rate_hz", &c.imu.rate_hz, 10.0, 10000.0);
  s.real("imu.gyro_noise_density", &c.imu.gyro_noise_density, 1e-7, 1.0);
  s.real("imu.accel_noise_density", &c.imu.accel_noise_density, 1e-6, 10.0);
  s.real("imu.gyro_bias_random_walk", &c.imu.gyro_bias_random_walk, 1e-9, 1.0);
  s.real("imu.accel_bias_random_walk", &c.imu.accel_bias_random_walk, 1e-9, 10.0);
  s.real("imu.gravity_m_s2", &c.imu.gravity_m_s2, 9.7, 9.9);
  s.real("imu.max_gap_s", &c.imu.max_gap_s, 0.001, 10.0);
  s.real("imu.gyro_range_rad_s", &c.imu.gyro_range_rad_s, 1.0, 1000.0);
  s.real("imu.accel_range_m_s2", &c.imu.accel_range_m_s2, 10.0, 10000.0);

  s.vector3("extrinsics.lidar_to_imu.translation_m", &c.extrinsics.lidar_to_imu_translation, 10.0);
  s.quaternion("extrinsics.lidar_to_imu.rotation_xyzw", &c.extrinsics.lidar_to_imu_rotation);
  s.real("extrinsics.lidar_time_offset_s", &c.extrinsics.lidar_time_offset_s, -1.0, 1.0);

  auto& o = c.odometry;
  s.choice("odometry.deskew", &o.deskew,
           {{"imu", DeskewMode::kImu}, {"constant_velocity", DeskewMode::kConstantVelocity}, {"none", DeskewMode::kNone}});
  s.choice("odometry.curvature", &o.curvature,
           {{"adaptive", CurvatureMode::kAdaptive}, {"fixed", CurvatureMode::kFixed}});
  s.choice("odometry.keyframe_gating", &o.keyframe_gating,
           {{"hausdorff", KeyframeGating::kHausdorff}, {"distance_angle", KeyframeGating::kDistanceAngle}});
  s.choice("odometry.edge_residual", &o.edge_residual,
           {{"along_ray", EdgeResidual::kAlongRay}, {"point_to_line", EdgeResidual::kPointToLine}});
  s.real("odometry.min_range_m", &o.min_range_m, 0.0, 50.0);
  s.real("odometry.max_range_m", &o.max_range_m, 5.0, 500.0);
  s.vector3("odometry.crop_box_min_m", &o.crop_box_min_m, 50.0);
  s.vector3("odometry.crop_box_max_m", &o.crop_box_max_m, 50.0);
  s.vector3("odometry.forward_axis", &o.forward_axis, 1.0);
  s.vector3("odometry.up_axis", &o.up_axis, 1.0);
  s.real("odometry.vertical_velocity_std_mps", &o.vertical_velocity_std_mps, 0.0, 10.0);
  s.real("odometry.extrinsics_check_s", &o.extrinsics_check_s, 0.0, 3600.0);
  s.real("odometry.occlusion_jump_m", &o.occlusion_jump_m, 0.01, 10.0);
  s.real("odometry.edge_curvature", &o.edge_curvature, 0.0, 10.0);
  s.real("odometry.plane_curvature", &o.plane_curvature, 0.0, 10.0);
  s.integer("odometry.sectors_per_ring", &o.sectors_per_ring, 1, 64);
  s.integer("odometry.max_edges_per_sector", &o.max_edges_per_sector, 0, 1000);
  s.real("odometry.plane_voxel_m", &o.plane_voxel_m, 0.01, 5.0);
  s.real("odometry.edge_voxel_m", &o.edge_voxel_m, 0.01, 5.0);
  s.real("odometry.map_voxel_m", &o.map_voxel_m, 0.1, 10.0);
  s.integer("odometry.map_points_per_voxel", &o.map_points_per_voxel, 1, kMapMaxPointsPerVoxel);
  s.real("odometry.map_min_point_spacing_m", &o.map_min_point_spacing_m, 0.0, 5.0);
  s.integer("odometry.map_min_observations", &o.map_min_observations, 1, 10);
}

// The front end's registration, keyframes, holds and priors.
void declare_registration(Schema& s, OdometryConfig& o) {
  constexpr double kInf = std::numeric_limits<double>::max();
  s.integer("odometry.max_iterations", &o.max_iterations, 1, 50);
  s.integer("odometry.forced_searches", &o.forced_searches, 1, 50);
  s.real("odometry.lidar_noise_m", &o.lidar_noise_m, 1e-4, 10.0);
  s.real("odometry.max_correspondence_m", &o.max_correspondence_m, 0.05, 20.0);
  s.integer("odometry.correspondence_neighbours", &o.correspondence_neighbours, 3, kMapMaxNeighbours);
  s.real("odometry.correspondence_gate_m", &o.correspondence_gate_m, 0.05, 20.0);
  s.real("odometry.plane_thickness_m", &o.plane_thickness_m, 1e-4, 10.0);
  s.boolean("odometry.fit_uncertainty", &o.fit_uncertainty);
  s.boolean("odometry.post_edges", &o.post_edges);
  s.real("odometry.post_max_width_m", &o.post_max_width_m, 0.0, 2.0);
  s.real("odometry.crossing_edge_tolerance_m", &o.crossing_edge_tolerance_m, 0.0, 1.0);
  s.boolean("odometry.move_off_planes_across", &o.move_off_planes_across);
  s.boolean("odometry.beam_calibration", &o.beam_calibration);
  s.boolean("odometry.beam_range_calibration", &o.beam_range_calibration);
  s.real("odometry.keyframe_distance_m", &o.keyframe_distance_m, 0.0, 100.0);
  s.real("odometry.keyframe_angle_deg", &o.keyframe_angle_deg, 0.0, 180.0);
  s.real("odometry.hausdorff_threshold_m", &o.hausdorff_threshold_m, 0.0, 100.0);
  s.real("odometry.hausdorff_voxel_m", &o.hausdorff_voxel_m, 0.05, 10.0);
  s.integer("odometry.window_keyframes", &o.window_keyframes, 1, 1000);
  s.real("odometry.degeneracy_eigenvalue", &o.degeneracy_eigenvalue, 0.0, kInf);
  s.real("odometry.hold_release_yaw_rate_deg_s", &o.hold_release_yaw_rate_deg_s, 0.0, 360.0);
  s.boolean("odometry.degeneracy_projection", &o.degeneracy_projection);
  s.real("odometry.init_gyro_bias_std", &o.init_gyro_bias_std, 1e-6, 1.0);
  s.real("odometry.init_accel_bias_std", &o.init_accel_bias_std, 1e-6, 10.0);
  s.real("odometry.init_velocity_std", &o.init_velocity_std, 1e-3, 100.0);
  s.real("odometry.init_tilt_std_deg", &o.init_tilt_std_deg, 0.01, 45.0);
}

void declare_backend(Schema& s, BackendConfig& b) {
  s.boolean("backend.enabled", &b.enabled);
  s.real("backend.loop_radius_m", &b.loop_radius_m, 0.5, 1000.0);
  s.real("backend.loop_time_gap_s", &b.loop_time_gap_s, 0.0, 86400.0);
  s.choice("backend.loop_distance", &b.loop_distance, {{"2d", LoopDistance::k2D}, {"3d", LoopDistance::k3D}});
  s.integer("backend.loop_candidates", &b.loop_candidates, 1, 20);
  s.integer("backend.loop_cooldown_keyframes", &b.loop_cooldown_keyframes, 0, 10000);
  s.integer("backend.submap_keyframes", &b.submap_keyframes, 1, 200);
  s.boolean("backend.similarity_check", &b.similarity_check);
  s.real("backend.similarity_threshold_m", &b.similarity_threshold_m, 0.05, 50.0);
  s.real("backend.similarity_quantile", &b.similarity_quantile, 0.1, 1.0);
  s.real("backend.similarity_search_m", &b.similarity_search_m, 0.0, 20.0);
  s.real("backend.similarity_search_yaw_deg", &b.similarity_search_yaw_deg, 0.0, 45.0);
  s.real("backend.loop_max_rms_m", &b.loop_max_rms_m, 0.005, 5.0);
  s.real("backend.loop_min_inlier_fraction", &b.loop_min_inlier_fraction, 0.0, 1.0);
  s.real("backend.max_vertical_m", &b.max_vertical_m, 0.05, 100.0);
  s.real("backend.max_tilt_deg", &b.max_tilt_deg, 0.05, 90.0);
  s.real("backend.robust_loss_scale", &b.robust_loss_scale, 0.0, 1000.0);
  s.choice("backend.odometry_weights", &b.odometry_weights,
           {{"covariance", OdometryWeights::kCovariance}, {"fixed", OdometryWeights::kFixed}});
  s.real("backend.odometry_translation_sigma_m", &b.odometry_translation_sigma_m, 1e-4, 100.0);
  s.real("backend.odometry_rotation_sigma_deg", &b.odometry_rotation_sigma_deg, 1e-4, 90.0);
  s.real("backend.loop_translation_sigma_m", &b.loop_translation_sigma_m, 1e-4, 100.0);
  s.real("backend.loop_rotation_sigma_deg", &b.loop_rotation_sigma_deg, 1e-4, 90.0);
  s.real("backend.tilt_sigma_deg", &b.tilt_sigma_deg, 0.0, 90.0);
  s.boolean("backend.imu_factors", &b.imu_factors);
  s.integer("backend.max_solver_iterations", &b.max_solver_iterations, 1, 10000);
  s.integer("backend.solve_window_keyframes", &b.solve_window_keyframes, 0, 100000000);
  s.real("backend.keyframe_voxel_m", &b.keyframe_voxel_m, 0.01, 10.0);
  s.real("backend.map_voxel_m", &b.map_voxel_m, 0.01, 10.0);
  s.boolean("backend.persist", &b.persist);
  s.integer("backend.memory_keyframes", &b.memory_keyframes, 0, 1000000);
  s.choice("backend.mode", &b.mode, {{"map", BackendMode::kMap}, {"localise", BackendMode::kLocalize}});
}

// The drivers' keys (drivers/sensor_config.hpp).
void declare_sensors(Schema& s, SensorConfig& c) {
  s.choice("lidar.model", &c.lidar.model,
           {{"helios5515", LidarModel::kHelios5515}, {"helios16p", LidarModel::kHelios16P}});
  s.integer("lidar.msop_port", &c.lidar.msop_port, 1, 65535);
  s.integer("lidar.difop_port", &c.lidar.difop_port, 1, 65535);
  s.text("lidar.angles_csv", &c.lidar.angles_csv);
  s.real("lidar.min_range_m", &c.lidar.min_range_m, 0.0, 10.0);
  s.real("lidar.max_range_m", &c.lidar.max_range_m, 1.0, 500.0);
  s.real("lidar.split_azimuth_deg", &c.lidar.split_azimuth_deg, 0.0, 359.99);
  s.integer("lidar.packets_before_difop", &c.lidar.packets_before_difop, 0, 65536);
  s.choice("lidar.calibration_updates", &c.lidar.calibration_updates,
           {{"pin", CalibrationUpdates::kPin}, {"follow", CalibrationUpdates::kFollow}});

  auto& dl = c.drivers.lidar;
  s.text("drivers.lidar.bind_address", &dl.bind_address);
  s.text("drivers.lidar.multicast_group", &dl.multicast_group);
  s.text("drivers.lidar.multicast_interface", &dl.multicast_interface);
  s.text("drivers.lidar.source_address", &dl.source_address);
  s.integer("drivers.lidar.receive_buffer_bytes", &dl.receive_buffer_bytes, 65536, 1 << 30);
  s.integer("drivers.lidar.batch", &dl.batch, 1, 1024);
  s.real("drivers.lidar.lost_after_s", &dl.lost_after_s, 0.05, 60.0);
  auto& di = c.drivers.imu;
  s.choice("drivers.imu.transport", &di.transport,
           {{"serial", ImuTransport::kSerial}, {"can", ImuTransport::kCan}, {"file", ImuTransport::kFile},
            {"none", ImuTransport::kNone}});
  s.text("drivers.imu.serial_device", &di.serial_device);
  s.integer("drivers.imu.serial_baud", &di.serial_baud, 9600, 4000000);
  s.text("drivers.imu.can_interface", &di.can_interface);
  s.choice("drivers.imu.can_profile", &di.can_profile, {{"j1939", CanProfile::kJ1939}, {"table", CanProfile::kTable}});
  s.integer("drivers.imu.j1939_source_address", &di.j1939_source_address, -1, 255);
  s.can_signals("drivers.imu.can_signals", &di.can_signals);
  s.text("drivers.imu.file", &di.file);
  s.real("drivers.imu.file_pace", &di.file_pace, 0.01, 1000.0);
  s.real("drivers.imu.lost_after_s", &di.lost_after_s, 0.005, 60.0);

  s.choice("time.lidar_clock", &c.time.lidar_clock,
           {{"auto", LidarClock::kAuto}, {"sensor", LidarClock::kSensor}, {"host", LidarClock::kHost}});
  s.real("time.offset_window_s", &c.time.offset_window_s, 0.1, 600.0);
  s.real("time.jump_threshold_s", &c.time.jump_threshold_s, 0.001, 3600.0);
  s.real("time.jump_flag_s", &c.time.jump_flag_s, 0.0, 3600.0);
  s.real("time.imu_wait_s", &c.time.imu_wait_s, 0.0, 5.0);
  s.text("time.pps_chip", &c.time.pps_chip);
  s.integer("time.pps_line", &c.time.pps_line, 0, 1023);

}

// The daemon's keys (daemon/daemon_config.hpp).
void declare_daemon(Schema& s, DaemonConfig& c) {
  s.text("log.level", &c.log.level);
  s.text("output.pose_socket", &c.output.pose_socket);
  s.text("output.state_dir", &c.output.state_dir);


  for (auto [name, t] : {std::pair{"lidar", &c.threads.lidar}, std::pair{"imu", &c.threads.imu},
                         std::pair{"odometry", &c.threads.odometry}, std::pair{"publisher", &c.threads.publisher}}) {
    s.integer(std::string("threads.") + name + ".priority", &t->priority, 0, 99);
    s.integer(std::string("threads.") + name + ".cpu", &t->cpu, -1, 1023);
  }
  s.integer("threads.backend_nice", &c.threads.backend_nice, -20, 19);
  s.integer("threads.scan_ring", &c.threads.scan_ring, 2, 1024);
  s.integer("threads.imu_ring", &c.threads.imu_ring, 16, 1 << 20);
  s.integer("threads.pose_ring", &c.threads.pose_ring, 16, 1 << 20);
  s.integer("threads.keyframe_ring", &c.threads.keyframe_ring, 2, 65536);
  s.real("threads.backend_max_lag_s", &c.threads.backend_max_lag_s, 0.1, 3600.0);
  s.real("threads.backend_work_limit_s", &c.threads.backend_work_limit_s, 1.0, 3600.0);
  s.real("threads.scan_max_lag_s", &c.threads.scan_max_lag_s, 0.0, 3600.0);
  s.boolean("threads.lock_memory", &c.threads.lock_memory);


  s.text("pose_socket.mode", &c.pose_socket.mode);
  s.integer("pose_socket.max_clients", &c.pose_socket.max_clients, 1, 4096);
  s.integer("pose_socket.client_buffer_bytes", &c.pose_socket.client_buffer_bytes, 4096, 1 << 28);
  s.real("pose_socket.stuck_timeout_s", &c.pose_socket.stuck_timeout_s, 0.01, 3600.0);
  s.real("pose_socket.imu_rate_horizon_s", &c.pose_socket.imu_rate_horizon_s, 0.01, 10.0);
  s.boolean("pose_socket.imu_rate", &c.pose_socket.imu_rate);
  s.real("pose_socket.health_interval_s", &c.pose_socket.health_interval_s, 0.05, 3600.0);
  s.real("pose_socket.health_log_interval_s", &c.pose_socket.health_log_interval_s, 0.0, 86400.0);
  s.real("pose_socket.max_speed_mps", &c.pose_socket.max_speed_mps, 1.0, 1000.0);
  s.real("pose_socket.max_gyro_bias_rad_s", &c.pose_socket.max_gyro_bias_rad_s, 1e-4, 10.0);
  s.real("pose_socket.max_accel_bias_m_s2", &c.pose_socket.max_accel_bias_m_s2, 1e-3, 100.0);
  s.real("pose_socket.stale_after_s", &c.pose_socket.stale_after_s, 0.001, 3600.0);
  s.integer("viewer.foxglove_port", &c.viewer.foxglove_port, 0, 65535);
  s.text("viewer.bind_address", &c.viewer.bind_address);
  s.integer("viewer.max_clients", &c.viewer.max_clients, 1, 256);
  s.integer("viewer.client_queue_bytes", &c.viewer.client_queue_bytes, 65536, 1 << 30);
  s.real("viewer.map_interval_s", &c.viewer.map_interval_s, 0.05, 3600.0);
  s.real("viewer.map_voxel_m", &c.viewer.map_voxel_m, 0.05, 100.0);
  s.real("viewer.scan_voxel_m", &c.viewer.scan_voxel_m, 0.0, 100.0);
}

Schema declare_schema(Config& c) {
  Schema s;
  declare_front_end(s, c);
  declare_registration(s, c.odometry);
  declare_backend(s, c.backend);
  declare_sensors(s, c);
  declare_daemon(s, c);
  return s;
}

void apply(const Schema& schema, const YAML::Node& node, const std::string& prefix, const std::string& file) {
  if (!node.IsMap()) {
    const Source src{file, prefix.empty() ? "<top level>" : prefix, node};
    fail(src, "must be a mapping of keys");
  }
  for (const auto& entry : node) {
    if (!entry.first.IsScalar()) {  // YAML's "? [a, b]: ..." complex keys name nothing liod knows
      fail(Source{file, prefix.empty() ? "<top level>" : prefix, entry.first}, "keys must be plain names");
    }
    const std::string key = prefix.empty() ? entry.first.as<std::string>() : prefix + "." + entry.first.as<std::string>();
    const YAML::Node& value = entry.second;
    if (const Setter* setter = schema.find(key)) {
      (*setter)(Source{file, key, value});
    } else if (value.IsMap()) {
      apply(schema, value, key, file);
    } else {
      fail(Source{file, key, value}, "unknown key (config/liod.yaml and config/examples/advanced.yaml list the keys liod knows)");
    }
  }
}

void validate_relations(const Config& c, const std::string& origin) {
  auto reject = [&](const std::string& key, double value, const std::string& why) {
    std::ostringstream msg;
    msg << origin << ": key '" << key << "' = '" << value << "': " << why;
    throw ConfigError(msg.str());
  };
  if (c.lidar.max_range_m <= c.lidar.min_range_m) {
    reject("lidar.max_range_m", c.lidar.max_range_m, "must exceed lidar.min_range_m");
  }
  if (c.odometry.max_range_m <= c.odometry.min_range_m) {
    reject("odometry.max_range_m", c.odometry.max_range_m, "must exceed odometry.min_range_m");
  }
  if (c.odometry.max_correspondence_m > c.odometry.map_voxel_m) {
    reject("odometry.max_correspondence_m", c.odometry.max_correspondence_m,
           "must not exceed odometry.map_voxel_m (neighbours are searched in the adjacent voxels)");
  }
  if (c.odometry.correspondence_gate_m > c.odometry.map_voxel_m) {
    reject("odometry.correspondence_gate_m", c.odometry.correspondence_gate_m,
           "must not exceed odometry.map_voxel_m (neighbours are searched in the adjacent voxels)");
  }
  if (std::abs(c.odometry.forward_axis.norm() - 1.0) > 0.01) {
    reject("odometry.forward_axis", c.odometry.forward_axis.norm(),
           "must be a unit vector, the vehicle's forward direction in the IMU frame (the value shown is its length)");
  }
  if (std::abs(c.odometry.up_axis.norm() - 1.0) > 0.01) {
    reject("odometry.up_axis", c.odometry.up_axis.norm(),
           "must be a unit vector, the vehicle's up direction in the IMU frame (the value shown is its length)");
  }
  if (std::abs(c.odometry.up_axis.dot(c.odometry.forward_axis)) > 0.02) {
    reject("odometry.up_axis", c.odometry.up_axis.dot(c.odometry.forward_axis),
           "must be orthogonal to odometry.forward_axis (the value shown is their dot product)");
  }
  if (c.odometry.plane_curvature >= c.odometry.edge_curvature) {
    reject("odometry.plane_curvature", c.odometry.plane_curvature, "must be below odometry.edge_curvature");
  }
  {
    // The socket mode is written in octal as in chmod; only permission bits are allowed.
    const std::string& m = c.pose_socket.mode;
    const bool octal = !m.empty() && m.size() <= 4 && m.find_first_not_of("01234567") == std::string::npos;
    if (!octal) {
      throw ConfigError(origin + ": key 'pose_socket.mode' = '" + m + "': must be octal permission bits, e.g. 0660");
    }
  }
  if (c.drivers.imu.transport == ImuTransport::kCan && c.drivers.imu.can_profile == CanProfile::kTable) {
    // An axis the table never receives would read 0 as if measured; the decoder emits no sample without it.
    for (const char* q : {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"}) {
      bool mapped = false;
      for (const auto& sig : c.drivers.imu.can_signals) mapped = mapped || sig.quantity == q;
      if (!mapped) {
        throw ConfigError(origin + ": key 'drivers.imu.can_signals': the table profile needs a signal for each of "
                          "gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z (" + q + " has none)");
      }
    }
  }
  static const char* kLevels[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  bool level_ok = false;
  for (const char* level : kLevels) level_ok = level_ok || c.log.level == level;
  if (!level_ok) {
    throw ConfigError(origin + ": key 'log.level' = '" + c.log.level +
                      "': must be one of trace, debug, info, warn, error, critical, off");
  }
}

void apply_text(Config& config, const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  if (root.IsNull()) return;  // an empty file changes nothing
  const Schema schema = declare_schema(config);
  apply(schema, root, "", origin);
}

}  // namespace

Config load_config_from_string(const std::string& yaml_text, const std::string& origin) {
  Config config;
  apply_text(config, yaml_text, origin);
  validate_relations(config, origin);
  return config;
}

Config load_config(const std::vector<std::string>& paths) {
  Config config;
  std::string origins;
  for (const auto& path : paths) {
    std::ifstream in(path);
    if (!in) throw ConfigError(path + ": cannot open configuration file");
    std::ostringstream text;
    text << in.rdbuf();
    apply_text(config, text.str(), path);
    origins += (origins.empty() ? "" : " + ") + path;
  }
  validate_relations(config, origins.empty() ? "<defaults>" : origins);
  return config;
}

}  // namespace liod
