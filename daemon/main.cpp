// liod: the one command-line entry point. Each subcommand parses its options, loads and
// validates the configuration (exiting non-zero before doing anything on an error), then runs.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <iostream>

#include "liod/config.hpp"
#include "liod/daemon/calibrate_command.hpp"
#include "liod/daemon/decode_command.hpp"
#include "liod/daemon/logging.hpp"
#include "liod/daemon/map_export.hpp"
#include "liod/daemon/replay.hpp"
#include "liod/daemon/run_command.hpp"

namespace {

constexpr int kConfigErrorExit = 2;

int check_config(const std::vector<std::string>& paths) {
  liod::load_config(paths);
  std::cout << "configuration OK:";
  for (const auto& p : paths) std::cout << ' ' << p;
  std::cout << '\n';
  return 0;
}

// Each subcommand's options, filled by CLI11.
struct Commands {
  CLI::App* check = nullptr;
  std::vector<std::string> check_paths;
  CLI::App* decode = nullptr;
  liod::DecodeOptions decode_options;
  CLI::App* replay = nullptr;
  std::vector<std::string> replay_configs;
  liod::ReplayOptions replay_options;
  CLI::App* run = nullptr;
  std::vector<std::string> run_configs;
  liod::RunOptions run_options;
  CLI::App* record = nullptr;
  std::vector<std::string> record_configs;
  liod::RunOptions record_options;
  CLI::App* pose = nullptr;
  liod::PoseCommandOptions pose_options;
  std::vector<std::string> pose_configs;
  std::string pose_format = "text";
  CLI::App* map_export = nullptr;
  liod::MapExportOptions map_export_options;
  CLI::App* calibrate = nullptr;
  std::vector<std::string> calibrate_configs;
  liod::CalibrateOptions calibrate_options;
};

liod::PoseFormat pose_format(const std::string& name) {
  if (name == "json") return liod::PoseFormat::Json;
  if (name == "csv") return liod::PoseFormat::Csv;
  if (name == "tum") return liod::PoseFormat::Tum;
  return liod::PoseFormat::Text;
}

void add_replay_command(CLI::App& app, Commands& c) {
  c.replay = app.add_subcommand("replay", "Run a recorded drive (LiDAR pcap + IMU CSV, a KITTI raw drive, or a ROS bag) through the odometry");
  auto& r = c.replay_options;
  c.replay->add_option("--config", c.replay_configs, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);
  auto* pcap = c.replay->add_option("--pcap", r.pcap, "LiDAR packets (pcap or pcapng)")->check(CLI::ExistingFile);
  auto* imu = c.replay->add_option("--imu", r.imu_csv, "IMU log (CSV, see README)")->check(CLI::ExistingFile);
  auto* kitti = c.replay->add_option("--kitti-raw", r.kitti_raw,
                                     "a KITTI raw drive's folder (velodyne_points/, oxts/, calib_imu_to_velo.txt here or in its parent) "
                                     "instead of --pcap and --imu")->check(CLI::ExistingDirectory);
  auto* bag = c.replay->add_option("--bag", r.bag, "a ROS 1 bag (.bag) or an MCAP file (.mcap, ROS 2) instead of --pcap and --imu: "
                                                  "sensor_msgs/PointCloud2 and sensor_msgs/Imu on the topics below")->check(CLI::ExistingFile);
  auto* lidar_topic = c.replay->add_option("--lidar-topic", r.lidar_topic, "--bag: the point clouds' topic")->needs(bag);
  auto* imu_topic = c.replay->add_option("--imu-topic", r.imu_topic, "--bag: the IMU's topic")->needs(bag);
  bag->needs(lidar_topic)->needs(imu_topic);
  kitti->excludes(pcap)->excludes(imu)->excludes(bag);
  bag->excludes(pcap)->excludes(imu);
  pcap->needs(imu);
  imu->needs(pcap);
  c.replay->callback([pcap, kitti, bag] {
    if (pcap->count() == 0 && kitti->count() == 0 && bag->count() == 0) {
      throw CLI::RequiredError("--pcap and --imu, --kitti-raw, or --bag with --lidar-topic and --imu-topic,");
    }
  });
  c.replay->add_option("--trajectory", r.trajectory_tum, "output: scan-rate poses, TUM format")->required();
  c.replay->add_option("--imu-rate-trajectory", r.imu_rate_tum, "output: IMU-rate poses, TUM format");
  c.replay->add_option("--map-frame-trajectory", r.map_frame_tum,
                       "output: scan-rate map-frame poses as published (those placed in the map), TUM format");
  c.replay->add_option("--scan-log", r.scan_log_csv, "output: per-scan status, features and timings (CSV)");
  c.replay->add_flag("!--no-progress", r.progress, "no progress bar (one is drawn only on a terminal)");
  r.progress = true;
  c.replay->add_option("--pace", r.pace, "replay at this multiple of the recorded pace (1 = as recorded); default: as fast as possible, deterministic")->check(CLI::Range(0.0, 1000.0));
  c.replay->add_option("--pose-socket", r.pose_socket, "also serve the poses on this Unix socket (see docs/pose-protocol.md)");
  c.replay->add_option("--foxglove", r.foxglove_port, "the live view: a Foxglove WebSocket server on this port (with --pace 1 to watch at the recorded pace)")
      ->check(CLI::Range(1, 65535));
}

void add_offline_commands(CLI::App& app, Commands& c) {
  c.check = app.add_subcommand("check-config", "Load and validate configuration files, then exit");
  c.check->add_option("--config", c.check_paths, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);

  c.decode = app.add_subcommand("decode", "Decode RS-Helios packets from a pcap into sweeps (PCD)");
  c.decode->add_option("--pcap", c.decode_options.pcap, "capture file (pcap or pcapng)")->required();
  c.decode->add_option("--angles", c.decode_options.angles_csv, "calibration CSV (vertical_deg,horizontal_deg) used until a DIFOP arrives");
  c.decode->add_option("--out", c.decode_options.out_dir, "directory for one PCD file per sweep");

  c.calibrate = app.add_subcommand("calibrate", "Estimate the LiDAR-IMU extrinsic and time offset from a recorded drive with turns");
  auto& k = c.calibrate_options;
  c.calibrate->add_option("--config", c.calibrate_configs, "configuration file(s), later ones override; their extrinsics are the starting guess")->required()->check(CLI::ExistingFile);
  c.calibrate->add_option("--pcap", k.pcap, "LiDAR packets (pcap or pcapng)")->required()->check(CLI::ExistingFile);
  c.calibrate->add_option("--imu", k.imu_csv, "IMU log (CSV, see README)")->required()->check(CLI::ExistingFile);
  c.calibrate->add_option("--out", k.out, "output: the extrinsics as a config fragment (YAML)")->required();
  c.calibrate->add_option("--passes", k.passes, "odometry passes, each with the previous estimate")->capture_default_str()->check(CLI::Range(1, 10));
}

void add_map_commands(CLI::App& app, Commands& c) {
  CLI::App* map = app.add_subcommand("map", "Work with a state directory's map (backend.persist)");
  map->require_subcommand(1);
  c.map_export = map->add_subcommand("export", "Write the global map of every run in a state directory as a binary PCD");
  auto& m = c.map_export_options;
  m.voxel_m = liod::BackendConfig{}.map_voxel_m;
  c.map_export->add_option("--state", m.state_dir, "state directory (output.state_dir)")->required()->check(CLI::ExistingDirectory);
  c.map_export->add_option("--out", m.out, "output PCD file")->required();
  c.map_export->add_option("--voxel", m.voxel_m, "voxel size of the merged map in m; 0 = every stored point")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
}

void add_live_commands(CLI::App& app, Commands& c) {
  c.run = app.add_subcommand("run", "The live daemon: sensor drivers, odometry, pose socket (systemd: Type=notify)");
  c.run->add_option("--config", c.run_configs, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);
  c.run->add_option("--max-seconds", c.run_options.max_seconds, "stop by itself after this long (tests)");

  c.record = app.add_subcommand("record", "Run live and also write what the drivers receive (lidar.pcap + imu.csv) for replay");
  c.record->add_option("--config", c.record_configs, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);
  c.record->add_option("--out", c.record_options.record_dir, "output directory (created)")->required();
  c.record->add_option("--max-seconds", c.record_options.max_seconds, "stop by itself after this long");

  c.pose = app.add_subcommand("pose", "Print the poses a running liod publishes");
  auto& p = c.pose_options;
  c.pose->add_option("--socket", p.socket, "pose socket path (default: output.pose_socket of --config, else /run/liod/pose.sock)");
  c.pose->add_option("--config", c.pose_configs, "configuration file(s) to take the socket path from")->check(CLI::ExistingFile);
  c.pose->add_option("--format", c.pose_format,
                     "text (default): one line a pose; json: the server's JSON lines; csv: a header, then one row a pose "
                     "(exact numbers); tum: `t x y z qx qy qz qw`, scan-rate poses only")
      ->check(CLI::IsMember({"text", "json", "csv", "tum"}));
  c.pose->add_flag_callback("--json", [&c] { c.pose_format = "json"; }, "the same as --format json");
  c.pose->add_flag("--scan-only", p.scan_only, "scan-rate poses only");
  c.pose->add_flag("--map-frame", p.map_frame, "tum: the map-frame poses (loop-corrected) instead of the odometry frame's");
  c.pose->add_flag("--health", p.health, "also print health messages");
  c.pose->add_option("--count", p.count, "exit after this many poses");
  c.pose->add_option("--timeout", p.timeout_s, "exit after this many seconds without a message");
}

liod::Config load(const std::vector<std::string>& paths, const std::string& log_level) {
  liod::Config config = liod::load_config(paths);
  if (log_level.empty()) spdlog::set_level(spdlog::level::from_str(config.log.level));
  return config;
}

int dispatch(Commands& c, const std::string& log_level) {
  if (*c.check) return check_config(c.check_paths);
  if (*c.decode) return liod::run_decode(c.decode_options, std::cout);
  if (*c.map_export) return liod::run_map_export(c.map_export_options, std::cout);
  if (*c.replay) return liod::run_replay(load(c.replay_configs, log_level), c.replay_options, std::cout);
  if (*c.calibrate) return liod::run_calibrate(load(c.calibrate_configs, log_level), c.calibrate_options, std::cout);
  if (*c.run) return liod::run_daemon(load(c.run_configs, log_level), c.run_options);
  if (*c.record) return liod::run_daemon(load(c.record_configs, log_level), c.record_options);
  if (*c.pose) {
    if (c.pose_options.socket.empty()) {
      c.pose_options.socket =
          c.pose_configs.empty() ? liod::Config{}.output.pose_socket : liod::load_config(c.pose_configs).output.pose_socket;
    }
    c.pose_options.format = pose_format(c.pose_format);
    return liod::run_pose_client(c.pose_options, std::cout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"liod " LIOD_VERSION ": LiDAR-inertial odometry and SLAM for the RS-Helios + IMU, without ROS"};
  app.set_version_flag("--version", "liod " LIOD_VERSION);
  app.require_subcommand(1);
  std::string log_level;
  app.add_option("--log-level", log_level, "trace|debug|info|warn|error|critical|off (overrides log.level)");
  Commands commands;
  add_offline_commands(app, commands);
  add_replay_command(app, commands);
  add_live_commands(app, commands);
  add_map_commands(app, commands);
  CLI11_PARSE(app, argc, argv);

  try {
    liod::setup_logging(log_level.empty() ? "info" : log_level);
    return dispatch(commands, log_level);
  } catch (const liod::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kConfigErrorExit;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
