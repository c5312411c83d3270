// liod: the one command-line entry point. Each subcommand parses its options, loads and
// validates the configuration (exiting non-zero before doing anything on an error), then runs.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <iostream>

#include "liod/config.hpp"
#include "liod/daemon/decode_command.hpp"
#include "liod/daemon/logging.hpp"
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"liod " LIOD_VERSION ": LiDAR-inertial odometry and SLAM for the RS-Helios + IMU, without ROS"};
  app.set_version_flag("--version", "liod " LIOD_VERSION);
  app.require_subcommand(1);
  std::string log_level;
  app.add_option("--log-level", log_level, "trace|debug|info|warn|error|critical|off (overrides log.level)");

  auto* check = app.add_subcommand("check-config", "Load and validate configuration files, then exit");
  std::vector<std::string> check_paths;
  check->add_option("--config", check_paths, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);

  auto* decode = app.add_subcommand("decode", "Decode RS-Helios packets from a pcap into sweeps (PCD)");
  liod::DecodeOptions decode_options;
  decode->add_option("--pcap", decode_options.pcap, "capture file (pcap or pcapng)")->required();
  decode->add_option("--angles", decode_options.angles_csv, "calibration CSV (vertical_deg,horizontal_deg) used until a DIFOP arrives");
  decode->add_option("--out", decode_options.out_dir, "directory for one PCD file per sweep");

  auto* replay = app.add_subcommand("replay", "Run a recorded drive (LiDAR pcap + IMU CSV) through the odometry");
  std::vector<std::string> replay_configs;
  liod::ReplayOptions replay_options;
  replay->add_option("--config", replay_configs, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);
  replay->add_option("--pcap", replay_options.pcap, "LiDAR packets (pcap or pcapng)")->required()->check(CLI::ExistingFile);
  replay->add_option("--imu", replay_options.imu_csv, "IMU log (CSV, see README)")->required()->check(CLI::ExistingFile);
  replay->add_option("--trajectory", replay_options.trajectory_tum, "output: scan-rate poses, TUM format")->required();
  replay->add_option("--imu-rate-trajectory", replay_options.imu_rate_tum, "output: IMU-rate poses, TUM format");
  replay->add_option("--scan-log", replay_options.scan_log_csv, "output: per-scan status, features and timings (CSV)");
  replay->add_flag("!--no-progress", replay_options.progress, "no progress bar (one is drawn only on a terminal)");
  replay_options.progress = true;
  replay->add_option("--pace", replay_options.pace, "replay at this multiple of the recorded pace (1 = as recorded); default: as fast as possible, deterministic")->check(CLI::Range(0.0, 1000.0));
  replay->add_option("--pose-socket", replay_options.pose_socket, "also serve the poses on this Unix socket (see docs/pose-protocol.md)");

  auto* run = app.add_subcommand("run", "The live daemon: sensor drivers, odometry, pose socket (systemd: Type=notify)");
  std::vector<std::string> run_configs;
  liod::RunOptions run_options;
  run->add_option("--config", run_configs, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);
  run->add_option("--max-seconds", run_options.max_seconds, "stop by itself after this long (tests)");

  auto* record = app.add_subcommand("record", "Run live and also write what the drivers receive (lidar.pcap + imu.csv) for replay");
  std::vector<std::string> record_configs;
  liod::RunOptions record_options;
  record->add_option("--config", record_configs, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);
  record->add_option("--out", record_options.record_dir, "output directory (created)")->required();
  record->add_option("--max-seconds", record_options.max_seconds, "stop by itself after this long");

  auto* pose = app.add_subcommand("pose", "Print the poses a running liod publishes");
  liod::PoseCommandOptions pose_options;
  std::vector<std::string> pose_configs;
  pose->add_option("--socket", pose_options.socket, "pose socket path (default: output.pose_socket of --config, else /run/liod/pose.sock)");
  pose->add_option("--config", pose_configs, "configuration file(s) to take the socket path from")->check(CLI::ExistingFile);
  pose->add_flag("--json", pose_options.json, "JSON lines (the server's text mode)");
  pose->add_flag("--scan-only", pose_options.scan_only, "scan-rate poses only");
  pose->add_flag("--health", pose_options.health, "also print health messages");
  pose->add_option("--count", pose_options.count, "exit after this many poses");
  pose->add_option("--timeout", pose_options.timeout_s, "exit after this many seconds without a message");

  CLI11_PARSE(app, argc, argv);

  try {
    liod::setup_logging(log_level.empty() ? "info" : log_level);
    if (*check) return check_config(check_paths);
    if (*decode) return liod::run_decode(decode_options, std::cout);
    if (*replay) {
      const liod::Config config = liod::load_config(replay_configs);
      if (log_level.empty()) spdlog::set_level(spdlog::level::from_str(config.log.level));
      return liod::run_replay(config, replay_options, std::cout);
    }
    if (*run || *record) {
      const liod::Config config = liod::load_config(*run ? run_configs : record_configs);
      if (log_level.empty()) spdlog::set_level(spdlog::level::from_str(config.log.level));
      return liod::run_daemon(config, *run ? run_options : record_options);
    }
    if (*pose) {
      if (pose_options.socket.empty()) {
        pose_options.socket = pose_configs.empty() ? liod::Config{}.output.pose_socket : liod::load_config(pose_configs).output.pose_socket;
      }
      return liod::run_pose_client(pose_options, std::cout);
    }
  } catch (const liod::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kConfigErrorExit;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
