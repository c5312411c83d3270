// liod: the one command-line entry point. Each subcommand parses its options, loads and
// validates the configuration (exiting non-zero before doing anything on an error), then runs.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <iostream>

#include "liod/config.hpp"
#include "liod/daemon/decode_command.hpp"
#include "liod/daemon/logging.hpp"
#include "liod/daemon/replay.hpp"

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
  } catch (const liod::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kConfigErrorExit;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
